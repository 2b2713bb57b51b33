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

"""Offline replay: identical to the node's core, outputs written atomically, bad bags refused."""

import csv
import dataclasses
from functools import partial
import itertools
import math
from pathlib import Path
import shutil

import numpy as np
from pump_friction_ros.app.cli import main
from pump_friction_ros.bags import reader as bag_reader
from pump_friction_ros.bags.fleet import discover_bags, ReplayJob, run_jobs
from pump_friction_ros.bags.outputs import CSV_COLUMNS
from pump_friction_ros.bags.replay import replay_bag
from pump_friction_ros.bags.sinks import float64_cdr
from pump_friction_ros.core.estimator import Estimate, TorqueEstimator
from pump_friction_ros.core.estimator_setup import estimator_from_config
from pump_friction_ros.core.inputs import Defect, InputKind, inputs_for
from pump_friction_ros.core.node_parameters import (
    EstimatorConfig,
    load_estimator_config,
    PressureSource,
    SpeedSource,
    TorqueSource,
    ViscositySource,
)
from pump_friction_ros.errors import BagError, OutputError
from pump_friction_ros.messages.conversions import input_sample, stamp_to_ns
from pump_friction_ros.sim.duty_cycle import DutyCycle, simulate_duty_cycle
from pump_friction_ros.sim.sample_bags import make_sample_bags, WEAR_SCALE, write_run
from pump_friction_ros.table.friction_table import build_table
import pytest

try:
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer
    from rosbags.serde import SerdeError
    from rosbags.typesys import get_typestore, Stores
except ImportError:  # a ROS shell without pip's rosbags
    pytestmark = pytest.mark.skip(reason='rosbags is not installed (pip install rosbags)')

REPO = Path(__file__).resolve().parents[1]
# the shipped defaults, then what the sample bags' simulated pump brings with them
SAMPLE_PARAMS = REPO / 'bags' / 'eha_params.yaml'
CONFIG = load_estimator_config([REPO / 'config' / 'torque_estimator.yaml', SAMPLE_PARAMS])


@pytest.fixture(scope='module')
def table(paper_params):
    return build_table(paper_params)


@pytest.fixture(scope='module')
def bags(tmp_path_factory, monkeypatch_module):
    out = tmp_path_factory.mktemp('bags')
    return dict(zip(('nominal', 'wear'), make_sample_bags(out, seed=7, duration_s=12.0),
                    strict=True))


