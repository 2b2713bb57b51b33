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

"""The healthy baseline file: atomic, exact round trip, provenance checked, never a crash."""

from dataclasses import fields, replace
import json
import math
import os
from pathlib import Path

import numpy as np
from pump_friction_ros.core import baseline_disk, baseline_file
from pump_friction_ros.core.baseline_disk import archive_baseline, writable_folder
from pump_friction_ros.core.baseline_file import (
    baseline_document,
    load_baseline,
    PROVENANCE_PARAMETERS,
    read_baseline,
    restore_baseline,
    write_baseline,
)
from pump_friction_ros.core.baseline_store import (
    baseline_path,
    BaselineStore,
    default_baseline_path,
)
from pump_friction_ros.core.estimator import TorqueEstimator
from pump_friction_ros.core.inputs import InputKind as K
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.errors import BaselineError, BaselineMismatchError, OutputError
from pump_friction_ros.sim.duty_cycle import DutyCycle, simulate_duty_cycle
from pump_friction_ros.table.friction_table import build_table
import pytest
import yaml

from .test_estimator import feed as feed_run, WithOilTemperature

NS = 1_000_000_000
T0 = 1_700_000_000 * NS
CONFIG = EstimatorConfig(oil_viscosity_m2_s=46e-6, drive_loss_torque_nm=0.05)
SPEED, DP = 300.0, 100e5
N_WITHOUT_TORQUE, N_WITH_TORQUE = 50, 150
SETTLE = round(CONFIG.monitor_settle_s * 1000)  # samples before the first monitored one
LOOKAHEAD = round(CONFIG.monitor_lookahead_s * 1000)  # samples after the last
N_MONITORED = N_WITH_TORQUE - SETTLE - LOOKAHEAD


def first_last(start=0):
    """Return the stamps of the first and the last monitored sample [ns]."""
    return stamps()[N_WITHOUT_TORQUE + SETTLE] + start, stamps()[-1 - LOOKAHEAD] + start


@pytest.fixture(scope='module')
def table(paper_params):
    return build_table(paper_params)


def make(table, config=CONFIG):
    return TorqueEstimator(config, table, 46e-6, 'hong_doh_2004')


def stamps():
    """Stamps of the joint states [ns]: 1 kHz from T0."""
    return [T0 + k * 1_000_000 for k in range(N_WITHOUT_TORQUE + N_WITH_TORQUE)]


def feed(core, extra_nm=0.3, start=0):
    """
    Feed steady running at SPEED and DP, stamps shifted by ``start`` [ns].

    First joint states without torque (not learnt from), then N_WITH_TORQUE with a torque
    ``extra_nm`` above the model, learnt from once the running has settled (SETTLE samples)
    and but for the last LOOKAHEAD (the monitor takes a sample once the running has gone on
    steadily after it).
    """
    expected = core.table.lookup(SPEED, DP, 46e-6).input_nm + CONFIG.drive_loss_torque_nm
    for k, stamp in enumerate(stamps()):
        stamp += start
        core.on_input(K.LOAD_PRESSURE, stamp - 1000, DP)
        torque = expected + extra_nm if k >= N_WITHOUT_TORQUE else None
        core.on_input(K.JOINT_STATE, stamp, SPEED, torque)
    return core


def learnt_core(table):
    core = feed(make(table))
    first, last = first_last()
    assert core.learnt == (N_MONITORED, first, last)  # known by construction
    assert core.monitor.state_dict() != make(table).monitor.state_dict()  # it learnt
    return core


def same(a, b):
    """Return whether two plain-value structures are equal, NaN equal to NaN."""
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def test_round_trip_through_the_file_restores_the_monitor_state_exactly(table, tmp_path):
    core = learnt_core(table)
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(core, origin='test'))
    fresh = make(table)
    load_baseline(fresh, path)
    assert same(fresh.monitor.state_dict(), core.monitor.state_dict())
    assert fresh.learnt == (N_MONITORED, *first_last())


def _numpy_values(value, where='state'):
    """Yield where a structure holds a numpy value instead of a plain one."""
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _numpy_values(item, f'{where}/{key}')
    elif isinstance(value, (list, tuple)):
        for k, item in enumerate(value):
            yield from _numpy_values(item, f'{where}[{k}]')
    elif type(value).__module__ == 'numpy':
        yield where


