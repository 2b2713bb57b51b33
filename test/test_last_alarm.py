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

"""The last alarm outlives its clearing: an intermittent fault's name is not lost."""

import math
from types import SimpleNamespace

import numpy as np
from pump_friction_ros.core.attribution import Verdict
from pump_friction_ros.core.baseline_file import _DUMPER
from pump_friction_ros.core.diagnostics import level_message
from pump_friction_ros.core.last_alarm import LastAlarm
from pump_friction_ros.core.monitor import ERROR, OK, WARN
from pump_friction_ros.evaluation.bank import read_monitor
import pytest
import yaml

from .test_baseline_monitor import _changed, DT, monitor, run, TRUTH


def _episode(mon, rng, t, on_windows, cause='valve_plate', size=0.8):
    """Run a change for ``on_windows``, then healthy until the level is back at OK."""
    onsets, levels, height, in_alarm = set(), [], -1.0, None
    cleared = math.nan
    for k in range(on_windows + 2000):  # then off: the CUSUMs drain, the alarm clears
        before = mon.level
        change = _changed(cause, size) if k < on_windows else None
        t = run(mon, rng, 1, TRUTH, change=change, noise=0.002, t0=t)
        if mon.level != OK:
            levels.append(mon.level)
            onsets.add(mon.alarm_onset_s)
            assert mon.last_alarm.active and mon.last_alarm.onset_s == mon.alarm_onset_s
            cusum = max(mon.cusum_pos_nm_s, mon.cusum_neg_nm_s)
            if cusum >= height:  # the alarm at its height: the reading then
                height = cusum
                in_alarm = (mon.verdict(1.0), mon.theta_vp, mon.valve_plate_scale_std)
        elif before != OK:
            cleared = t - DT  # the last sample of the window it cleared on
            break
    return t, onsets, max(levels), in_alarm, cleared


def _commissioned(seed):
    mon = monitor()
    rng = np.random.default_rng(seed)
    t = run(mon, rng, 240, TRUTH, noise=0.002)
    assert not mon.learning and mon.level == OK and mon.last_alarm.level == OK
    return mon, rng, t


@pytest.mark.parametrize('seed', [41, 42])
def test_an_alarm_that_cleared_is_kept_with_its_verdict_and_said_at_ok(seed):
    mon, rng, t = _commissioned(seed)
    assert level_message(OK, mon) == 'torque as the healthy baseline'  # none yet
    t, onsets, highest, in_alarm, cleared = _episode(mon, rng, t, 60)
    assert mon.level == OK and len(onsets) == 1 and highest >= WARN
    last = mon.last_alarm
    assert not last.active
    assert last.onset_s == onsets.pop() < last.cleared_s == pytest.approx(cleared)
    assert last.level == highest
    # what the alarm said at its height, not what the healthy windows as it drained say
    (verdict, words), scale, std = in_alarm
    assert verdict == Verdict.VALVE_PLATE == last.verdict and last.words == words
    assert (last.valve_plate_scale, last.valve_plate_scale_std) == (scale, std)
    assert abs(last.valve_plate_scale - 1.8) < 1.96 * last.valve_plate_scale_std
    message = level_message(OK, mon)
    assert message.startswith('torque as the healthy baseline; last alarm ')
    assert f'{last.onset_s:.1f}-{last.cleared_s:.1f} s, cleared: valve plate' in message


def test_a_new_alarm_replaces_the_last_one():
    mon, rng, t = _commissioned(43)
    t, first, *_ = _episode(mon, rng, t, 60)
    t, second, highest, ((verdict, _), *_), _ = _episode(mon, rng, t, 60, 'torque_offset',
                                                         0.1)
    last = mon.last_alarm
    assert last.onset_s == second.pop() > first.pop()
    assert last.level == highest and last.verdict == verdict == Verdict.NOT_FRICTION


def test_the_last_alarm_survives_a_restart_and_a_reset_forgets_it():
    mon, rng, t = _commissioned(44)
    _episode(mon, rng, t, 60)
    state = mon.state_dict()
    again = monitor()
    again.load_state_dict(state)
    assert again.last_alarm.state() == mon.last_alarm.state()
    assert level_message(OK, again) == level_message(OK, mon)
    older = {key: value for key, value in state.items() if key != 'last_alarm'}
    again.load_state_dict(older)  # a file from before it was kept: none
    assert again.last_alarm.level == OK and level_message(OK, again).endswith('baseline')
    mon.reset()  # a repair: learnt afresh, the old alarm is history
    assert mon.last_alarm.level == OK and math.isnan(mon.last_alarm.onset_s)


@pytest.mark.parametrize('bad', [{'level': 7}, {'level': 1.0}, {'verdict': 3},
                                 {'followed': 'yes'}, {'onset_s': math.nan},
                                 {'cleared_s': math.inf}])
def test_a_bad_last_alarm_in_the_state_is_refused_and_changes_nothing(bad):
    mon, rng, t = _commissioned(45)
    _episode(mon, rng, t, 60)
    before = mon.state_dict()
    assert before['last_alarm']['onset_s'] > 1.0
    with pytest.raises(ValueError, match='malformed monitor state'):
        mon.load_state_dict(before | {'last_alarm': before['last_alarm'] | bad})
    assert mon.state_dict() == before


