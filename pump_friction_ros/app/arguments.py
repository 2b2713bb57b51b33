# Copyright 2026 pump_friction_ros developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""The command line's parser and argument types: a bad argument is one line, exit 2."""

from __future__ import annotations

import argparse
from collections.abc import Callable
import math
from typing import Any, NoReturn

from ..errors import UsageError

__all__ = ['SEED', 'Parser', 'bounded_float', 'bounded_int']


class Parser(argparse.ArgumentParser):
    """
    Argument parser that reports a bad argument in one line and exits with code 2.

    Abbreviations are off (``allow_abbrev=False``) for the main parser and every
    sub-command, so that a typo such as ``--plot`` for ``--plots`` is an error instead of
    a guess.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs['allow_abbrev'] = False
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        """Raise `UsageError` instead of printing usage and exiting."""
        raise UsageError(f'{message} (see {self.prog} --help)')

    def _get_value(self, action: argparse.Action, arg_string: str) -> Any:
        # every value is a path, an address, a name or a number: an empty one is a mistake
        # (an unset shell variable), never "none" (--baseline '') or "here" (replay '')
        # (a sub-command's own strings pass through here too: its parser judges them)
        if arg_string == '' and action.default != '' and not isinstance(
                action, argparse._SubParsersAction):
            raise argparse.ArgumentError(action, 'expected a value, got an empty string')
        return super()._get_value(action, arg_string)


def bounded_float(name: str, low: float, high: float) -> Callable[[str], float]:
    """
    Return an argument type: a finite number in [low, high].

    Parameters
    ----------
    name : str
        The option, for the error message.
    low, high : float
        The bounds, in the option's own unit.

    Returns
    -------
    callable
        Text to float, raising `argparse.ArgumentTypeError` with one line.

    """

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f'{name} must be a number, got {text!r}') from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f'{name} must be finite, got {text!r}')
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f'{name} must be in [{low:g}, {high:g}], '
                                             f'got {value:g}')
        return value

    return parse


def bounded_int(name: str, low: int, high: int) -> Callable[[str], int]:
    """
    Return an argument type: an integer in [low, high].

    Parameters
    ----------
    name : str
        The option, for the error message.
    low, high : int
        The bounds.

    Returns
    -------
    callable
        Text to int, raising `argparse.ArgumentTypeError` with one line.

    """

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f'{name} must be an integer, got {text!r}') from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f'{name} must be in [{low}, {high}], got {value}')
        return value

    return parse


SEED = bounded_int('--seed', 0, 2 ** 32 - 1)
"""A random seed: numpy's are non-negative (a negative one raised deep in numpy)."""