def test_a_baseline_learnt_with_the_temperature_topic_is_saved_and_restored(table, tmp_path):
    # the torque measurement's drift with the oil (`gain_follow`) enters every window's
    # change from the baseline: its state, the EWMA's and the isolation's, must stay plain
    # numbers, or the file is refused as "not plain values" and nothing learnt is kept
    run = simulate_duty_cycle(table, DutyCycle(duration_s=60.0), seed=4)
    config = replace(CONFIG, viscosity_source='temperature', baseline_learn_s=10.0)
    core = make(table, config)
    feed_run(WithOilTemperature(core, lambda ns: 41.5 if ns < 30 * NS else 44.0), run)
    mon = core.monitor
    assert not mon.learning and mon.ewma_nm != 0.0  # windows judged after the baseline
    assert list(_numpy_values(mon.state_dict())) == []
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(core, origin='test'))
    fresh = make(table, config)
    load_baseline(fresh, path)
    assert same(fresh.monitor.state_dict(), mon.state_dict())
    assert fresh.monitor.baseline_temperature_c == pytest.approx(41.5, abs=1e-9)


def test_a_numpy_number_in_a_document_is_written_as_the_plain_number(tmp_path):
    path = tmp_path / 'baseline.yaml'
    document = {'x': np.float64(0.1), 'n': np.int64(3), 'flag': np.bool_(True),
                'sums': [np.float32(1.5), np.float64(-2.0)], 'none': np.float64('nan')}
    write_baseline(path, document)
    back = yaml.safe_load(path.read_text())
    assert back['x'] == 0.1 and back['n'] == 3 and back['flag'] is True
    assert back['sums'] == [1.5, -2.0] and math.isnan(back['none'])


def test_learning_on_after_a_clock_restart_saves_a_file_that_loads(table, tmp_path):
    """The clock stepped back (simulated time replayed again): the first stamp is later."""
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(learnt_core(table)))
    core = make(table)
    load_baseline(core, path)
    feed(core, start=-1000 * 1_000_000_000)  # the same running, 1000 s earlier
    first, last = core.learnt[1:]
    assert first > last  # kept from the file / the latest stamp
    write_baseline(path, baseline_document(core))
    again = make(table)
    load_baseline(again, path)
    assert again.learnt == core.learnt


def test_learning_goes_on_after_a_restart_from_the_file(table, tmp_path):
    """A restart keeps what was learnt: the counts and the span run on across it."""
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(learnt_core(table)))
    restarted = make(table)
    load_baseline(restarted, path)
    feed(restarted, start=10 * NS)
    assert restarted.learnt == (2 * N_MONITORED, first_last()[0],
                                first_last(10 * NS)[1])


def test_negative_stamps_are_rejected_so_a_saved_file_always_loads_back(table, tmp_path):
    core = feed(make(table), start=-2 * T0)  # every stamp before 1970
    assert core.counts['rejected_negative_stamp'] == 2 * len(stamps())
    assert core.learnt[0] == 0 and core.counts['estimates'] == 0
    feed(core)  # then a sane clock: learnt from, and the file loads back at a restart
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(core))
    fresh = make(table)
    load_baseline(fresh, path)
    assert fresh.learnt == (N_MONITORED, *first_last())


def test_the_chunk_path_records_the_same_learnt_span_as_on_input(table):
    n = N_WITHOUT_TORQUE + N_WITH_TORQUE
    joint = np.array(stamps(), dtype=np.int64)
    kinds = np.empty(2 * n, dtype=np.int64)
    kinds[0::2], kinds[1::2] = int(K.LOAD_PRESSURE), int(K.JOINT_STATE)
    at = np.empty(2 * n, dtype=np.int64)
    at[0::2], at[1::2] = joint - 1000, joint
    core = make(table)
    expected = core.table.lookup(SPEED, DP, 46e-6).input_nm + CONFIG.drive_loss_torque_nm
    values = np.where(kinds == int(K.JOINT_STATE), SPEED, DP)
    has_torque = (kinds == int(K.JOINT_STATE)) & (np.arange(2 * n) >= 2 * N_WITHOUT_TORQUE)
    torques = np.where(has_torque, expected + 0.3, math.nan)
    core.on_chunk(kinds, at, at, values, torques, np.ones(2 * n, dtype=bool), has_torque,
                  np.zeros(2 * n, dtype=np.int64))
    assert core.learnt == (N_MONITORED, *first_last())


