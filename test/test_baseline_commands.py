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

"""``pump_friction learn-baseline``, ``reset-baseline`` and ``replay --baseline``."""

import json
from pathlib import Path

from pump_friction_ros.app.cli import main
from pump_friction_ros.bags import fleet
from pump_friction_ros.bags.fleet import ReplayJob, run_job
from pump_friction_ros.bags.replay import replay_bag
from pump_friction_ros.core.baseline_file import load_baseline, provenance, read_baseline
from pump_friction_ros.core.estimator_setup import estimator_from_config
from pump_friction_ros.core.node_parameters import BAG_PARAMS_FILE, load_estimator_config
import pytest

REPO = Path(__file__).resolve().parents[1]
NOMINAL = REPO / 'bags' / 'eha_nominal'
WEAR = REPO / 'bags' / 'eha_valve_plate_wear'
SAMPLE_PARAMS = REPO / 'bags' / 'eha_params.yaml'
BAG_START_NS = 1_700_000_000 * 1_000_000_000  # the sample bags' first stamp
BAG_LENGTH_NS = 75 * 1_000_000_000


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def learn(capsys, out, *bags, extra=()):
    code, text, err = run(capsys, 'learn-baseline', *bags, '--params', SAMPLE_PARAMS, '--out',
                          out, '--quiet', *extra)
    assert code == 0, err
    return text


def bag_config(bag):
    return load_estimator_config([bag / BAG_PARAMS_FILE, SAMPLE_PARAMS])


def same(a, b):
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


@pytest.fixture(scope='module')
def nominal_replayed():
    """Return the core after a plain replay of the healthy bag: what learn-baseline keeps."""
    core = estimator_from_config(bag_config(NOMINAL))
    summary = replay_bag(NOMINAL, bag_config(NOMINAL), core=core)
    return core, summary


def test_learn_baseline_keeps_what_a_replay_of_the_healthy_bag_learns(capsys, tmp_path,
                                                                      nominal_replayed):
    core, summary = nominal_replayed
    out = tmp_path / 'baseline.yaml'
    text = learn(capsys, out, NOMINAL)
    assert str(out) in text
    doc = read_baseline(out)
    assert same(doc['monitor_state'], core.monitor.state_dict())
    learnt = doc['learnt']
    assert learnt['samples'] == summary.counts['monitor_samples'] > 0
    assert BAG_START_NS <= learnt['first_stamp_ns'] < learnt['last_stamp_ns'] \
        <= BAG_START_NS + BAG_LENGTH_NS
    assert doc['provenance'] == provenance(core)
    # the node run with the bag's parameters takes it
    load_baseline(estimator_from_config(bag_config(NOMINAL)), out)


def test_learning_two_bags_is_learning_one_then_going_on_from_its_baseline(capsys, tmp_path):
    both, first, then, alone = (tmp_path / f'{n}.yaml' for n in ('ab', 'a', 'a_b', 'b'))
    learn(capsys, both, NOMINAL, WEAR)
    learn(capsys, first, NOMINAL)
    learn(capsys, then, WEAR, extra=('--baseline', first))
    learn(capsys, alone, WEAR)
    a, b, ab, a_b = (read_baseline(p) for p in (first, alone, both, then))
    assert same(ab['monitor_state'], a_b['monitor_state'])
    assert ab['learnt'] == a_b['learnt']
    assert ab['learnt']['samples'] == a['learnt']['samples'] + b['learnt']['samples']
    assert ab['learnt']['first_stamp_ns'] == a['learnt']['first_stamp_ns']
    assert ab['learnt']['last_stamp_ns'] == b['learnt']['last_stamp_ns']
    assert a_b['created_utc'] == a['created_utc']  # the baseline began with the first bag


@pytest.mark.parametrize('again', [NOMINAL, NOMINAL.parent / '..' / 'bags' / NOMINAL.name,
                                   NOMINAL.parent])  # the folder holding it finds it again