@pytest.fixture(scope='module')
def monkeypatch_module(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv('XDG_CACHE_HOME', str(tmp_path_factory.mktemp('cache')))
    yield mp
    mp.undo()


def core_for(table, config=CONFIG):
    return TorqueEstimator(config, table, 70e-6, 'hong_doh_2004')


def node_callbacks(bag, config, core):
    """
    Run a bag through the node's callback logic, without rclpy.

    What `node.TorqueEstimatorNode` does with each message of a subscribed topic: rosbags
    deserialises it (where rclpy would), `input_sample` converts it, a defect is counted,
    else the stamp rule picks the header stamp (its receive time, here the log time, when
    zero or headerless) and the core takes the sample. Nothing of the replay's reader or
    batch decoder is used. A message that does not deserialise is one rclpy would never
    deliver; a bag can hold it, and it is counted as undecodable.
    """
    ts = get_typestore(Stores.ROS2_JAZZY)
    specs = {'/' + spec.topic: spec for spec in inputs_for(config)}
    out = []
    with AnyReader([Path(bag)], default_typestore=ts) as reader:
        conns = [c for c in reader.connections if c.topic in specs]
        for conn, now, raw in reader.messages(connections=conns):
            spec = specs[conn.topic]
            try:
                msg = ts.deserialize_cdr(raw, conn.msgtype)
            except SerdeError:
                core.on_defect(Defect.UNDECODABLE)
                continue
            value, torque, defect = input_sample(spec, msg, config.joint_name)
            if defect:
                core.on_defect(defect)
                continue
            stamp = (stamp_to_ns(msg.header.stamp) or now) if spec.has_header else now
            est = core.on_input(spec.kind, stamp, value, torque, now)
            if est is not None:
                out.append(est)
    return out


def _flat(estimate):
    for x in estimate:
        yield from (x if isinstance(x, tuple) else (x,))


def same(a: Estimate, b: Estimate) -> bool:
    return all(x == y or (isinstance(x, float) and math.isnan(x) and math.isnan(y))
               for x, y in zip(_flat(a), _flat(b), strict=True))


@pytest.mark.parametrize('which', ['nominal', 'wear'])
def test_sample_bags_replay_like_the_node_callbacks_without_fallback_decoding(bags, table,
                                                                              which):
    core = core_for(table)
    summary = replay_bag(bags[which], CONFIG, keep_estimates=True, core=core)
    reference_core = core_for(table)
    reference = node_callbacks(bags[which], CONFIG, reference_core)
    assert len(summary.estimates_list) == len(reference) == 12000
    assert all(same(a, b) for a, b in zip(summary.estimates_list, reference, strict=True))
    assert summary.counts == core.counts == reference_core.counts
    # A performance guard, not a correctness one: the fallback gives the same samples
    # (test_cdr.py) about 15x slower, so a layout-parser change that sent every regular
    # message to it would pass every other test and make replays crawl.
    assert summary.decoded_one_by_one == 0


SOURCE_COMBOS = list(itertools.product(SpeedSource, TorqueSource, PressureSource,
                                       ViscositySource))
_LATENCY_NS = {  # receive latency per topic: log times never tie, so bag order is defined
    InputKind.JOINT_STATE: 150_001, InputKind.SHAFT_SPEED: 150_003,
    InputKind.MOTOR_TORQUE: 150_007, InputKind.LOAD_PRESSURE: 90_011,
    InputKind.PRESSURE_A: 90_013, InputKind.PRESSURE_B: 90_017,
    InputKind.OIL_TEMPERATURE: 50_019}
_START_NS = 1_700_000_000 * 1_000_000_000


def _header(t, ns, frame):
    return t['std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](
        sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id=frame)


def _irregular_joint_state(k, t, joint, ns, speed, torque):
    """Make JointState number ``k``: mostly regular, with the defects the node must count."""
    one = partial(np.array, dtype=np.float64)
    names, pos, vel, eff, frame = [joint], one([]), one([speed]), one([torque]), ''
    if 100 <= k < 105:
        eff = one([math.nan])  # NaN effort: rejected_non_finite (torque from JointState)
    elif k == 200:
        names = ['wheel']  # rejected_missing_joint
    elif k == 300:
        vel = eff = one([])  # empty arrays: rejected_malformed
    elif k == 400:
        names, vel = ['wheel', joint], one([1.0, speed])  # effort of 1 for 2 names: malformed
    elif k == 500:
        ns = 0  # zero header stamp: the receive (log) time is used
    elif k == 600:
        ns -= 30_000_000  # out-of-order stamp
    elif k == 650:
        ns -= 1_000_000  # the previous sample's stamp: duplicate
    elif 700 <= k < 705:
        names, pos = [joint, 'wheel'], one([0.0, 0.0])  # reordered joints, position filled
        vel, eff = one([speed, 3.0]), one([torque, -1.0])
    elif 800 <= k < 810:
        frame = 'pump_frame'  # frame_id changes mid-stream
    elif k == 900:
        eff = one([])  # speed only
    elif k == 901:
        vel = one([])  # torque only
    elif k == 1000:
        ns += 5_000_000_000  # far ahead of the receive time: rejected_future_stamp
    return t['sensor_msgs/msg/JointState'](header=_header(t, ns, frame), name=names,
                                           position=pos, velocity=vel, effort=eff)


def write_source_bag(path, run, config, storage):
    """
    Write the topics ``inputs_for(config)`` lists, from a simulated run, with defects.

    JointState, FluidPressure and Temperature carry the sample time in their header; the
    Float64 topics carry speed and torque with their log (receive) time as the only stamp.
    Each topic also holds a big-endian message and a truncated (undecodable) one.
    """
    ts = get_typestore(Stores.ROS2_JAZZY)
    t = ts.types
    joint_ns = (_START_NS + np.round(run.t_s * 1e9).astype(np.int64)).tolist()
    press_ns = (_START_NS + np.round(run.pressure_t_s * 1e9).astype(np.int64)).tolist()
    messages = []  # (log time, kind, raw)

    def add(spec, k, sample_ns, msg, big_endian_at, truncate_at=-1):
        raw = bytes(ts.serialize_cdr(msg, spec.msgtype, little_endian=k != big_endian_at))
        if k == truncate_at:
            raw = raw[:len(raw) - 5]
        messages.append((sample_ns + _LATENCY_NS[spec.kind], spec.kind, raw))

    for spec in inputs_for(config):
        kind = spec.kind
        if kind == InputKind.JOINT_STATE:
            for k, ns in enumerate(joint_ns):
                add(spec, k, ns, _irregular_joint_state(k, t, config.joint_name, ns,
                                                        run.speed_rad_s[k], run.torque_nm[k]),
                    big_endian_at=1050, truncate_at=1100)
        elif kind in (InputKind.SHAFT_SPEED, InputKind.MOTOR_TORQUE):
            values = (run.speed_rad_s if kind == InputKind.SHAFT_SPEED
                      else run.torque_nm).copy()
            values[150:153] = math.nan
            values[350] = 2.0e4  # beyond any plausible speed or torque: out of range
            for k, ns in enumerate(joint_ns):
                add(spec, k, ns, t[spec.msgtype](data=float(values[k])), big_endian_at=550,
                    truncate_at=450)
        elif kind == InputKind.OIL_TEMPERATURE:
            for k, ns in enumerate(range(joint_ns[0], joint_ns[-1], 50_000_000)):
                celsius = 300.0 if k == 7 else math.nan if k == 9 else 45.0 + 0.2 * k
                msg = t[spec.msgtype](header=_header(t, 0 if k == 11 else ns, 'oil'),
                                      temperature=celsius, variance=0.0)
                add(spec, k, ns, msg, big_endian_at=13)
        else:
            dp = run.pressure_diff_pa
            if kind == InputKind.LOAD_PRESSURE:
                values = dp.copy()
            else:  # port pressures, a - b = dp
                values = 1.0e5 + np.maximum((1.0 if kind == InputKind.PRESSURE_A else -1.0)
                                            * dp, 0.0)
            values[120] = math.nan
            for k, ns in enumerate(press_ns):
                if 600 <= k < 650:
                    continue  # 100 ms without pressure: stale_skips
                stamp = 0 if k == 250 else ns - 40_000_000 if k == 260 else ns
                msg = t[spec.msgtype](header=_header(t, stamp, 'pump'),
                                      fluid_pressure=float(values[k]), variance=0.0)
                add(spec, k, ns, msg, big_endian_at=300, truncate_at=310)
    messages.sort(key=lambda m: m[0])
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        conns = {spec.kind: writer.add_connection('/' + spec.topic, spec.msgtype, typestore=ts)
                 for spec in inputs_for(config)}
        for log_ns, kind, raw in messages:
            writer.write(conns[kind], log_ns, raw)
    return path


@pytest.fixture(scope='module')
def short_run(table):
    return simulate_duty_cycle(table, DutyCycle(duration_s=3.0), seed=11)


@pytest.mark.parametrize(('speed', 'torque', 'pressure', 'viscosity'), SOURCE_COMBOS,
                         ids=['-'.join(c.value for c in combo) for combo in SOURCE_COMBOS])
def test_replay_equals_the_node_callbacks_for_every_source_combination(
        tmp_path, table, short_run, monkeypatch, speed, torque, pressure, viscosity):
    config = dataclasses.replace(CONFIG, speed_source=speed, torque_source=torque,
                                 pressure_source=pressure, viscosity_source=viscosity)
    storage = ('sqlite3', 'mcap')[SOURCE_COMBOS.index((speed, torque, pressure, viscosity)) % 2]
    bag = write_source_bag(tmp_path / 'bag', short_run, config, storage)
    monkeypatch.setattr(bag_reader, '_CHUNK_MESSAGES', 997)  # layouts split across chunks
    core = core_for(table, config)
    summary = replay_bag(bag, config, keep_estimates=True, core=core)
    reference_core = core_for(table, config)
    reference = node_callbacks(bag, config, reference_core)

    assert summary.storage == storage
    assert len(summary.estimates_list) == len(reference) > 1000
    assert all(same(a, b) for a, b in zip(summary.estimates_list, reference, strict=True))
    assert core.counts == reference_core.counts == summary.counts
    counts = core.counts  # the bag holds every defect it was written with
    for name in ('rejected_non_finite', 'rejected_out_of_order', 'rejected_undecodable',
                 'stale_skips', 'residuals', 'monitor_samples'):
        assert counts[name], name
    joint_used = SpeedSource.JOINT_STATE in (speed, torque)
    for name in ('rejected_missing_joint', 'rejected_malformed', 'rejected_future_stamp',
                 'rejected_duplicate'):
        assert bool(counts[name]) == joint_used, name
    assert bool(counts['rejected_out_of_range']) == (
        SpeedSource.FLOAT64 in (speed, torque) or viscosity == ViscositySource.TEMPERATURE)


def test_output_bag_holds_the_nodes_topics_at_publication_times(tmp_path, bags, table):
    out = tmp_path / 'out'
    summary = replay_bag(bags['wear'], CONFIG, out_bag=out, keep_estimates=True,
                         core=core_for(table))
    assert list(out.glob('*.mcap'))  # same storage as the input
    published = [e for e in summary.estimates_list if e.publish]
    ts = get_typestore(Stores.ROS2_JAZZY)
    with Reader(out) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types['/torque_estimator/expected_torque'] == 'std_msgs/msg/Float64'
        assert types['/diagnostics'] == 'diagnostic_msgs/msg/DiagnosticArray'
        got = {}
        for conn, log_ns, raw in reader.messages():
            got.setdefault(conn.topic, []).append((log_ns, raw))
    expected = got['/torque_estimator/expected_torque']
    assert [ts.deserialize_cdr(raw, 'std_msgs/msg/Float64').data for _, raw in expected] == \
        [e.expected_nm for e in published]
    assert [log for log, _ in expected] == [e.stamp_ns for e in published]  # stamp = log time
    assert bytes(expected[0][1]) == float64_cdr(published[0].expected_nm)
    residuals = [e for e in published if not math.isnan(e.residual_nm)]
    assert len(got['/torque_estimator/residual']) == len(residuals)
    diag = got['/diagnostics']
    assert len(diag) == 11  # 12 s at 1 Hz, first tick one period after the first message
    level = ts.deserialize_cdr(diag[-1][1], 'diagnostic_msgs/msg/DiagnosticArray').status[0]
    assert level.name == 'torque_estimator: hong_doh_2004' and level.hardware_id == 'eha_pump'


def test_storage_can_be_chosen_and_csv_and_plots_are_written(tmp_path, bags, table):
    summary = replay_bag(bags['nominal'], CONFIG, out_bag=tmp_path / 'o', storage='mcap',
                         csv_path=tmp_path / 'e.csv', plots_dir=tmp_path / 'plots',
                         core=core_for(table))
    assert list((tmp_path / 'o').glob('*.mcap'))
    with open(tmp_path / 'e.csv', newline='') as handle:
        rows = list(csv.reader(handle))
    assert tuple(rows[0]) == CSV_COLUMNS
    assert len(rows) == summary.estimates + 1
    assert sorted(p.name for p in (tmp_path / 'plots').iterdir()) == [
        'efficiency.png', 'friction_scales.png', 'residual.png', 'torque.png']
    assert not list(tmp_path.glob('.*partial*'))


def _with_first_message_earlier(src, dst, earlier_ns):
    """Copy a bag, its first message logged ``earlier_ns`` before the rest (a gap in the log)."""
    from rosbags.rosbag2 import Writer

    ts = get_typestore(Stores.ROS2_JAZZY)
    with Reader(src) as reader, Writer(dst, version=9) as writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=ts)
                 for c in reader.connections}
        for i, (conn, log_ns, raw) in enumerate(reader.messages()):
            writer.write(conns[conn.id], log_ns - (earlier_ns if i == 0 else 0), raw)