def test_a_crash_mid_write_leaves_the_old_file_intact(table, tmp_path, monkeypatch):
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(make(table)))
    old = path.read_bytes()

    def crash(*args):
        raise OSError(28, 'No space left on device')

    monkeypatch.setattr(baseline_disk.os, 'replace', crash)
    with pytest.raises(OutputError, match='No space left on device') as info:
        write_baseline(path, baseline_document(learnt_core(table)))
    assert '\n' not in str(info.value)
    assert path.read_bytes() == old
    assert sorted(tmp_path.iterdir()) == [path]  # no temporary file left behind


def test_an_interrupt_mid_write_leaves_the_old_file_intact(table, tmp_path, monkeypatch):
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(make(table)))
    old = path.read_bytes()

    def interrupted(fd):
        raise KeyboardInterrupt

    monkeypatch.setattr(baseline_disk.os, 'fsync', interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_baseline(path, baseline_document(learnt_core(table)))
    assert path.read_bytes() == old
    assert sorted(tmp_path.iterdir()) == [path]


def test_the_file_says_where_it_was_learnt(table, tmp_path, paper_params):
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(learnt_core(table), origin='node /eha1/x'))
    doc = yaml.safe_load(path.read_text())
    prov = doc['provenance']
    assert prov['pump'] == {'name': 'hong_doh_2004', 'sha256': paper_params.sha256}
    assert prov['parameters']['drive_loss_torque_nm'] == 0.05
    assert prov['parameters']['oil_viscosity_m2_s'] == 46e-6
    assert prov['parameters']['viscosity_source'] == 'parameter'
    assert 'oil_viscosity_40c_m2_s' not in prov['parameters']  # not used by this config
    assert doc['about']['origin'] == 'node /eha1/x'
    assert doc['learnt']['samples'] == N_MONITORED
    assert doc['monitor_state']['version'] == make(table).monitor.STATE_VERSION
    assert doc['created_utc'] <= doc['updated_utc']


def test_provenance_parameters_are_node_parameters():
    assert set(PROVENANCE_PARAMETERS) < {f.name for f in fields(EstimatorConfig)}


@pytest.mark.parametrize('change, words', [
    ({'drive_loss_torque_nm': 0.1}, 'drive_loss_torque_nm (file 0.05, now 0.1)'),
    ({'rotor_inertia_kg_m2': 3e-4}, 'rotor_inertia_kg_m2 (file 0.0002, now 0.0003)'),
    ({'joint_name': 'shaft2'}, "joint_name (file 'pump_shaft', now 'shaft2')"),
    ({'viscosity_source': 'temperature'}, 'viscosity_source'),
    ({'oil_viscosity_m2_s': 68e-6}, 'oil_viscosity_m2_s (file 4.6e-05, now 6.8e-05)'),
])
def test_other_parameters_refuse_the_file_naming_what_differs(table, tmp_path, change,
                                                              words):
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(learnt_core(table)))
    other = make(table, replace(CONFIG, **change))
    untouched = other.monitor.state_dict()
    with pytest.raises(BaselineMismatchError) as info:
        load_baseline(other, path)
    message = str(info.value)
    assert words in message and '\n' not in message and str(path) in message
    assert other.monitor.state_dict() == untouched and other.learnt[0] == 0


def test_another_pump_file_refuses_the_file(table, tmp_path, consistent_params):
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(learnt_core(table)))
    other = TorqueEstimator(CONFIG, build_table(consistent_params), 46e-6,
                            consistent_params.name)
    with pytest.raises(BaselineMismatchError, match=r'another pump file .*hong_doh_2004'):
        load_baseline(other, path)


def test_another_table_refuses_the_file(table, tmp_path):
    path = tmp_path / 'baseline.yaml'
    doc = baseline_document(learnt_core(table))
    doc['provenance']['table']['fingerprint'] = '0' * 64  # a table of another envelope
    write_baseline(path, doc)
    with pytest.raises(BaselineMismatchError, match='another table'):
        load_baseline(make(table), path)


def test_a_table_rebuilt_from_the_same_pump_has_the_same_fingerprint(table, paper_params):
    assert baseline_file.table_fingerprint(build_table(paper_params)) == \
        baseline_file.table_fingerprint(table)


def _document_with(table, **changes):
    doc = baseline_document(learnt_core(table))
    for dotted, value in changes.items():
        *parents, key = dotted.split('.')
        inner = doc
        for name in parents:
            inner = inner[name]
        inner[key] = value
    return yaml.safe_dump(doc)