def test_the_same_bag_twice_is_refused_before_anything_is_learnt(capsys, tmp_path, again):
    out = tmp_path / 'twice.yaml'
    code, text, err = run(capsys, 'learn-baseline', NOMINAL, again, '--params', SAMPLE_PARAMS,
                          '--out', out, '--quiet')
    assert code == 2 and text == ''
    assert err.startswith('pump_friction: error: bag given twice: ') and len(
        err.strip().splitlines()) == 1
    assert not out.exists()


def test_a_bag_that_begins_before_what_was_learnt_ends_is_learnt_with_a_note(capsys,
                                                                             tmp_path):
    """The two sample bags share their start (as runs in simulated time from 0 do)."""
    text = learn(capsys, tmp_path / 'ab.yaml', NOMINAL, WEAR)
    notes = [line for line in text.splitlines() if line.startswith('note: ')]
    assert len(notes) == 1 and str(WEAR) in notes[0]
    assert f'begins at {BAG_START_NS * 1e-9:.3f} s, before what was learnt ends' in notes[0]
    then = learn(capsys, tmp_path / 'b.yaml', WEAR, extra=('--baseline', tmp_path / 'ab.yaml'))
    assert 'before what was learnt ends (' + str(tmp_path / 'ab.yaml') in then
    alone = learn(capsys, tmp_path / 'a.yaml', NOMINAL)
    assert 'note: ' not in alone


def test_replay_with_a_baseline_starts_the_monitor_from_it(capsys, tmp_path, monkeypatch):
    path = tmp_path / 'baseline.yaml'
    learn(capsys, path, NOMINAL)
    saved = read_baseline(path)
    seen = {}
    real = fleet.replay_bag

    def spy(bag, config, **kwargs):
        core = kwargs['core']
        seen['start'] = (core.learnt[0], core.monitor.state_dict())
        summary = real(bag, config, **kwargs)
        seen['end'] = core.learnt[0]
        return summary

    monkeypatch.setattr(fleet, 'replay_bag', spy)
    summary = run_job(ReplayJob(bag=str(WEAR), config=bag_config(WEAR), baseline=str(path)))
    assert not summary.error
    samples, state = seen['start']
    assert samples == saved['learnt']['samples'] and same(state, saved['monitor_state'])
    assert seen['end'] == samples + summary.counts['monitor_samples']


def test_replay_cli_takes_a_baseline(capsys, tmp_path):
    path = tmp_path / 'baseline.yaml'
    learn(capsys, path, NOMINAL)
    code, out, err = run(capsys, 'replay', WEAR, '--params', SAMPLE_PARAMS, '--baseline', path,
                         '--quiet', '--workers', '1')
    assert code == 0, err
    assert f'started from the baseline file {path}' in out


def test_replay_with_a_baseline_of_other_parameters_exits_2_naming_them(capsys, tmp_path):
    path = tmp_path / 'baseline.yaml'
    learn(capsys, path, NOMINAL)
    other = tmp_path / 'other.yaml'
    other.write_text('/**:\n  ros__parameters:\n    drive_loss_torque_nm: 0.1\n')
    code, _, err = run(capsys, 'replay', WEAR, '--params', other, '--baseline', path,
                       '--quiet', '--workers', '1')
    assert code == 2
    assert len(err.strip().splitlines()) == 1
    assert 'drive_loss_torque_nm (file 0.05, now 0.1)' in err


def test_replay_with_a_baseline_whose_state_is_not_finite_exits_2_in_one_line(capsys, tmp_path):
    path = tmp_path / 'baseline.yaml'
    learn(capsys, path, NOMINAL)
    text = path.read_text()
    first = text.index('monitor_state:')
    number = text.index('- - ', first) + 4  # the first learnt sum: not finite now
    end = text.index('\n', number)
    path.write_text(text[:number] + '.nan' + text[end:])
    code, out, err = run(capsys, 'replay', WEAR, '--params', SAMPLE_PARAMS, '--baseline', path,
                         '--quiet', '--workers', '1', '--out', tmp_path / 'out')
    assert code == 2
    assert len(err.strip().splitlines()) == 1
    assert 'monitor_state' in err and 'not finite' in err
    assert 'started from the baseline file' not in out  # it did not