def test_a_day_long_gap_in_the_log_writes_a_few_stale_ticks_not_one_per_second(
        tmp_path, bags, table):
    """A message logged a day early: the replay ends, the gap's ticks are three, it says so."""
    day_ns = 86_400 * 10**9
    gapped = tmp_path / 'gapped'
    _with_first_message_earlier(bags['wear'], gapped, day_ns)
    summary = replay_bag(gapped, CONFIG, out_bag=tmp_path / 'out', core=core_for(table))
    ts = get_typestore(Stores.ROS2_JAZZY)
    with Reader(tmp_path / 'out') as reader:
        diag = [(log_ns, ts.deserialize_cdr(raw, 'diagnostic_msgs/msg/DiagnosticArray'))
                for conn, log_ns, raw in reader.messages() if conn.topic == '/diagnostics']
    start = min(log_ns for log_ns, _ in diag) - 10**9  # the first tick is 1 s after the start
    # the rest begins at the first message's own time, a tick's: the gap's last is there
    in_gap = [(log_ns, msg) for log_ns, msg in diag if log_ns <= start + day_ns]
    # up to STALE (stale_timeout_s 0.5 s + 2 periods), then the last before the data
    assert [log_ns - start for log_ns, _ in in_gap] == [10**9, 2 * 10**9, day_ns]
    assert all(msg.status[0].message.startswith('stale') for _, msg in in_gap[1:])
    after = len(diag) - len(in_gap)
    assert 11 <= after <= 12  # the 12 s of data at 1 Hz, as without the gap
    assert summary.diagnostics_gaps == [86_400 - 3]  # 86,400 ticks in the gap, 3 written
    assert 'gaps in the log: 1, in which 86397 ticks' in summary.formatted()