def _document_mapped(table, dotted, change):
    """Return a learnt document whose entry at ``dotted`` is ``change(entry)``."""
    doc = baseline_document(learnt_core(table))
    *parents, key = dotted.split('.')
    inner = doc
    for name in parents:
        inner = inner[name]
    inner[key] = change(inner[key])
    return yaml.safe_dump(doc)


def _negative_definite(rows):
    return [[-1.0 if i == j else 0.0 for j in range(len(rows))] for i in range(len(rows))]


BROKEN = {
    'not_yaml': lambda table: 'format: [unclosed\n',
    'empty': lambda table: '',
    'a_string': lambda table: 'just text\n',
    'binary': lambda table: '\udcff\x00\x01',
    'other_file': lambda table: '/**/torque_estimator:\n  ros__parameters: {}\n',
    'format_version': lambda table: _document_with(table, format_version=2),
    'state_version': lambda table: _document_with(table, **{'monitor_state.version': 99}),
    'state_malformed': lambda table: _document_with(table, **{'monitor_state': {'version': 1}}),
    'samples': lambda table: _document_with(table, **{'learnt.samples': -3}),
    'stamp': lambda table: _document_with(table, **{'learnt.first_stamp_ns': 'yesterday'}),
    'provenance': lambda table: _document_with(table, provenance=[1, 2]),
    # finite but impossible: each would crash a node that took it (a negative variance
    # under a square root), or is not what this package writes
    'variance_negative': lambda table: _document_with(
        table, **{'monitor_state.ewma_var_nm2': -1.0}),
    'cusum_negative': lambda table: _document_mapped(
        table, 'monitor_state.cusum_pos_nm_s', lambda sums: [-1.0] * len(sums)),
    'gram_not_positive': lambda table: _document_mapped(
        table, 'monitor_state.commissioning.learner.a', _negative_definite),
    'windows_fraction': lambda table: _document_with(table, **{'monitor_state.windows': 2.5}),
    'complete_not_bool': lambda table: _document_with(
        table, **{'monitor_state.baseline_complete': 'yes'}),
    'stamp_beyond_int64': lambda table: _document_with(
        table, **{'learnt.last_stamp_ns': 10**30}),
    # a level is an integer as written: int() would have read each of these as one
    'level_fraction': lambda table: _document_with(table, **{'monitor_state.level': 1.7}),
    'level_text': lambda table: _document_with(table, **{'monitor_state.level': '2'}),
    'level_bool': lambda table: _document_with(table, **{'monitor_state.level': True}),
    # a version is an integer as written: true == 1 and 1.0 == 1 in Python
    'format_version_bool': lambda table: _document_with(table, format_version=True),
    'format_version_float': lambda table: _document_with(table, format_version=1.0),
    # sums that no sequence of windows adds up to: windows learnt with no weight, or
    # weight and sums with no window
    'learner_windows_no_weight': lambda table: _document_with(
        table, **{'monitor_state.commissioning.learner.windows': 3}),
    'learner_weight_no_window': lambda table: _document_with(
        table, **{'monitor_state.commissioning.learner.weight': 2.0}),
    'learner_sums_no_window': lambda table: _document_with(
        table, **{'monitor_state.commissioning.recent.c': 0.5}),
}


@pytest.mark.parametrize('case', sorted(BROKEN))
def test_a_corrupt_or_foreign_file_is_one_line_error_and_never_loaded(table, tmp_path, case):
    path = tmp_path / 'baseline.yaml'
    path.write_bytes(BROKEN[case](table).encode('utf-8', 'surrogateescape'))
    core = make(table)
    with pytest.raises(BaselineError) as info:
        load_baseline(core, path)
    assert not isinstance(info.value, BaselineMismatchError)
    assert str(path) in str(info.value) and '\n' not in str(info.value)
    assert core.learnt[0] == 0 and same(core.monitor.state_dict(),
                                        make(table).monitor.state_dict())


def test_the_node_side_counts_a_bad_file_keeps_it_and_says_why(table, tmp_path):
    path = tmp_path / 'baseline.yaml'
    path.write_text(BROKEN['format_version'](table))
    old = path.read_bytes()
    core = make(table)
    baseline = BaselineStore(path, core)
    core.baseline = baseline
    severity, line = baseline.load()
    assert severity == 'error' and 'format_version 2' in line and '\n' not in line
    assert baseline.errors == 1 and baseline.status.startswith('not used: ')
    feed(core)
    assert baseline.save() == '' and baseline.save(force=True) == ''
    assert path.read_bytes() == old  # learnt in memory only, the file kept
    snap = core.diagnostics(stamps()[-1])
    values = dict(snap.values)
    assert values['baseline_status'].startswith('not used: ') and values['baseline_errors'] == '1'
    assert 'baseline file not used' in snap.message


