"""Offline replay: identical to the node's core, outputs written atomically, bad bags refused."""

import csv
import math
import shutil
from pathlib import Path

import pytest

try:
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
except ImportError:  # a ROS shell without pip's rosbags
    pytestmark = pytest.mark.skip(reason='rosbags is not installed (pip install rosbags)')

from pump_friction_ros.bags import BagError
from pump_friction_ros.cli import main
from pump_friction_ros.config import EstimatorConfig, load_estimator_config
from pump_friction_ros.estimator import Estimate, TorqueEstimator
from pump_friction_ros.replay import (
    CSV_COLUMNS,
    ReplayJob,
    discover_bags,
    float64_cdr,
    replay_bag,
    run_jobs,
)
from pump_friction_ros.ros_messages import joint_sample, stamp_to_ns
from pump_friction_ros.samples import make_sample_bags, write_run
from pump_friction_ros.simulate import DutyCycle, simulate_duty_cycle
from pump_friction_ros.table import build_table

REPO = Path(__file__).resolve().parents[1]
CONFIG = load_estimator_config(REPO / 'config' / 'torque_estimator.yaml')


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


def core_for(table):
    return TorqueEstimator(CONFIG, table, 70e-6, 'hong_doh_2004')


def node_path_estimates(bag, table):
    """Compute what the live node's callbacks would: rosbags messages, node conversions."""
    core = core_for(table)
    out = []
    with AnyReader([Path(bag)]) as reader:
        for conn, log_ns, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            stamp = stamp_to_ns(msg.header.stamp) or log_ns
            if conn.topic == '/joint_states':
                sample = joint_sample(msg, CONFIG.joint_name)
                if sample is not None:
                    est = core.on_joint_state(stamp, *sample)
                    if est is not None:
                        out.append(est)
            elif conn.topic == '/load_pressure':
                core.on_pressure(stamp, msg.fluid_pressure)
    return out


def same(a: Estimate, b: Estimate) -> bool:
    return all((x == y) or (isinstance(x, float) and math.isnan(x) and math.isnan(y))
               for x, y in zip(a, b, strict=True))


@pytest.mark.parametrize('which', ['nominal', 'wear'])
def test_replay_equals_the_live_nodes_core_message_for_message(bags, table, which):
    summary = replay_bag(bags[which], CONFIG, keep_estimates=True, core=core_for(table))
    reference = node_path_estimates(bags[which], table)
    assert len(summary.estimates_list) == len(reference) == 12000
    assert all(same(a, b) for a, b in zip(summary.estimates_list, reference, strict=True))
    assert summary.decoded_one_by_one == 0  # the batch decoder handled every message


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
        'efficiency.png', 'residual.png', 'torque.png', 'valve_plate_scale.png']
    assert not list(tmp_path.glob('.*partial*'))


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
    with pytest.raises(BagError, match='output exists'):
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
    from pump_friction_ros.bags import parse_remaps
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


def test_shipped_sample_bags_replay_as_documented():
    nominal = replay_bag(REPO / 'bags' / 'eha_nominal', CONFIG)
    wear = replay_bag(REPO / 'bags' / 'eha_valve_plate_wear', CONFIG)
    assert nominal.storage == 'sqlite3' and wear.storage == 'mcap'
    assert nominal.duration_s >= 60 and wear.duration_s >= 60
    assert nominal.messages_read == {'/joint_states': 75000, '/load_pressure': 37500}
    assert not nominal.warn_intervals and not nominal.error_intervals
    assert wear.warn_intervals and wear.warn_intervals[0][0] > 25.0  # wear starts at 25 s
    assert wear.final_valve_plate_scale > 1.15
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
    assert 'fleet: 2 bags (0 failed)' in out and 'worst valve-plate scale' in out


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
