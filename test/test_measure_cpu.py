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

"""The CPU benchmark's ROS-free parts: reading a process's CPU time, the report."""

import os
import sys
import time

from pump_friction_ros.node.measure_cpu import (
    cpu_seconds,
    format_run,
    format_summary,
    main,
    NodeResult,
    RunResult,
)
import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith('linux'), reason='/proc is Linux')


def test_cpu_seconds_follows_os_times():
    before, t0 = cpu_seconds(os.getpid()), os.times()
    end = time.process_time() + 0.3
    while time.process_time() < end:
        pass
    after, t1 = cpu_seconds(os.getpid()), os.times()
    own = (t1.user + t1.system) - (t0.user + t0.system)
    assert after - before == pytest.approx(own, abs=0.03)  # clock ticks of 10 ms


def run(reliable, bare_cpu, estimator_cpu, lost=0):
    sent = {'joint_states': 20000, 'load_pressure': 10000}
    result = RunResult(reliable, 20.0, sent, 0)
    result.nodes['bare'] = NodeResult(bare_cpu, dict(sent), 20000)
    result.nodes['estimator'] = NodeResult(
        estimator_cpu, {'joint_states': 20000 - lost, 'load_pressure': 10000}, 2000)
    return result


def test_ratio_is_per_message_received():
    r = run(False, 9.0, 9.0, lost=3000)  # same CPU for fewer messages: dearer per message
    assert r.nodes['bare'].per_message_us() == pytest.approx(300.0)
    assert r.ratio() == pytest.approx(30000 / 27000)
    text = format_run(1, r)
    assert 'best effort inputs' in text and ' 3000 ' in text
    assert 'CPU per input message: 1.11' in text


def test_summary_per_qos_and_undefined_ratio():
    runs = [run(False, 10.0, 8.0), run(False, 10.0, 9.0), run(True, 10.0, 12.0),
            run(True, 0.0, 1.0)]
    text = format_summary(runs)
    assert 'best effort: estimator / bare = 0.85 (median of 2; 0.80 to 0.90)' in text
    assert 'reliable: estimator / bare = 1.20 (median of 1; 1.20 to 1.20)' in text


def test_help_runs_without_ros(capsys):
    with pytest.raises(SystemExit) as stop:
        main(['--help'])
    assert stop.value.code == 0
    assert 'sourced ROS 2' in capsys.readouterr().out