def test_a_gap_after_stamps_that_lead_the_log_still_writes_the_status_turning_stale(
        tmp_path, bags, table):
    """Header stamps 0.9 s ahead of the log (within max_stamp_lead_s), 10 Hz status, 60 s gap."""
    ts = get_typestore(Stores.ROS2_JAZZY)
    src, led = bags['wear'], tmp_path / 'led'
    with Reader(src) as reader, Writer(led, version=9) as writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=ts)
                 for c in reader.connections}
        first = reader.start_time
        for conn, log_ns, raw in reader.messages():
            later = 60 * 10**9 if log_ns - first > 6 * 10**9 else 0  # the gap after 6 s
            writer.write(conns[conn.id], log_ns - 900_000_000 + later, raw)
    config = dataclasses.replace(CONFIG, diagnostics_rate_hz=10.0)
    replay_bag(led, config, out_bag=tmp_path / 'out', core=core_for(table, config))
    with Reader(tmp_path / 'out') as reader:
        diag = [(log_ns, ts.deserialize_cdr(raw, 'diagnostic_msgs/msg/DiagnosticArray')
                 .status[0].message) for conn, log_ns, raw in reader.messages()
                if conn.topic == '/diagnostics']
    gap_start, gap_end = first + 6 * 10**9 - 900_000_000, first + 66 * 10**9 - 900_000_000
    in_gap = [message for log_ns, message in diag if gap_start < log_ns < gap_end]
    # as the node: OK while the last estimate (stamped 0.9 s ahead) is younger than
    # stale_timeout_s, then STALE, written before the gap's ticks are left out
    assert not in_gap[0].startswith('stale') and in_gap[-1].startswith('stale')
    assert sum(m.startswith('stale') for m in in_gap) >= 2