def test_an_alarm_under_way_goes_through_the_baseline_file_and_goes_on_after_it(tmp_path):
    mon, rng, t = _commissioned(47)
    for _ in range(60):  # in alarm at the restart: its clearing NaN, its height finite
        t = run(mon, rng, 1, TRUTH, change=_changed('valve_plate', 0.8), noise=0.002, t0=t)
    assert mon.level >= WARN and mon.last_alarm.active
    path = tmp_path / 'state.yaml'  # the baseline file's own YAML writer and reader
    state = mon.state_dict()
    path.write_text(yaml.dump(state['last_alarm'], Dumper=_DUMPER, sort_keys=False))
    again = monitor()
    again.load_state_dict(state | {'last_alarm': yaml.safe_load(path.read_text())})
    saved = again.last_alarm.state()
    assert math.isnan(saved.pop('cleared_s'))
    assert saved == {k: v for k, v in mon.last_alarm.state().items() if k != 'cleared_s'}
    # the same alarm goes on: its onset kept, cleared when the CUSUMs drain
    _, onsets, *_ = _episode(again, rng, t, 1)
    assert onsets == {mon.last_alarm.onset_s} and not again.last_alarm.active


def test_a_clock_restarted_during_an_alarm_is_kept_and_the_next_alarm_is_new():
    mon, rng, _ = _commissioned(48)  # commissioned at 0-60 s; the clock then restarts
    _, onsets, *_ = _episode(mon, rng, 10_000.0, 60)
    _, second, *_ = _episode(mon, rng, onsets.pop(), 60)  # the next alarm: the same stamps
    last = mon.last_alarm
    assert last.onset_s == second.pop() and last.cleared_s > last.onset_s
    # a clearing before its onset (stamps restarted in between) is a state like any other
    state = mon.state_dict()
    state['last_alarm'] = state['last_alarm'] | {'cleared_s': last.onset_s - 9_000.0}
    again = monitor()
    again.load_state_dict(state)
    assert again.last_alarm.cleared_s == last.onset_s - 9_000.0


def test_an_alarm_the_baseline_followed_says_what_for_and_the_bank_does_not_count_it():
    mon, rng, t = _commissioned(49)
    _episode(mon, rng, t, 60)
    alarm = mon.last_alarm
    assert ' s, cleared: valve plate' in alarm.note()
    alarm.onset_s, alarm.cleared_s = 5.0, math.nan  # as if under way, then followed
    alarm.end(7.0, 'oil')
    name = 'ERROR' if alarm.level == ERROR else 'WARN'
    assert alarm.note() == (f'last alarm {name} 5.0-7.0 s, taken for the oil thinning '
                            f'(friction baseline followed): {alarm.words}')
    assert read_monitor(SimpleNamespace(monitor=mon)).cleared_attribution == 'none'
    alarm.cleared_s = math.nan  # with the temperature topic: the k_t drift learnt instead
    alarm.end(7.0, 'drift')
    assert "taken for the torque measurement's drift with the oil temperature" in alarm.note()
    again = monitor()  # what it was taken for goes through the state file
    again.load_state_dict(mon.state_dict())
    assert again.last_alarm.note() == alarm.note()


def test_a_last_alarm_written_with_followed_as_a_bool_loads_as_the_oil_s_or_none():
    # files of the code before what an alarm was taken for was named: True meant the oil
    # follow, the only follow then; an upgrade must not refuse a state of months
    mon, rng, t = _commissioned(49)
    _episode(mon, rng, t, 60)
    state = mon.state_dict()
    for old, now in ((True, 'oil'), (False, '')):
        state['last_alarm']['followed'] = old
        again = monitor()
        again.load_state_dict(state)
        assert again.last_alarm.followed == now
        assert again.last_alarm.note().startswith('last alarm')
        assert ('taken for the oil thinning' in again.last_alarm.note()) == old


def test_an_alarm_still_under_way_is_not_a_cleared_one():
    alarm = LastAlarm()
    assert alarm.verdict_under_way == ''
    alarm.during(10.0, WARN, 0.7, Verdict.VALVE_PLATE, 'valve plate', 1.8, 0.1)
    alarm.during(10.0, ERROR, 1.3, Verdict.VALVE_PLATE, 'valve plate', 1.9, 0.1)
    alarm.during(10.0, WARN, 0.9, Verdict.CANNOT_TELL, 'cannot tell', 1.2, 0.3)
    assert alarm.active and alarm.note() == '' and alarm.level == ERROR  # the highest
    assert (alarm.verdict, alarm.valve_plate_scale) == (Verdict.VALVE_PLATE, 1.9)  # its height
    assert alarm.verdict_under_way == Verdict.VALVE_PLATE  # (no drift learnt: gain_follow)
    alarm.end(20.0)
    assert alarm.verdict_under_way == ''
    alarm.end(30.0)  # nothing under way: the clearing stays the first
    assert not alarm.active and alarm.cleared_s == 20.0
    assert alarm.note() == 'last alarm ERROR 10.0-20.0 s, cleared: valve plate'


def test_the_bank_reads_the_cleared_alarm_s_verdict_only_out_of_alarm():
    mon, rng, t = _commissioned(46)
    core = SimpleNamespace(monitor=mon)  # read_monitor reads the estimator's monitor only
    assert read_monitor(core).cleared_attribution == 'none'
    t, onsets, *_ = _episode(mon, rng, t, 60)
    reading = read_monitor(core)
    assert reading.level == OK and reading.attribution == 'none'
    assert reading.cleared_attribution == Verdict.VALVE_PLATE
    assert reading.cleared_onset_s == onsets.pop()
    run(mon, rng, 60, TRUTH, change=_changed('valve_plate', 0.8), noise=0.002, t0=t)
    again = read_monitor(core)  # in alarm again: the verdict now, nothing cleared
    assert again.level >= WARN and again.attribution == Verdict.VALVE_PLATE
    assert again.cleared_attribution == 'none'
