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

"""process_map: results in order; a caller's stop terminates the workers, the rest undone."""

import multiprocessing
from pathlib import Path
import time

from pump_friction_ros.process_pool import process_map
import pytest


def square(x):
    return x * x


def slow_mark(args):
    """Sleep, then leave a file saying this item ran to its end."""
    folder, k = args
    time.sleep(0.3)
    Path(folder, f'{k}.done').touch()
    return k


def test_results_come_back_in_the_order_of_the_items():
    assert process_map(square, range(20), 2) == [k * k for k in range(20)]


def test_a_stop_of_the_caller_terminates_the_workers_and_leaves_the_queue_undone(tmp_path):
    """pool.map hands every item out at once: a context manager's exit would run them all."""
    items = [(str(tmp_path), k) for k in range(12)]

    def stop(done):
        raise KeyboardInterrupt  # a Ctrl-C (or a SIGTERM taken as one) after the first result

    before = set(multiprocessing.active_children())  # (an earlier test's helper may be exiting)
    with pytest.raises(KeyboardInterrupt):
        process_map(slow_mark, items, 2, stop)
    assert set(multiprocessing.active_children()) <= before  # terminated and joined
    ran = len(list(tmp_path.glob('*.done')))
    time.sleep(0.6)  # two more items' time: nothing is still running to mark them
    assert len(list(tmp_path.glob('*.done'))) == ran < len(items)


def test_a_failing_item_is_raised_and_the_workers_are_gone():
    before = set(multiprocessing.active_children())
    with pytest.raises(ZeroDivisionError):
        process_map(_inverse, [1, 2, 0, 4], 2)
    assert set(multiprocessing.active_children()) <= before


def _inverse(x):
    return 1 / x