def test_an_mcap_zeroed_in_the_middle_says_how_many_messages_it_did_not_give(
        tmp_path, table, short_run):
    """The reader stops at the damage without an error: the metadata counts what is lost."""
    intact = write_run(short_run, tmp_path / 'intact', 'mcap', compress=False)
    damaged = tmp_path / 'damaged'
    shutil.copytree(intact, damaged)
    (file,) = damaged.glob('*.mcap')
    data = bytearray(file.read_bytes())
    third = len(data) // 3
    data[third:third + 5000] = bytes(5000)
    file.write_bytes(bytes(data))
    written = {'/joint_states': short_run.t_s.size, '/load_pressure': short_run.pressure_t_s.size}
    whole = replay_bag(intact, CONFIG, core=core_for(table))
    assert whole.messages_read == written and whole.unread == {}
    assert 'unread' not in whole.formatted() + whole.skipped()
    cut = replay_bag(damaged, CONFIG, core=core_for(table))
    assert set(cut.unread) == set(written)  # both topics lose their messages after the damage
    for topic, n in written.items():
        assert cut.messages_read[topic] + cut.unread[topic] == n
    assert sum(cut.messages_read.values()) < sum(written.values()) / 2
    assert f"unread: /joint_states {cut.unread['/joint_states']}" in cut.formatted()
    assert ', unread: ' in cut.skipped()


def _write_bag(path, topics, storage='sqlite3', count=5):
    ts = get_typestore(Stores.ROS2_JAZZY)
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        for topic, msgtype in topics:
            conn = writer.add_connection(topic, msgtype, typestore=ts)
            if msgtype == 'std_msgs/msg/Float64':
                for k in range(count):
                    writer.write(conn, 1000 + k, float64_cdr(float(k)))
    return path