def test_a_mismatched_file_is_kept_until_a_reset_moves_it_aside(table, tmp_path):
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(learnt_core(table)))
    old = path.read_bytes()
    core = make(table, replace(CONFIG, drive_loss_torque_nm=0.2))
    baseline = BaselineStore(path, core, 'node /torque_estimator')
    severity, line = baseline.load()
    assert severity == 'warning' and 'drive_loss_torque_nm (file 0.05, now 0.2)' in line
    feed(core)
    assert baseline.save() == '' and path.read_bytes() == old
    ok, message = baseline.reset()
    assert ok and 're-learning' in message
    backups = list(tmp_path.glob('baseline.yaml.*.bak'))
    assert len(backups) == 1 and backups[0].read_bytes() == old and str(backups[0]) in message
    doc = read_baseline(path)
    assert doc['learnt']['samples'] == 0 and core.learnt[0] == 0
    assert doc['provenance']['parameters']['drive_loss_torque_nm'] == 0.2
    assert baseline.status == 'saved' and baseline.note == ''


def test_nothing_learnt_since_the_last_save_writes_nothing(table, tmp_path):
    path = tmp_path / 'baseline.yaml'
    core = make(table)
    baseline = BaselineStore(path, core)
    assert baseline.load()[0] == 'info' and baseline.save() == ''
    assert not path.exists() and baseline.note == 'no baseline yet (learning)'
    feed(core)
    assert baseline.save() == '' and read_baseline(path)['learnt']['samples'] == N_MONITORED
    mtime = path.stat().st_mtime_ns
    assert baseline.save() == '' and path.stat().st_mtime_ns == mtime


def test_an_unwritable_path_warns_once_counts_and_never_raises(table, tmp_path):
    blocker = tmp_path / 'file'
    blocker.write_text('')
    core = make(table)
    baseline = BaselineStore(blocker / 'baseline.yaml', core)  # a folder that is a file
    feed(core)
    warning = baseline.save()
    assert warning.startswith('cannot write baseline file ') and '\n' not in warning
    feed(core, start=NS)
    assert baseline.save() == ''  # the same reason: said once
    assert baseline.errors == 2 and baseline.status.startswith('not saved: ')
    assert dict(baseline.diagnostics()[0])['baseline_errors'] == 2


def test_a_file_name_too_long_for_the_file_system_is_one_line_and_never_raises(
        table, tmp_path):
    path = tmp_path / ('b' * 300 + '.yaml')  # past NAME_MAX (255): even stat() fails
    core = make(table)
    baseline = BaselineStore(path, core)
    severity, line = baseline.load()
    assert severity == 'error' and 'File name too long' in line and '\n' not in line
    feed(core)
    assert baseline.save() == '' and not baseline.writable  # learnt in memory only
    assert baseline.status.startswith('not used: ') and baseline.errors == 1


@pytest.mark.parametrize('umask', [0o022, 0o027, 0o077])
def test_a_new_baseline_file_gets_the_permissions_open_would_give_it(table, tmp_path, umask):
    """Not mkstemp's 0o600: the node's user must read what the maintenance user learnt."""
    old = os.umask(umask)
    try:
        write_baseline(tmp_path / 'b.yaml', baseline_document(make(table)))
    finally:
        os.umask(old)
    assert (tmp_path / 'b.yaml').stat().st_mode & 0o777 == 0o666 & ~umask


def test_an_existing_files_permissions_are_kept(table, tmp_path):
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(make(table)))
    os.chmod(path, 0o640)
    write_baseline(path, baseline_document(learnt_core(table)))
    assert path.stat().st_mode & 0o777 == 0o640


def test_archive_moves_the_file_aside_and_keeps_earlier_backups(tmp_path):
    path = tmp_path / 'baseline.yaml'
    assert archive_baseline(path) is None
    path.write_text('first')
    one = archive_baseline(path)
    path.write_text('second')
    two = archive_baseline(path)
    assert not path.exists() and one != two
    assert (one.read_text(), two.read_text()) == ('first', 'second')
    with pytest.raises(OutputError, match='is a folder'):
        archive_baseline(tmp_path)


