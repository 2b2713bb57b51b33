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

"""
Bad input and ordinary mistakes, through the command line as a user meets them (issue 11).

Every case writes its input in ``tmp_path`` and runs ``pump_friction`` in a subprocess with
a timeout, so a hang fails the test instead of stalling it. A refused input gives one line
on stderr, exit code 2, no traceback and no output; a skipped message is counted and
reported with exit code 0.
"""

import os
from pathlib import Path
import subprocess
import sys

import pytest

from .conftest import PAPER_PUMP

REPO = Path(__file__).resolve().parents[1]


def cli(env, *argv, cwd=None, timeout=60):
    """Run ``pump_friction`` in a subprocess; a hang fails the test after ``timeout`` s."""
    return subprocess.run([sys.executable, '-m', 'pump_friction_ros.app.cli', *map(str, argv)],
                          capture_output=True, text=True, timeout=timeout, cwd=cwd, env=env,
                          check=False)


def refused(proc, *words):
    """Exit code 2, one line on stderr naming ``words``, no traceback, nothing on stdout."""
    assert proc.returncode == 2, proc.stderr
    assert 'Traceback' not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith('pump_friction: error: ')
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def alias_bomb(depth=9, width=9):
    """YAML "billion laughs": 10 lines that expand to width**depth strings."""
    lines = ['lol0: &a0 [' + ', '.join(['"lol"'] * width) + ']']
    lines += [f'lol{i}: &a{i} [' + ', '.join([f'*a{i - 1}'] * width) + ']'
              for i in range(1, depth + 1)]
    return '\n'.join(lines) + '\n'


# -- hangs ---------------------------------------------------------------------------------


def test_billion_laughs_pump_file_fails_fast_with_one_line(env, tmp_path):
    text = PAPER_PUMP.read_text().replace('n_pistons: 5 ', 'n_pistons: *a9 ')
    pump = tmp_path / 'bomb.yaml'
    pump.write_text(alias_bomb() + text)
    proc = cli(env, 'torque', '--speed-rpm', 1000, '--pressure-bar', 100, '--pump', pump,
               timeout=30)
    line = refused(proc, 'geometry.n_pistons', 'expected an integer')
    assert len(line) < 300


def test_billion_laughs_params_file_fails_fast_with_one_line(env, tmp_path):
    params = tmp_path / 'params.yaml'
    params.write_text(alias_bomb() + '/**/torque_estimator:\n  ros__parameters:\n'
                      '    hardware_id: *a9\n')
    proc = cli(env, 'replay', REPO / 'bags' / 'eha_nominal', '--params', params, timeout=30)
    line = refused(proc, 'hardware_id', 'expected a string')
    assert len(line) < 300


# -- bags written here, message by message -------------------------------------------------

T0 = 1_700_000_000 * 1_000_000_000
JOINT = 'sensor_msgs/msg/JointState'
PRESSURE = 'sensor_msgs/msg/FluidPressure'


def write_bag(path, n=2000, joint=None, pressure=None, extra=(), storage='sqlite3',
              extra_first=False):
    """
    Write a bag of ``n`` joint states at 1 kHz and pressure at 500 Hz, log time = stamp.

    ``joint(k, fields)`` may change the fields of joint state k (``name``, ``velocity``,
    ``effort``, ``stamp_ns``) or return raw bytes to write instead; ``pressure(k, fields)``
    likewise (``fluid_pressure``, ``stamp_ns``); returning None drops the message.
    ``extra`` lists (topic, msgtype, count) of std_msgs/Float64 topics to add, after the
    inputs' connections or, with ``extra_first``, before them.
    """
    import numpy as np
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores

    ts = get_typestore(Stores.ROS2_JAZZY)
    t = ts.types

    def header(ns):
        return t['std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](
            sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id='')

    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3

    def add_extra(writer):
        for topic, msgtype, count in extra:
            conn = writer.add_connection(topic, msgtype, typestore=ts)
            for k in range(count):
                writer.write(conn, T0 + k * 1_000_000,
                             ts.serialize_cdr(t[msgtype](data=float(k)), msgtype))

    with Writer(path, version=9, storage_plugin=plugin) as writer:
        if extra_first:
            add_extra(writer)
        jc = writer.add_connection('/joint_states', JOINT, typestore=ts)
        pc = writer.add_connection('/load_pressure', PRESSURE, typestore=ts)
        for k in range(n):
            log = T0 + k * 1_000_000
            if k % 2 == 0:
                fields = {'fluid_pressure': 150e5, 'stamp_ns': log}
                if pressure is not None:
                    fields = pressure(k, fields)
                if isinstance(fields, bytes):
                    writer.write(pc, log, fields)
                elif fields is not None:
                    msg = t[PRESSURE](header=header(fields['stamp_ns']),
                                      fluid_pressure=fields['fluid_pressure'], variance=0.0)
                    writer.write(pc, log, ts.serialize_cdr(msg, PRESSURE))
            fields = {'name': ['pump_shaft'], 'velocity': [400.0 + 0.01 * k],
                      'effort': [8.0], 'stamp_ns': log}
            if joint is not None:
                fields = joint(k, fields)
            if isinstance(fields, bytes):
                writer.write(jc, log, fields)
            elif fields is not None:
                msg = t[JOINT](header=header(fields['stamp_ns']), name=fields['name'],
                               position=np.zeros(0), velocity=np.array(fields['velocity']),
                               effort=np.array(fields['effort']))
                writer.write(jc, log, ts.serialize_cdr(msg, JOINT))
        if not extra_first:
            add_extra(writer)
    return path


def joint_cdr(fields):
    """Serialise a JointState of ``fields`` (as `write_bag` passes them)."""
    import numpy as np
    from rosbags.typesys import get_typestore, Stores

    ts = get_typestore(Stores.ROS2_JAZZY)
    t = ts.types
    ns = fields['stamp_ns']
    msg = t[JOINT](header=t['std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](
        sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id=''),
        name=fields['name'], position=np.zeros(0), velocity=np.array(fields['velocity']),
        effort=np.array(fields['effort']))
    return bytes(ts.serialize_cdr(msg, JOINT))


def summary_counts(stdout):
    """Return the replay summary's 'skipped:' counters as a dict."""
    line = next(x for x in stdout.splitlines() if x.strip().startswith('skipped:'))
    items = line.split(':', 1)[1].split(',')
    return {k: int(v) for k, v in (item.split() for item in items)}