def test_learn_baseline_refuses_bags_of_other_parameters(capsys, tmp_path):
    other = tmp_path / 'other_bag'
    other.mkdir()
    for item in NOMINAL.iterdir():
        if item.name != BAG_PARAMS_FILE:
            (other / item.name).symlink_to(item)
    (other / BAG_PARAMS_FILE).write_text(
        '/**:\n  ros__parameters:\n    rotor_inertia_kg_m2: 0.0003\n')
    out = tmp_path / 'baseline.yaml'
    code, _, err = run(capsys, 'learn-baseline', NOMINAL, other, '--out', out, '--quiet')
    assert code == 2 and not out.exists()
    assert len(err.strip().splitlines()) == 1
    assert 'rotor_inertia_kg_m2 (file 0.0002, now 0.0003)' in err


def test_reset_baseline_moves_the_file_aside_for_relearning(capsys, tmp_path):
    path = tmp_path / 'baseline.yaml'
    learn(capsys, path, NOMINAL)
    old = path.read_bytes()
    code, out, err = run(capsys, 'reset-baseline', path)
    assert code == 0, err
    backups = list(tmp_path.glob('baseline.yaml.*.bak'))
    assert not path.exists() and len(backups) == 1 and backups[0].read_bytes() == old
    assert str(backups[0]) in out


def test_reset_baseline_moves_a_foreign_file_only_with_force(capsys, tmp_path):
    path = tmp_path / 'params.yaml'
    path.write_text('/**:\n  ros__parameters: {}\n')
    code, _, err = run(capsys, 'reset-baseline', path)
    assert code == 2 and path.exists() and '--force' in err
    assert run(capsys, 'reset-baseline', path, '--force')[0] == 0
    assert not path.exists()


BAD = {
    'learn_without_out': lambda tmp: ['learn-baseline', NOMINAL],
    'learn_missing_bag': lambda tmp: ['learn-baseline', tmp / 'nope', '--out', tmp / 'b.yaml'],
    'learn_out_exists': lambda tmp: ['learn-baseline', NOMINAL, '--out', SAMPLE_PARAMS],
    'learn_out_folder': lambda tmp: ['learn-baseline', NOMINAL, '--out', tmp],
    # (a folder that cannot be made: refused before the bag is replayed, which prints)
    'learn_out_unwritable': lambda tmp: ['learn-baseline', NOMINAL, '--out',
                                         Path(SAMPLE_PARAMS) / 'b.yaml'],
    'learn_bad_start': lambda tmp: ['learn-baseline', NOMINAL, '--out', tmp / 'b.yaml',
                                    '--baseline', SAMPLE_PARAMS],
    'reset_missing': lambda tmp: ['reset-baseline', tmp / 'nope.yaml'],
    'reset_folder': lambda tmp: ['reset-baseline', tmp],
    'replay_missing': lambda tmp: ['replay', NOMINAL, '--baseline', tmp / 'nope.yaml'],
    'replay_abbreviated': lambda tmp: ['replay', NOMINAL, '--base', tmp / 'b.yaml'],
}


def test_learn_baseline_leaves_no_folder_made_for_its_out_when_it_fails(capsys, tmp_path):
    out = tmp_path / 'new' / 'deeper' / 'b.yaml'  # folders it could make, then a bad bag
    code, _, err = run(capsys, 'learn-baseline', tmp_path / 'nope', '--out', out)
    assert code == 2 and 'nope' in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.parametrize('case', sorted(BAD))
def test_bad_arguments_exit_2_with_one_line(capsys, tmp_path, case):
    code, out, err = run(capsys, *BAD[case](tmp_path))
    assert code == 2 and out == ''
    assert len(err.strip().splitlines()) == 1 and err.startswith('pump_friction: error: ')
    assert 'Traceback' not in err
    assert not (tmp_path / 'b.yaml').exists()