def _corrupt_sqlite(tmp_path, bags):
    bag = tmp_path / 'corrupt'
    shutil.copytree(bags['nominal'], bag)
    (db,) = bag.glob('*.db3*')
    db.write_bytes(b'garbage' * 100)
    return bag


def _truncated_mcap(tmp_path, bags):
    bag = tmp_path / 'truncated'
    shutil.copytree(bags['wear'], bag)
    (mcap,) = bag.glob('*.mcap')
    data = mcap.read_bytes()
    mcap.write_bytes(data[: len(data) // 2])
    return bag


@pytest.mark.parametrize(('make', 'message'), [
    (lambda t, b: t / 'missing', 'bag not found'),
    (lambda t, b: (t / 'plain').mkdir() or t / 'plain', 'no metadata.yaml'),
    (lambda t, b: (t / 'x.txt').write_text('hi') and t / 'x.txt', 'not a rosbag2 bag'),
    (_corrupt_sqlite, 'cannot read bag'),
    (_truncated_mcap, 'cannot read bag'),
    (lambda t, b: _write_bag(t / 'other', [('/chatter', 'std_msgs/msg/Float64')]),
     'none of the input topics'),
    (lambda t, b: _write_bag(t / 'typed', [('/joint_states', 'std_msgs/msg/Float64'),
                                           ('/load_pressure', 'std_msgs/msg/Float64')]),
     'has type std_msgs/msg/Float64'),
    (lambda t, b: _write_bag(t / 'empty', [('/joint_states', 'sensor_msgs/msg/JointState')],
                             count=0), 'holds no messages'),
])
def test_unusable_bags_give_one_clear_error_and_leave_nothing(tmp_path, bags, make, message):
    bag = make(tmp_path, bags)
    out = tmp_path / 'result'
    with pytest.raises(BagError, match=message):
        replay_bag(bag, CONFIG, out_bag=out, csv_path=tmp_path / 'r.csv')
    assert not out.exists() and not (tmp_path / 'r.csv').exists()
    assert not list(tmp_path.glob('.*partial*'))


@pytest.mark.parametrize('cut', [4096, 40960])
def test_damage_found_at_open_or_while_reading_leaves_nothing(tmp_path, table, cut):
    run = simulate_duty_cycle(table, DutyCycle(duration_s=3.0), seed=1)
    bag = write_run(run, tmp_path / 'bag', 'sqlite3', compress=False)
    (db,) = bag.glob('*.db3')
    data = db.read_bytes()
    db.write_bytes(data[:-cut])  # lose the last pages
    out = tmp_path / 'out'
    with pytest.raises(BagError, match=r'corrupt|cannot read|malformed'):
        replay_bag(bag, CONFIG, out_bag=out, core=core_for(table))
    assert not out.exists() and not list(tmp_path.glob('.*partial*'))


def test_existing_output_is_refused_unless_forced(tmp_path, bags, table):
    out = tmp_path / 'out'
    replay_bag(bags['nominal'], CONFIG, out_bag=out, core=core_for(table))
    with pytest.raises(OutputError, match='output exists'):
        replay_bag(bags['nominal'], CONFIG, out_bag=out, core=core_for(table))
    summary = replay_bag(bags['nominal'], CONFIG, out_bag=out, force=True, core=core_for(table))
    assert summary.outputs['bag'] == str(out)


def test_topic_remap_reads_renamed_topics(tmp_path, table):
    run = simulate_duty_cycle(table, DutyCycle(duration_s=2.0), seed=4)
    bag = write_run(run, tmp_path / 'renamed', 'mcap', joint_name='pump_shaft')
    ts = get_typestore(Stores.ROS2_JAZZY)
    moved = tmp_path / 'moved'
    with Reader(bag) as reader, Writer(moved, version=9) as writer:
        conns = {}
        for conn, log_ns, raw in reader.messages():
            name = {'/joint_states': '/eha/js', '/load_pressure': '/eha/dp'}[conn.topic]
            if name not in conns:
                conns[name] = writer.add_connection(name, conn.msgtype, typestore=ts)
            writer.write(conns[name], log_ns, raw)
    with pytest.raises(BagError, match='--topic-remap'):
        replay_bag(moved, CONFIG)
    from pump_friction_ros.bags.reader import parse_remaps
    summary = replay_bag(moved, CONFIG, core=core_for(table),
                         remaps=parse_remaps(['joint_states:=/eha/js', 'load_pressure:=/eha/dp']))
    assert summary.estimates == 2000


def test_sample_bags_are_reproducible_from_their_seed(tmp_path, monkeypatch_module):
    a = make_sample_bags(tmp_path / 'a', seed=3, duration_s=2.0)
    b = make_sample_bags(tmp_path / 'b', seed=3, duration_s=2.0)
    c = make_sample_bags(tmp_path / 'c', seed=4, duration_s=2.0)

    def payloads(bag):
        with Reader(bag) as reader:
            return [bytes(raw) for _, _, raw in reader.messages()]

    assert payloads(a[0]) == payloads(b[0])
    assert payloads(a[1]) == payloads(b[1])
    assert payloads(a[0]) != payloads(c[0])
    with pytest.raises(BagError, match='output exists'):
        make_sample_bags(tmp_path / 'a', seed=3, duration_s=2.0)


def test_sample_bags_are_written_all_or_none(tmp_path, monkeypatch):
    from pump_friction_ros.errors import OutputError
    from pump_friction_ros.sim import sample_bags

    real, calls = sample_bags.simulate_duty_cycle, []

    def fail_on_the_second_bag(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt  # Ctrl-C while the wear bag is simulated
        return real(*args, **kwargs)

    monkeypatch.setattr(sample_bags, 'simulate_duty_cycle', fail_on_the_second_bag)
    out = tmp_path / 'bags'
    with pytest.raises(KeyboardInterrupt):
        make_sample_bags(out, seed=3, duration_s=1.0)
    assert len(calls) == 2 and not out.exists()  # not the first bag alone, nor its folder
    a_file = tmp_path / 'a_file'
    a_file.write_text('mine\n')
    with pytest.raises(OutputError, match='a_file is not a folder'):
        make_sample_bags(a_file / 'bags', seed=3, duration_s=1.0)
    assert len(calls) == 2  # refused before anything was simulated


def test_shipped_sample_bags_replay_as_documented():
    """The figures for the sample bags, parsed from their page, docs/replay.md."""
    import re
    page = (REPO / 'docs' / 'replay.md').read_text()
    figures = re.search(r'the wear bag goes WARN at\s+([\d.]+) s and ERROR at ([\d.]+) s, '
                        r'and ends\s+with the valve-plate scale at ([\d.]+) \+- ([\d.]+) '
                        r'\(95 %;\s+the simulated truth is ([\d.]+)\)', page)
    warn_s, error_s, final, interval, truth = map(float, figures.groups())
    learnt = estimator_from_config(CONFIG)  # commissioning on the nominal bag
    nominal = replay_bag(REPO / 'bags' / 'eha_nominal', CONFIG, core=learnt)
    core = estimator_from_config(CONFIG)
    core.monitor.load_state_dict(learnt.monitor.state_dict())
    wear = replay_bag(REPO / 'bags' / 'eha_valve_plate_wear', CONFIG, core=core)
    assert nominal.storage == 'sqlite3' and wear.storage == 'mcap'
    assert nominal.duration_s >= 60 and wear.duration_s >= 60
    assert nominal.messages_read == {'/joint_states': 75000, '/load_pressure': 37500}
    assert not nominal.warn_intervals and not nominal.error_intervals  # "stays OK"
    assert not learnt.monitor.learning  # "teaches the healthy baseline"
    assert wear.warn_intervals[0][0] == pytest.approx(warn_s, abs=0.05)  # wear from 25 s
    assert wear.error_intervals[0][0] == pytest.approx(error_s, abs=0.05)
    assert wear.final_valve_plate_scale == pytest.approx(final, abs=5e-4)
    assert 1.96 * wear.final_valve_plate_scale_std == pytest.approx(interval, abs=5e-4)
    assert truth == 1.6 == WEAR_SCALE  # the wear the sample bag was made with
    assert abs(wear.final_valve_plate_scale - truth) < interval  # the interval holds the truth
    assert 'valve plate' in wear.attribution
    defaults = estimator_from_config(EstimatorConfig())
    replay_bag(REPO / 'bags' / 'eha_nominal', EstimatorConfig(), core=defaults)
    level = 1.0 + defaults.monitor.baseline.coefficients[0]  # docs: "at 0.52 of the model"
    assert level == pytest.approx(0.52, abs=0.005)
    for bag in ('eha_nominal', 'eha_valve_plate_wear'):
        size = sum(f.stat().st_size for f in (REPO / 'bags' / bag).iterdir())
        assert size < 5e6


def test_fleet_reports_a_failing_bag_and_finishes_the_others(tmp_path, bags):
    fleet = tmp_path / 'fleet'
    fleet.mkdir()
    for name, bag in bags.items():
        shutil.copytree(bag, fleet / name)
    broken = fleet / 'zz_broken'
    shutil.copytree(bags['nominal'], broken)
    next(broken.glob('*.db3*')).write_bytes(b'not a database')
    found = discover_bags([fleet])
    assert [p.name for p in found] == ['nominal', 'wear', 'zz_broken']
    jobs = [ReplayJob(bag=str(b), config=CONFIG) for b in found]
    summaries = run_jobs(jobs, workers=2)
    errors = [s for s in summaries if s.error]
    assert len(errors) == 1 and 'zz_broken' in errors[0].bag
    assert all(s.estimates == 12000 for s in summaries if not s.error)


def test_cli_fleet_prints_one_line_per_bag_and_a_table(tmp_path, bags, capsys):
    code = main(['replay', str(bags['nominal'].parent), '--workers', '2', '--quiet'])
    out = capsys.readouterr().out
    assert code == 0
    assert 'fleet: 2 bags (0 failed)' in out and 'highest valve-plate scale at the end' in out
    assert out.count(' estimates, ') == 2  # one line per bag


def test_cli_fleet_with_a_failing_bag_exits_2_with_one_error_line_naming_it(
        tmp_path, bags, capsys):
    fleet = tmp_path / 'fleet'
    shutil.copytree(bags['nominal'], fleet / 'good')
    shutil.copytree(bags['nominal'], fleet / 'broken')
    next((fleet / 'broken').glob('*.db3*')).write_bytes(b'not a database')
    code = main(['replay', str(fleet), '--workers', '2', '--quiet'])
    out, err = capsys.readouterr()
    assert code == 2 and 'fleet: 2 bags (1 failed)' in out
    assert err == 'pump_friction: error: 1 of 2 bags failed: broken (why: above)\n'


def test_cli_single_bag_errors_exit_2_with_one_line(tmp_path, capsys):
    assert main(['replay', str(tmp_path / 'nothing')]) == 2
    err = capsys.readouterr().err
    assert err.startswith('pump_friction: error: bag not found') and err.count('\n') == 1


def test_dask_cluster_runs_the_same_per_bag_function(bags, table):
    distributed = pytest.importorskip('dask.distributed', reason='dask[distributed] missing')
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        jobs = [ReplayJob(bag=str(b), config=CONFIG) for b in bags.values()]
        remote = run_jobs(jobs, dask_address=cluster.scheduler_address)
    local = run_jobs(jobs, workers=1)
    assert [s.error for s in remote] == ['', '']
    for r, loc in zip(remote, local, strict=True):
        assert r.estimates == loc.estimates
        assert r.final_valve_plate_scale == loc.final_valve_plate_scale
        assert r.warn_intervals == loc.warn_intervals


def test_every_input_message_is_read(bags):
    summary = replay_bag(bags['nominal'], CONFIG)
    with Reader(bags['nominal']) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    assert summary.messages_read == counts == {'/joint_states': 12000, '/load_pressure': 6000}


def test_node_defaults_replay_too(bags):
    assert replay_bag(bags['nominal'], EstimatorConfig()).estimates == 12000


def test_pipelined_and_inline_replays_write_identical_bags(tmp_path, bags, table):
    results = {}
    for pipeline in (True, False):
        out = tmp_path / f'out_{pipeline}'
        summary = replay_bag(bags['wear'], CONFIG, out_bag=out, keep_estimates=True,
                             core=core_for(table), pipeline=pipeline)
        with Reader(out) as reader:
            messages = [(c.topic, t, bytes(raw)) for c, t, raw in reader.messages()]
        results[pipeline] = (summary.estimates_list, summary.messages_read, messages)
    assert results[True][1] == results[False][1]
    assert results[True][2] == results[False][2]
    assert all(same(a, b) for a, b in zip(results[True][0], results[False][0], strict=True))