def estimates_of(stdout):
    line = next(x for x in stdout.splitlines() if x.strip().startswith('estimates:'))
    return int(line.split()[1])


def test_corrupted_name_count_is_skipped_counted_and_reported(env, tmp_path):
    def corrupt(k, fields):
        if k != 700:
            return fields
        raw = joint_cdr(fields)
        at = raw.index(b'\x01\x00\x00\x00\x0b\x00\x00\x00pump_shaft')  # name count 1
        return raw[:at] + (0x0FFFFFFF).to_bytes(4, 'little') + raw[at + 4:]

    bag = write_bag(tmp_path / 'bag', joint=corrupt)
    proc = cli(env, 'replay', bag, '--quiet', timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ''
    counts = summary_counts(proc.stdout)
    assert counts['rejected_undecodable'] == 1
    assert estimates_of(proc.stdout) == 1999


@pytest.mark.parametrize(('change', 'counter'), [
    (lambda f: f.update(name=['motor']), 'rejected_missing_joint'),
    (lambda f: f.update(velocity=[], effort=[]), 'rejected_malformed'),
    (lambda f: f.update(name=['pump_shaft', 'other']), 'rejected_malformed'),
    (lambda f: f.update(effort=[1.0, 2.0]), 'rejected_malformed'),
    (lambda f: f.update(name=['pump_shaft'] * 2, velocity=f['velocity'] * 2,
                        effort=f['effort'] * 2), 'rejected_malformed'),  # joint named twice
])
def test_a_bag_of_only_defective_joint_states_says_no_estimate_and_why(env, tmp_path, change,
                                                                       counter):
    def defect(k, fields):
        change(fields)
        return fields

    bag = write_bag(tmp_path / 'bag', joint=defect)
    out = tmp_path / 'out'
    proc = cli(env, 'replay', bag, '--out', out, '--csv', tmp_path / 'e.csv', '--quiet')
    refused(proc, 'no estimate', f'{counter} 2000')
    assert sorted(p.name for p in tmp_path.iterdir()) == ['bag']  # nothing written


def test_defective_joint_states_among_good_ones_are_counted_like_the_node(env, tmp_path):
    kinds = {0: lambda f: f.update(name=['motor']),
             1: lambda f: f.update(velocity=[], effort=[]),
             2: lambda f: f.update(name=['pump_shaft', 'other']),
             3: lambda f: f.update(effort=[float('nan')])}

    def some(k, fields):
        if k % 10 == 5:
            kinds[(k // 10) % 4](fields)
        return fields

    proc = cli(env, 'replay', write_bag(tmp_path / 'bag', joint=some), '--quiet')
    assert proc.returncode == 0, proc.stderr
    counts = summary_counts(proc.stdout)
    assert counts['rejected_missing_joint'] == counts['rejected_non_finite'] == 50
    assert counts['rejected_malformed'] == 100
    assert estimates_of(proc.stdout) == 2000 - 150  # a NaN effort still has its speed


def test_a_fleet_and_learn_baseline_say_what_each_bag_skipped(env, tmp_path):
    def nan_speed(k, fields):
        if k % 10 == 5:
            fields.update(velocity=[float('nan')])
        return fields

    write_bag(tmp_path / 'fleet' / 'clean')
    write_bag(tmp_path / 'fleet' / 'nans', joint=nan_speed)
    proc = cli(env, 'replay', tmp_path / 'fleet', '--workers', '2', '--quiet')
    assert proc.returncode == 0, proc.stderr
    lines = {line.split(':')[0]: line for line in proc.stdout.splitlines()
             if ' estimates, ' in line}
    assert 'skipped' not in lines['clean']
    assert lines['nans'].endswith(', skipped: rejected_non_finite 200'), lines['nans']
    proc = cli(env, 'learn-baseline', tmp_path / 'fleet' / 'nans', '--out', tmp_path / 'b.yaml',
               '--quiet')
    assert proc.returncode == 0, proc.stderr
    assert ' monitored samples, skipped: rejected_non_finite 200' in proc.stdout, proc.stdout


@pytest.mark.parametrize('first', [True, False])
def test_another_type_on_an_input_topic_is_not_read_and_is_reported(env, tmp_path, first):
    clean = write_bag(tmp_path / 'clean', n=1000)
    mixed = write_bag(tmp_path / 'mixed', n=1000, extra_first=first,
                      extra=[('/load_pressure', 'std_msgs/msg/Float64', 999)])
    runs = [cli(env, 'replay', bag, '--csv', tmp_path / f'{bag.name}.csv')
            for bag in (clean, mixed)]
    assert all(proc.returncode == 0 for proc in runs), runs[1].stderr
    assert estimates_of(runs[0].stdout) == estimates_of(runs[1].stdout) > 0
    # the node's FluidPressure subscription never receives the Float64s: the same outputs
    assert (tmp_path / 'clean.csv').read_text() == (tmp_path / 'mixed.csv').read_text()
    assert 'not read, of another type: /load_pressure (std_msgs/msg/Float64) 999' \
        in runs[1].stdout
    assert 'of another type' not in runs[0].stdout


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
@pytest.mark.parametrize('shift_s, stretch_s', [(-1000, 0), (0, 500), (10**9, 0)])
def test_the_time_span_comes_from_the_storage_not_an_edited_metadata_file(
        env, tmp_path, storage, shift_s, stretch_s):
    import yaml
    bags = [write_bag(tmp_path / name, n=1000, storage=storage) for name in ('true', 'edited')]
    meta_file = bags[1] / 'metadata.yaml'
    meta = yaml.safe_load(meta_file.read_text())
    info = meta['rosbag2_bagfile_information']
    info['starting_time']['nanoseconds_since_epoch'] += shift_s * 10**9
    info['duration']['nanoseconds'] += stretch_s * 10**9
    meta_file.write_text(yaml.safe_dump(meta))
    runs = [cli(env, 'replay', bag, '--csv', tmp_path / f'{bag.name}.csv', '--out',
                tmp_path / f'{bag.name}_out') for bag in bags]
    assert all(proc.returncode == 0 for proc in runs), runs[1].stderr
    assert (tmp_path / 'true.csv').read_text() == (tmp_path / 'edited.csv').read_text()
    # the same duration, no gap, the same /diagnostics (count) in the output bag
    head = [line for line in runs[0].stdout.splitlines() if 'replayed in' not in line
            and 'out' not in line]
    assert head == [line.replace('edited', 'true') for line in runs[1].stdout.splitlines()
                    if 'replayed in' not in line and 'out' not in line]


def test_a_replay_whose_diagnostics_are_all_stale_does_not_just_say_no_alarm(env, tmp_path):
    """Header stamps an hour behind the log time: the node's /diagnostics would be STALE."""
    hour = 3600 * 10**9

    def behind(k, fields):
        return {**fields, 'stamp_ns': fields['stamp_ns'] - hour}

    bag = write_bag(tmp_path / 'bag', n=5000, joint=behind, pressure=behind)
    proc = cli(env, 'replay', bag, '--out', tmp_path / 'out')
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert '  no alarm' not in lines
    assert '  no alarm from the monitor, but every /diagnostics status was STALE' in lines
    stale = [line for line in lines if line.startswith('  /diagnostics STALE in ')]
    assert len(stale) == 1 and 'stamped 3600 s before this clock' in stale[0]
    good = cli(env, 'replay', write_bag(tmp_path / 'good', n=5000), '--out', tmp_path / 'o2')
    assert '  no alarm' in good.stdout.splitlines() and 'STALE in' not in good.stdout


@pytest.mark.parametrize(('remaps', 'words'), [
    (['joint_state:=/eha/js'], 'the node has no input /joint_state'),  # a typo
    (['joint_states:=/a:=/b'], "bad --topic-remap 'joint_states:=/a:=/b'"),
    (['joint_states:=/a', 'joint_states:=/b'], '/joint_states remapped twice'),
    (['load_pressure:=/joint_states'], '/joint_states and /load_pressure would both read'),
])
def test_a_topic_remap_that_cannot_mean_what_it_says_is_refused(env, tmp_path, remaps, words):
    bag = write_bag(tmp_path / 'bag', n=50)
    refused(cli(env, 'replay', bag, '--topic-remap', *remaps), words)


def test_input_topics_without_messages_are_refused_even_if_another_topic_has_some(env,
                                                                                  tmp_path):
    bag = write_bag(tmp_path / 'bag', n=0, extra=[('/chatter', 'std_msgs/msg/Float64', 300)])
    refused(cli(env, 'replay', bag, '--out', tmp_path / 'out'), 'hold no messages')
    assert not (tmp_path / 'out').exists()


def test_metadata_claiming_no_messages_does_not_hide_the_storages(env, tmp_path):
    import yaml

    bag = write_bag(tmp_path / 'bag', n=3000)
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())
    info = meta['rosbag2_bagfile_information']
    info['message_count'] = 0
    for topic in info['topics_with_message_count']:
        topic['message_count'] = 0
    (bag / 'metadata.yaml').write_text(yaml.safe_dump(meta))
    proc = cli(env, 'replay', bag, '--quiet')
    assert proc.returncode == 0, proc.stderr
    assert estimates_of(proc.stdout) == 3000
    assert '/joint_states 3000, /load_pressure 1500' in proc.stdout


def test_metadata_listing_a_storage_file_twice_is_refused_not_read_twice(env, tmp_path):
    import yaml

    bag = write_bag(tmp_path / 'bag', n=3000)
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())
    info = meta['rosbag2_bagfile_information']
    name = info['relative_file_paths'][0]
    info['relative_file_paths'] = [name, f'elsewhere/{name}']  # rosbags reads the base name
    (bag / 'metadata.yaml').write_text(yaml.safe_dump(meta))
    refused(cli(env, 'replay', bag, '--out', tmp_path / 'out'), 'metadata.yaml', 'twice', name)
    assert not (tmp_path / 'out').exists()


# -- outputs that cannot be made: one line naming the target, nothing half-written ---------

BENCH = REPO / 'config' / 'examples' / 'bench_example.csv'


def listing(folder):
    """Every path under ``folder``, relative, hidden ones included."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob('*'))


@pytest.mark.parametrize('flag', ['--out', '--csv', '--plots'])
def test_replay_output_below_a_regular_file_is_refused(env, tmp_path, flag):
    (tmp_path / 'file').write_text('a regular file\n')
    bag = write_bag(tmp_path / 'bag', n=50)
    before = listing(tmp_path)
    line = refused(cli(env, 'replay', bag, flag, tmp_path / 'file' / 'x'),
                   'cannot create the output', 'is not a folder')
    assert 'partial' not in line
    assert listing(tmp_path) == before


def test_replay_output_where_nothing_can_be_written_names_no_temporary_file(env, tmp_path):
    bag = write_bag(tmp_path / 'bag', n=50)
    line = refused(cli(env, 'replay', bag, '--out', '/proc/bag'), '/proc/bag')
    assert 'partial' not in line and 'Error' not in line


def test_calibrate_out_below_a_regular_file_is_refused(env, tmp_path):
    (tmp_path / 'file').write_text('x\n')
    refused(cli(env, 'calibrate', BENCH, '--pump', PAPER_PUMP, '--out',
                tmp_path / 'file' / 'pump.yaml'), 'is not a folder')
    assert listing(tmp_path) == ['file']


def test_calibrate_report_below_a_file_leaves_no_pump_file_behind(env, tmp_path):
    (tmp_path / 'file').write_text('x\n')
    refused(cli(env, 'calibrate', BENCH, '--pump', PAPER_PUMP, '--out', tmp_path / 'pump.yaml',
                '--report', tmp_path / 'file' / 'report'), 'report', 'is not a folder')
    assert listing(tmp_path) == ['file']  # no pump.yaml, no staging folder


def test_build_table_out_below_a_file_and_over_a_file(env, tmp_path):
    (tmp_path / 'file').write_text('x\n')
    refused(cli(env, 'build-table', '--quiet', '--out', tmp_path / 'file' / 't.npz'),
            'is not a folder')
    table = tmp_path / 'table.npz'
    table.write_text('an earlier file\n')
    refused(cli(env, 'build-table', '--quiet', '--out', table), 'output exists', '--force')
    assert table.read_text() == 'an earlier file\n'
    proc = cli(env, 'build-table', '--quiet', '--out', table, '--force',
               '--max-speed-rpm', 2000)
    assert proc.returncode == 0, proc.stderr
    assert table.read_bytes()[:2] == b'PK' and listing(tmp_path) == ['file', 'table.npz']


def test_force_never_replaces_an_output_of_another_kind(env, tmp_path):
    folder = tmp_path / 'important'
    folder.mkdir()
    (folder / 'notes.txt').write_text('keep me\n')
    bag = write_bag(tmp_path / 'bag', n=50)
    refused(cli(env, 'replay', bag, '--csv', folder, '--force'), 'is a folder')
    refused(cli(env, 'replay', bag, '--out', folder, '--force'), 'does not look like')
    assert (folder / 'notes.txt').read_text() == 'keep me\n'


@pytest.mark.parametrize('argv', [
    ('replay', 'BAG', '--csv', 'PIPE'), ('replay', 'BAG', '--out', 'PIPE'),
    ('learn-baseline', 'BAG', '--out', 'PIPE'),
    ('build-table', '--out', 'PIPE'),
    ('calibrate', 'CSV', '--pump', PAPER_PUMP, '--out', 'PIPE'),
])
def test_force_never_replaces_a_named_pipe_or_a_device_with_a_file(env, tmp_path, argv):
    pipe = tmp_path / 'pipe'  # stands for /dev/null, which a test must not risk
    os.mkfifo(pipe)
    bag = write_bag(tmp_path / 'bag', n=50) if 'BAG' in argv else None
    csv = tmp_path / 'bench.csv'
    csv.write_text('speed_rpm,pressure_bar,torque_nm\n1000,100,2.0\n2000,150,3.0\n')
    given = {'PIPE': pipe, 'BAG': bag, 'CSV': csv}
    argv = [given.get(arg, arg) if isinstance(arg, str) else arg for arg in argv]
    refused(cli(env, *argv, '--force'), str(pipe), 'named pipe', 'not replaced')
    assert pipe.is_fifo()


@pytest.mark.parametrize('argv', [
    ('learn-baseline', 'BAG', '--out', 'BAG/metadata.yaml'),
    ('calibrate', 'BAG', '--pump', PAPER_PUMP, '--out', 'BAG/metadata.yaml'),
    ('calibrate', 'CSV', '--pump', PAPER_PUMP, '--out', 'CSV'),
    ('calibrate', 'CSV', '--pump', PAPER_PUMP, '--out', 'OUT', '--report', 'HERE'),
])
def test_force_never_writes_an_output_into_or_over_an_input(env, tmp_path, argv):
    bag = write_bag(tmp_path / 'data' / 'bag', n=50)
    csv = tmp_path / 'data' / 'bench.csv'
    csv.write_text('speed_rpm,pressure_bar,torque_nm\n1000,100,2.0\n2000,150,3.0\n')
    given = {'BAG': str(bag), 'CSV': str(csv), 'OUT': str(tmp_path / 'p.yaml'),
             'HERE': str(tmp_path / 'data')}
    argv = [arg.replace(arg.split('/')[0], given[arg.split('/')[0]])
            if isinstance(arg, str) and arg.split('/')[0] in given else arg for arg in argv]
    before = {p: p.read_bytes() for p in (tmp_path / 'data').rglob('*') if p.is_file()}
    refused(cli(env, *argv, '--force'), 'an output cannot be at, in or around the input')
    assert {p: p.read_bytes() for p in (tmp_path / 'data').rglob('*') if p.is_file()} == before
    assert not (tmp_path / 'p.yaml').exists()


# -- fleets: unique output names, folders not files, paths that survive a Dask worker -------


@pytest.fixture(scope='module')
def small_bag(tmp_path_factory):
    return write_bag(tmp_path_factory.mktemp('small') / 'bag', n=1000)


def test_fleet_bags_with_the_same_name_get_distinct_outputs(env, tmp_path, small_bag):
    import shutil
    for site in ('site_a', 'site_b'):
        shutil.copytree(small_bag, tmp_path / 'fleet' / site / 'run1')
    proc = cli(env, 'replay', tmp_path / 'fleet', '--csv', tmp_path / 'csv', '--out',
               tmp_path / 'out', '--workers', 2, '--quiet')
    assert proc.returncode == 0, proc.stderr
    assert listing(tmp_path / 'csv') == ['site_a', 'site_a/run1.csv', 'site_b',
                                         'site_b/run1.csv']
    assert (tmp_path / 'out' / 'site_a' / 'run1' / 'metadata.yaml').exists()
    assert (tmp_path / 'out' / 'site_b' / 'run1' / 'metadata.yaml').exists()
    table = proc.stdout.split('\n\n')[-1]
    assert 'site_a/run1 ' in table and 'site_b/run1 ' in table


@pytest.mark.parametrize(('flags', 'words'), [
    (['--csv', 'res/m3.csv'], ['--csv res/m3.csv', 'names a folder']),
    (['--out', 'res/x', '--plots', 'res/x'], ['--out and --plots name the same output']),
    (['--out', 'a'], ['an output cannot be at, in or around the input ']),
])
def test_fleet_output_mistakes_are_refused_before_anything_runs(env, tmp_path, small_bag,
                                                                flags, words):
    import shutil
    shutil.copytree(small_bag, tmp_path / 'a')
    shutil.copytree(small_bag, tmp_path / 'b')
    before = listing(tmp_path)
    refused(cli(env, 'replay', 'a', 'b', *flags, cwd=tmp_path), *words)
    assert listing(tmp_path) == before


def test_the_same_bag_twice_is_refused(env, small_bag):
    refused(cli(env, 'replay', small_bag, small_bag.parent), 'bag given twice')


def test_dask_workers_in_another_directory_find_relative_paths(env, tmp_path, small_bag,
                                                               monkeypatch):
    import shutil
    distributed = pytest.importorskip('dask.distributed', reason='dask[distributed] missing')
    work = tmp_path / 'work'
    for name in ('eha_a', 'eha_b'):
        shutil.copytree(small_bag, work / 'bags' / name)
    elsewhere = tmp_path / 'elsewhere'
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # the workers start here, not where the bags are
    monkeypatch.setenv('XDG_CACHE_HOME', env['XDG_CACHE_HOME'])
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        proc = cli(env, 'replay', 'bags/eha_a', 'bags/eha_b', '--csv', 'out/csv', '--dask',
                   cluster.scheduler_address, cwd=work, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert listing(work / 'out') == ['csv', 'csv/eha_a.csv', 'csv/eha_b.csv']
    assert not list(elsewhere.iterdir())


# -- Ctrl-C: one line, exit code 130, nothing left -----------------------------------------


def interrupt(env, argv, watch, group=True, cwd=None, signum=None):
    """Start the CLI, wait until it stages an output under ``watch``, then Ctrl-C it."""
    import signal
    import time

    signum = signal.SIGINT if signum is None else signum

    def as_in_a_terminal():  # a runner in the background starts us with Ctrl-C ignored
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    proc = subprocess.Popen([sys.executable, '-m', 'pump_friction_ros.app.cli', *map(str, argv)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env, cwd=cwd, start_new_session=True,
                            preexec_fn=as_in_a_terminal)
    try:
        end = time.monotonic() + 60
        while not any('.partial' in p.name for p in watch.rglob('*')) if watch.exists() \
                else True:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < end, 'no staged output appeared'
            time.sleep(0.005)
        if group:  # a terminal's Ctrl-C reaches the whole foreground process group
            os.killpg(proc.pid, signum)
        else:  # kill -INT <pid>: the command itself must stop its helpers
            proc.send_signal(signum)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode, out, err


@pytest.fixture(scope='module')
def long_bag(tmp_path_factory, env):
    """Copy a 75 s sample bag to a private folder (the CLI is interrupted replaying it)."""
    import shutil
    bag = tmp_path_factory.mktemp('long') / 'eha_wear'
    shutil.copytree(REPO / 'bags' / 'eha_valve_plate_wear', bag)
    cli(env, 'build-table', '--quiet')  # warm the cache: the replay starts at once
    return bag


def test_ctrl_c_during_a_replay_leaves_nothing(env, tmp_path, long_bag):
    res = tmp_path / 'res'
    code, out, err = interrupt(env, ['replay', long_bag, '--out', res / 'bag', '--csv',
                                     res / 'e.csv', '--plots', res / 'plots'], tmp_path)
    assert (code, err) == (130, 'pump_friction: interrupted\n')
    assert 'Traceback' not in out
    assert not res.exists()  # no output, no staging folder, no folder made for them


@pytest.mark.parametrize('group', [False, True], ids=['kill', 'killpg'])
def test_sigterm_during_a_replay_or_a_fleet_leaves_nothing_and_says_terminated(
        env, tmp_path, long_bag, group):
    import shutil
    import signal
    for name in ('one', 'two'):
        shutil.copytree(long_bag, tmp_path / 'fleet' / name)
    for bags, res in (([long_bag], tmp_path / 'res1'), ([tmp_path / 'fleet'], tmp_path / 'res2')):
        code, out, err = interrupt(env, ['replay', *bags, '--workers', '2', '--out', res / 'bag',
                                         '--csv', res / 'csv', '--plots', res / 'plots'],
                                   tmp_path, group=group, signum=signal.SIGTERM)
        assert (code, err) == (143, 'pump_friction: terminated\n'), out
        assert not res.exists(), listing(res)  # no output, no staging folder
        assert not any('.partial' in p.name for p in tmp_path.rglob('*')), listing(tmp_path)


SECOND_CTRL_C = '''
import os, signal, sys
from pump_friction_ros.app import cli, data_commands


class CtrlCWhileReporting:
    """stderr that receives another Ctrl-C while the first one is being reported."""

    def write(self, text):
        os.kill(os.getpid(), signal.SIGINT)
        return sys.__stderr__.write(text)

    def flush(self):
        sys.__stderr__.flush()


def interrupted(args):
    sys.stderr = CtrlCWhileReporting()
    raise KeyboardInterrupt


data_commands.cmd_evaluate_monitor = interrupted
sys.exit(cli.main(['evaluate-monitor', '--quick']))
'''


def test_a_second_ctrl_c_while_reporting_the_first_still_exits_130_with_one_line(env):
    # a Ctrl-C pending when the first is caught (a second keypress, or one noted during the
    # clean-up) was raised in the report: the process died of SIGINT (-2), not exit 130
    proc = subprocess.run([sys.executable, '-c', SECOND_CTRL_C], capture_output=True,
                          text=True, timeout=60, env=env, check=False)
    assert (proc.returncode, proc.stderr) == (130, 'pump_friction: interrupted\n')


CTRL_C_AFTER_THE_COMMIT = """
import os, signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal, not a runner's
from pump_friction_ros.app import cli, data_commands
from pump_friction_ros.staging import StagedOutputs


def committed_then_interrupted(args):
    staged = StagedOutputs()
    item = staged.add(sys.argv[1], False, False)
    item.path.write_text('complete\\n')
    staged.commit()
    os.kill(os.getpid(), signal.SIGINT)  # while the summary prints: the output is in place
    print('summary')
    return 0


data_commands.cmd_evaluate_monitor = committed_then_interrupted
sys.exit(cli.main(['evaluate-monitor', '--quick']))
"""


def test_a_ctrl_c_after_the_outputs_are_in_place_says_they_are_complete(env, tmp_path):
    out = tmp_path / 'result.txt'
    proc = subprocess.run([sys.executable, '-c', CTRL_C_AFTER_THE_COMMIT, str(out)],
                          capture_output=True, text=True, timeout=60, env=env, check=False)
    assert proc.returncode == 130
    assert proc.stderr == (f'pump_friction: interrupted after writing {out} (complete; nothing '
                           'else was written)\n')
    assert out.read_text() == 'complete\n'


SIGNAL_IN_A_FINALISER = '''
import os, signal, sys
from pump_friction_ros.app import cli
from pump_friction_ros.bags import replay

SIGNAL = signal.{signal}


class CollectedDuringTheSignal:
    """An object whose finaliser runs when the signal arrives (a pipe's end, an NpzFile)."""

    def __del__(self):
        os.kill(os.getpid(), SIGNAL)  # raised in __del__: Python only prints it


run = replay._run


def run_with_the_signal_in_a_finaliser(*args, **kwargs):
    CollectedDuringTheSignal()
    return run(*args, **kwargs)


replay._run = run_with_the_signal_in_a_finaliser  # (in a fleet, in each forked worker)
sys.exit(cli.main(sys.argv[1:]))
'''
CTRL_C_IN_A_FINALISER = SIGNAL_IN_A_FINALISER.format(signal='SIGINT')
SIGTERM_IN_A_FINALISER = SIGNAL_IN_A_FINALISER.format(signal='SIGTERM')


def test_a_ctrl_c_that_lands_in_a_finaliser_still_interrupts_and_leaves_nothing(
        env, tmp_path, long_bag):
    # CI, f314839: the Ctrl-C landed in a multiprocessing Connection's __del__, where Python
    # prints a KeyboardInterrupt and goes on: the replay ran to its end and committed (exit 0)
    import signal
    res = tmp_path / 'res'
    proc = subprocess.run([sys.executable, '-c', CTRL_C_IN_A_FINALISER, 'replay', str(long_bag),
                           '--out', str(res / 'bag'), '--csv', str(res / 'e.csv')],
                          capture_output=True, text=True, timeout=120, env=env, check=False,
                          # as in a terminal: a runner in the background ignores Ctrl-C
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert (proc.returncode, proc.stderr) == (130, 'pump_friction: interrupted\n')
    assert not res.exists(), listing(res)


@pytest.mark.parametrize('group', [True, False])
def test_ctrl_c_during_a_fleet_leaves_nothing(env, tmp_path, long_bag, group):
    import shutil
    for name in ('one', 'two', 'three'):
        shutil.copytree(long_bag, tmp_path / 'fleet' / name)
    res = tmp_path / 'res'
    code, _, err = interrupt(env, ['replay', tmp_path / 'fleet', '--workers', 2, '--out',
                                   res / 'bags', '--csv', res / 'csv'], res, group=group)
    assert (code, err) == (130, 'pump_friction: interrupted\n')
    assert not res.exists(), listing(res)


def test_a_sigterm_that_lands_in_a_workers_finaliser_still_stops_it_and_leaves_nothing(
        env, tmp_path, long_bag):
    # CI, e782729: the parent's SIGTERM (after a Ctrl-C) landed in a worker's NpzFile.__del__,
    # where Python printed "Exception ignored ... SystemExit" and the worker replayed on. Each
    # worker here is sent one there: it stops at the replay's next check, quietly, exit 143
    import shutil
    for name in ('one', 'two'):
        shutil.copytree(long_bag, tmp_path / 'fleet' / name)
    res = tmp_path / 'res'
    proc = subprocess.run([sys.executable, '-c', SIGTERM_IN_A_FINALISER, 'replay',
                           str(tmp_path / 'fleet'), '--workers', '2', '--out', str(res / 'bags'),
                           '--csv', str(res / 'csv')],
                          capture_output=True, text=True, timeout=120, env=env, check=False)
    assert (proc.returncode, proc.stderr) == (
        2, 'pump_friction: error: 2 of 2 bags failed: one, two (why: above)\n')
    for name in ('one', 'two'):
        assert f'{name}: FAILED: the worker process died (exit code 143)' in proc.stdout
    assert not res.exists(), listing(res)


# -- pump files: any valid piston count works, physical ranges are enforced -----------------


def pump_file(path, **geometry_or_values):
    """Write the paper's pump file with some values changed (``section__key=value``)."""
    import yaml
    raw = yaml.safe_load(PAPER_PUMP.read_text())
    for name, value in geometry_or_values.items():
        section, key = name.split('__')
        raw[section][key] = value
    path.write_text(yaml.safe_dump(raw))
    return path


def same_displacement(n):
    """Geometry of the paper pump redrawn with n pistons of its displacement (test_model)."""
    import math
    return {'geometry__n_pistons': n, 'geometry__bore_diameter_m': 9.5e-3 * math.sqrt(5 / n),
            'geometry__bore_pitch_radius_m': 11.5e-3}


@pytest.mark.parametrize('n', [7, 9])
def test_pumps_with_seven_or_nine_pistons_work_model_and_table(env, tmp_path, n):
    import json
    pump = pump_file(tmp_path / f'p{n}.yaml', **same_displacement(n))
    proc = cli(env, 'torque', '--speed-rpm', 4000, '--pressure-bar', 136, '--pump', pump,
               '--json')
    assert proc.returncode == 0, proc.stderr
    model = json.loads(proc.stdout)
    assert all(v is not None for v in model.values())
    assert model['theoretical_nm'] == pytest.approx(4.8979354e-6 * 136e5 / (2 * 3.141592653589793))
    table = tmp_path / 't.npz'
    assert cli(env, 'build-table', '--pump', pump, '--out', table, '--quiet').returncode == 0
    proc = cli(env, 'torque', '--speed-rpm', 4000, '--pressure-bar', 136, '--pump', pump,
               '--json', '--table', table)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)['friction_nm'] == pytest.approx(model['friction_nm'],
                                                                   rel=5e-3)


@pytest.mark.parametrize(('values', 'words'), [
    ({'geometry__n_pistons': 10**9}, ['geometry.n_pistons', 'do not fit']),
    ({'geometry__n_pistons': 7}, ['7 bores of 0.0095 m do not fit']),  # the paper's bores
    ({'geometry__n_pistons': 7, 'geometry__bore_diameter_m': 6e-3},
     ['barrel would lift off']),  # small bores under the paper's (balanced) valve plate
    ({'valve_plate__film_clearance_m': 1e-320}, ['film_clearance_m', 'must be >= 1e-07']),
    ({'oil__viscosity_m2_s': 70.0}, ['oil.viscosity_m2_s', 'must be <= 0.01']),  # cSt, not SI
])
def test_unphysical_pump_values_are_refused(env, tmp_path, values, words):
    pump = pump_file(tmp_path / 'p.yaml', **values)
    refused(cli(env, 'torque', '--speed-rpm', 4000, '--pressure-bar', 136, '--pump', pump),
            *words)


# -- mistakes a new user makes with params files ----------------------------------------------


def test_a_partial_params_file_changes_only_what_it_names(env, tmp_path):
    one = tmp_path / 'one.yaml'
    one.write_text('/**/torque_estimator:\n  ros__parameters:\n    hardware_id: pump_7\n')
    bag = REPO / 'bags' / 'eha_nominal'
    alone = cli(env, 'replay', bag, '--params', one, '--quiet')
    default = cli(env, 'replay', bag, '--quiet')
    assert alone.returncode == default.returncode == 0
    # hardware_id changes nothing else: the same model as without a params file

    def strip(text):
        return [line for line in text.splitlines()
                if 'replayed in' not in line and 'node parameters from' not in line]

    assert strip(alone.stdout) == strip(default.stdout)
    assert '  WARN: none' in alone.stdout  # the bag's own parameters (node_params.yaml) hold
    # with the sample bags' own parameters first, the healthy bag stays healthy
    both = cli(env, 'replay', bag, '--params', REPO / 'bags' / 'eha_params.yaml', '--params',
               one, '--quiet')
    assert both.returncode == 0, both.stderr
    assert '  WARN: none' in both.stdout and '  ERROR: none' in both.stdout


def test_a_relative_pump_file_from_another_directory_is_explained(env, tmp_path):
    out = tmp_path / 'repo' / 'out'
    out.mkdir(parents=True)
    (out / 'my_pump.yaml').write_text(PAPER_PUMP.read_text())
    params = out / 'my_params.yaml'
    params.write_text('/**/torque_estimator:\n  ros__parameters:\n    pump_file: '
                      'out/my_pump.yaml\n')
    elsewhere = tmp_path / 'elsewhere'
    elsewhere.mkdir()
    line = refused(cli(env, 'replay', REPO / 'bags' / 'eha_nominal', '--params', params,
                       cwd=elsewhere), 'pump_file', str(params), str(elsewhere),
                   'current directory')
    assert 'package://' in line
    ok = cli(env, 'replay', REPO / 'bags' / 'eha_nominal', '--params',
             REPO / 'bags' / 'eha_params.yaml', '--params', params, '--quiet',
             cwd=tmp_path / 'repo')
    assert ok.returncode == 0, ok.stderr


def test_replay_counts_exactly_what_the_nodes_conversion_counts(tmp_path, env, monkeypatch):
    """Batch decoder + replay vs rosbags messages through the node's own conversion."""
    from pump_friction_ros.bags.replay import replay_bag
    from pump_friction_ros.core.estimator_setup import estimator_from_config
    from pump_friction_ros.core.inputs import INPUTS
    from pump_friction_ros.core.node_parameters import EstimatorConfig
    from pump_friction_ros.messages.conversions import input_sample, stamp_to_ns
    from rosbags.highlevel import AnyReader

    monkeypatch.setenv('XDG_CACHE_HOME', env['XDG_CACHE_HOME'])
    kinds = {0: lambda f: f.update(name=['motor']),
             1: lambda f: f.update(velocity=[], effort=[]),
             2: lambda f: f.update(effort=[1.0, 2.0]),
             3: lambda f: f.update(effort=[float('nan')]),
             4: lambda f: f.update(velocity=[float('inf')]),
             5: lambda f: f.update(stamp_ns=f['stamp_ns'] + 10 * 365 * 86400 * 10**9)}

    def some(k, fields):
        if k % 7 == 3:
            kinds[(k // 7) % 6](fields)
        return fields

    def pressure(k, fields):
        if k % 50 == 10:
            fields['fluid_pressure'] = float('nan')
        return fields

    bag = write_bag(tmp_path / 'bag', joint=some, pressure=pressure)
    config = EstimatorConfig()
    summary = replay_bag(bag, config, keep_estimates=True)
    node = estimator_from_config(config)
    by_topic = {'/' + spec.topic: spec for spec in INPUTS}
    made = []
    with AnyReader([bag]) as reader:
        for conn, log_ns, raw in reader.messages():
            spec = by_topic[conn.topic]
            msg = reader.deserialize(raw, conn.msgtype)  # what rclpy hands the node
            value, torque, defect = input_sample(spec, msg, config.joint_name)
            if defect:
                node.on_defect(defect)
                continue
            stamp = stamp_to_ns(msg.header.stamp) or log_ns
            est = node.on_input(spec.kind, stamp, value, torque, log_ns)
            if est is not None:
                made.append(est)
    assert summary.counts == node.counts
    assert all(v > 0 for k, v in node.counts.items() if k in (
        'rejected_missing_joint', 'rejected_malformed', 'rejected_non_finite',
        'rejected_future_stamp'))
    assert [e.expected_nm for e in summary.estimates_list] == [e.expected_nm for e in made]


FILE_SIZE_LIMITED = """
import resource, signal, sys
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails, as on a full disk
resource.setrlimit(resource.RLIMIT_FSIZE, (int(sys.argv[1]), int(sys.argv[1])))
from pump_friction_ros.app.cli import main
raise SystemExit(main(sys.argv[2:]))
"""


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='RLIMIT_FSIZE as on Linux')
def test_sample_bags_on_a_full_disk_give_one_line_and_leave_nothing(env, tmp_path):
    out = tmp_path / 'bags'
    assert cli(env, 'make-sample-bags', '--out', tmp_path / 'warm', '--duration-s', 1
               ).returncode == 0  # the table cached first: only the bags meet the limit
    proc = subprocess.run([sys.executable, '-c', FILE_SIZE_LIMITED, '200000', 'make-sample-bags',
                           '--out', str(out), '--duration-s', '5'],
                          capture_output=True, text=True, timeout=120, env=env, check=False)
    refused(proc, 'cannot write the sample bag', 'eha_nominal')
    assert not out.exists()


INLINE_SIZE_LIMITED = """
import resource, signal, sys
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (int(sys.argv[1]), int(sys.argv[1])))
from pump_friction_ros.bags.replay import replay_bag
from pump_friction_ros.errors import PumpFrictionError
try:  # in this process, as a fleet's worker writes (InlineSink, no helper process)
    replay_bag(sys.argv[2], out_bag=sys.argv[3], storage=sys.argv[4], pipeline=False)
except PumpFrictionError as exc:
    print(exc)
    raise SystemExit(2)
"""


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='RLIMIT_FSIZE as on Linux')
@pytest.mark.parametrize(('flag', 'storage', 'limit'), [
    ('--csv', 'sqlite3', 100000), ('--plots', 'sqlite3', 20000),
    ('--out', 'sqlite3', 100000), ('--out', 'mcap', 100000),
])
def test_a_replay_output_on_a_full_disk_names_its_flag_and_leaves_nothing(
        env, tmp_path, flag, storage, limit):
    """Before: 'OSError: [Errno 28] No space left on device' or '... the output bag: ...'."""
    bag = REPO / 'bags' / 'eha_valve_plate_wear'  # mcap: reading a sqlite3 bag writes too
    warm = cli(env, 'replay', bag, '--plots', tmp_path / 'warm', '--quiet', timeout=120)
    assert warm.returncode == 0, warm.stderr  # table and font caches first: only the output
    out = tmp_path / 'sub' / 'output'
    proc = subprocess.run([sys.executable, '-c', FILE_SIZE_LIMITED, str(limit), 'replay',
                           str(bag), flag, str(out), '--storage', storage, '--quiet'],
                          capture_output=True, text=True, timeout=120, env=env, check=False)
    refused(proc, f'cannot write the output {flag} {out}: ')
    assert 'Errno' not in proc.stderr and not (tmp_path / 'sub').exists()
    if flag == '--out':
        proc = subprocess.run([sys.executable, '-c', INLINE_SIZE_LIMITED, str(limit), str(bag),
                               str(out), storage],
                              capture_output=True, text=True, timeout=120, env=env, check=False)
        assert proc.returncode == 2, proc.stderr
        assert proc.stdout.startswith(f'cannot write the output --out {out}: ')
        assert 'Errno' not in proc.stdout and not (tmp_path / 'sub').exists()


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='RLIMIT_FSIZE as on Linux')
@pytest.mark.parametrize(('command', 'name'), [('build-table', 't.npz'), ('plot', 'figures')])
def test_a_model_output_on_a_full_disk_names_its_flag_and_leaves_nothing(
        env, tmp_path, command, name):
    warm = cli(env, 'plot', '--out', tmp_path / 'warm', timeout=120)  # the font cache first
    assert warm.returncode == 0, warm.stderr
    out = tmp_path / 'sub' / name
    proc = subprocess.run([sys.executable, '-c', FILE_SIZE_LIMITED, '20000', command, '--out',
                           str(out)], capture_output=True, text=True, timeout=120, env=env,
                          check=False)
    refused(proc, f'cannot write the output --out {out}: ')
    assert 'Errno' not in proc.stderr and not (tmp_path / 'sub').exists()


@pytest.mark.skipif(not Path('/proc/version').is_file(), reason='needs /proc (Linux)')
def test_reset_baseline_of_a_file_that_cannot_be_moved_says_so_not_moved(env):
    """/proc/version is a file os.replace cannot move (ENOENT): before, 'moved to None', rc 0."""
    refused(cli(env, 'reset-baseline', '/proc/version', '--force'), 'cannot move', 'aside')


@pytest.mark.skipif(not Path('/proc/self/maps').exists(), reason='/proc maps (Linux)')
@pytest.mark.parametrize('delay_s', [0.0, 0.02, 0.1])
def test_a_ctrl_c_while_the_command_imports_its_modules_is_one_line_and_130(env, delay_s):
    """
    The console script's module (``app.entry``): numpy, scipy... imported after its try.

    Once the imports are done (0.1 s, a warm cache) the command itself may be stopped: it
    says so and exits 130, or (CPython, an interrupt it flagged unhandled in code an
    extension ran) dies of SIGINT after the line, which a shell reads as 130 all the same.
    """
    import signal
    import time

    def as_in_a_terminal():
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    proc = subprocess.Popen([sys.executable, '-m', 'pump_friction_ros.app.entry', 'replay',
                             str(REPO / 'bags' / 'eha_nominal'), '--quiet'],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True, preexec_fn=as_in_a_terminal)
    try:
        end = time.monotonic() + 60  # numpy's core library maps once the imports are under way
        while '_multiarray_umath' not in Path(f'/proc/{proc.pid}/maps').read_text():
            assert proc.poll() is None and time.monotonic() < end, proc.communicate()
            time.sleep(0.0005)
        time.sleep(delay_s)
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode in (130, -signal.SIGINT)
    assert (err, out) == ('pump_friction: interrupted\n', '')


def test_a_sqlite_bag_with_a_timestamp_of_text_is_one_line_naming_the_bag(env, tmp_path):
    import sqlite3

    bag = write_bag(tmp_path / 'bag', n=200)
    (db,) = bag.glob('*.db3')
    with sqlite3.connect(db) as conn:
        conn.execute("UPDATE messages SET timestamp = 'abc' WHERE id = 7")
    refused(cli(env, 'replay', bag, '--quiet'), f'bag {bag}: unreadable (ValueError:')


# -- inputs that are not regular files ----------------------------------------------------


def _not_a_file(kind, tmp_path):
    """Return a path that is a named pipe, /dev/zero, a directory or a 65 MiB sparse file."""
    if kind == 'dev_zero':
        return Path('/dev/zero')
    path = tmp_path / f'{kind}.yaml'
    if kind == 'fifo':
        os.mkfifo(path)  # nothing ever writes to it: opening it for reading would block
    elif kind == 'directory':
        path.mkdir()
    else:
        with open(path, 'wb') as handle:
            handle.truncate(65 << 20)
    return path


INPUT_FILES = {  # the command line that reads PATH as the input named
    'pump': ('torque', '--speed-rpm', 1000, '--pressure-bar', 100, '--pump', 'PATH'),
    'table': ('torque', '--speed-rpm', 1000, '--pressure-bar', 100, '--table', 'PATH'),
    'params': ('replay', REPO / 'bags' / 'eha_nominal', '--params', 'PATH'),
    'baseline': ('replay', REPO / 'bags' / 'eha_nominal', '--baseline', 'PATH'),
    'bench_csv': ('calibrate', 'PATH', '--pump', PAPER_PUMP, '--out', 'OUT'),
}


@pytest.mark.parametrize('kind', ['fifo', 'dev_zero', 'directory', 'oversized'])
@pytest.mark.parametrize('what', sorted(INPUT_FILES))
def test_an_input_that_is_not_a_regular_file_is_one_line_never_a_hang(env, tmp_path, what,
                                                                      kind):
    if kind in ('directory', 'oversized') and what in ('table', 'bench_csv'):
        pytest.skip('a directory of CSVs is an input; a table is a zip read by its index')
    path = _not_a_file(kind, tmp_path)
    argv = [path if arg == 'PATH' else tmp_path / 'out.yaml' if arg == 'OUT' else arg
            for arg in INPUT_FILES[what]]
    line = refused(cli(env, *argv, timeout=60), str(path))
    assert any(words in line for words in (
        'not a regular file', 'is not a file', 'larger than 64 MiB')), line
    assert not (tmp_path / 'out.yaml').exists()