def test_archive_never_moves_a_named_pipe_or_device_aside(tmp_path):
    fifo = tmp_path / 'baseline.yaml'
    os.mkfifo(fifo)
    with pytest.raises(OutputError, match='not a regular file'):
        archive_baseline(fifo)
    assert fifo.is_fifo() and os.listdir(tmp_path) == ['baseline.yaml']


def test_a_baseline_file_behind_a_symbolic_link_is_written_and_reset_there(table, tmp_path):
    """A link to a persistent volume stays a link: the file it names is written and moved."""
    volume = tmp_path / 'volume'
    volume.mkdir()
    link = tmp_path / 'baseline.yaml'
    link.symlink_to(volume / 'eha1.yaml')
    write_baseline(link, baseline_document(make(table)))  # a dangling link: its file made
    write_baseline(link, baseline_document(learnt_core(table)))
    assert link.is_symlink() and (volume / 'eha1.yaml').is_file()
    assert sorted(os.listdir(tmp_path)) == ['baseline.yaml', 'volume']
    assert read_baseline(link) == read_baseline(volume / 'eha1.yaml')
    aside = archive_baseline(link)
    assert aside is not None and aside.parent == volume and link.is_symlink()
    assert not (volume / 'eha1.yaml').exists()
    writable_folder(link)
    assert sorted(os.listdir(volume)) == [aside.name]  # the probe left nothing


def test_default_file_is_under_ros_home_named_after_the_node(monkeypatch, tmp_path):
    monkeypatch.setenv('ROS_HOME', str(tmp_path))
    assert default_baseline_path('/eha1/torque_estimator') == \
        tmp_path / 'pump_friction_ros' / 'baselines' / 'eha1.torque_estimator.yaml'
    assert baseline_path('', '/torque_estimator') == \
        tmp_path / 'pump_friction_ros' / 'baselines' / 'torque_estimator.yaml'
    monkeypatch.delenv('ROS_HOME')
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    assert default_baseline_path('/torque_estimator') == \
        tmp_path / 'home' / '.ros' / 'pump_friction_ros' / 'baselines' / 'torque_estimator.yaml'


def test_a_relative_baseline_file_is_relative_to_the_current_directory(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    assert baseline_path('state/b.yaml', '/x') == tmp_path / 'state' / 'b.yaml'
    assert baseline_path('/abs/b.yaml', '/x') == Path('/abs/b.yaml')


def _leaves(value, where=()):
    """Yield the path of every entry of a plain structure (a list's first item stands for all)."""
    if where:
        yield where
    if isinstance(value, dict):
        for key, inner in value.items():
            yield from _leaves(inner, (*where, key))
    elif isinstance(value, list) and value:
        yield from _leaves(value[0], (*where, 0))


# what a hand-edited or bit-flipped file can hold where the monitor wrote a number, a list
# or a mapping: infinities, a number past a double's range, the wrong kind of value
WRONG_VALUES = {'inf': math.inf, 'huge': 10**400, 'list': [1], 'null': None, 'text': 'x',
                'mapping': {}, 'bool': True, 'negative': -1}


@pytest.mark.parametrize('wrong', sorted(WRONG_VALUES))
def test_any_entry_of_the_monitor_state_replaced_is_refused_or_usable_never_a_crash(
        table, tmp_path, wrong):
    doc = baseline_document(learnt_core(table))
    fresh = make(table).monitor.state_dict()
    crashes = []
    for where in _leaves(doc['monitor_state']):
        if where == ('version',):
            continue
        broken = json.loads(json.dumps(doc)) if wrong != 'huge' else yaml.safe_load(
            yaml.safe_dump(doc))
        inner = broken['monitor_state']
        for key in where[:-1]:
            inner = inner[key]
        inner[where[-1]] = WRONG_VALUES[wrong]
        core = make(table)
        try:
            restore_baseline(core, broken, tmp_path / 'baseline.yaml')
        except BaselineError as exc:
            if '\n' in str(exc) or not same(core.monitor.state_dict(), fresh) \
                    or core.learnt[0] != 0:
                crashes.append(f'{where}: refused but half loaded or not one line')
            continue
        except Exception as exc:  # what the test is for: any other error
            crashes.append(f'{where}: {type(exc).__name__}: {exc}')
            continue
        try:  # taken: the monitor runs on, and saves a state that loads back
            feed(core, start=10**9)
            again = make(table)
            restore_baseline(again, baseline_document(core), tmp_path / 'baseline.yaml')
        except Exception as exc:
            crashes.append(f'{where}: taken, then {type(exc).__name__}: {exc}')
    assert not crashes, '\n'.join(crashes)
