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

"""Exceptions raised by pump_friction_ros; every one carries a message fit for a user."""

from typing import Any

__all__ = ['BagError', 'BaselineError', 'BaselineMismatchError', 'CalibrationError',
           'ConfigError', 'OutputError', 'PumpFrictionError', 'TableError', 'UsageError', 'quote']


class PumpFrictionError(Exception):
    """Base class of every error this package raises on purpose."""


class ConfigError(PumpFrictionError, ValueError):
    """A pump parameter file or a parameter set is missing, malformed or non-physical."""


class TableError(PumpFrictionError, ValueError):
    """A friction-torque table file is malformed or does not match the pump in use."""


class BagError(PumpFrictionError):
    """A bag is missing, not a bag, unreadable, corrupt, empty or lacks the input topics."""


class OutputError(PumpFrictionError):
    """An output exists (without --force), is of another kind, or cannot be written."""


class CalibrationError(PumpFrictionError):
    """Unusable calibration input: no samples, NaN, inconsistent units, too few points."""


class BaselineError(PumpFrictionError, ValueError):
    """A healthy-baseline file is missing, unreadable, corrupt or of another format version."""


class BaselineMismatchError(BaselineError):
    """A healthy-baseline file was learnt on another pump, table or node parameters."""


class UsageError(PumpFrictionError):
    """A bad command-line argument."""


def quote(value: Any, limit: int = 60) -> str:
    """
    Return ``repr(value)`` cut to ``limit`` characters, for error messages.

    A value from a file can be huge (a YAML alias bomb expands to gigabytes when printed):
    an error message names a container by its type and length and quotes only the start of
    anything else, so that reporting it cannot hang.

    Parameters
    ----------
    value : object
        The offending value.
    limit : int
        Most characters quoted.

    Returns
    -------
    str
        The quotation, at most ``limit`` + 5 characters.

    """
    if isinstance(value, (dict, list, tuple, set)):
        return f'a {type(value).__name__} of {len(value)} item(s)'
    if isinstance(value, str) and len(value) > limit:
        return repr(value[:limit]) + '...'
    try:
        text = repr(value)
    except ValueError:  # an integer too long to print (Python's digit limit)
        return 'an integer too long to print'
    return text if len(text) <= limit + 2 else text[:limit] + '...'
