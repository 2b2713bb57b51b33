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

"""Output bags as Jazzy's rosbag2 reads them: metadata v9, offered QoS, compression."""

import sqlite3

import pytest
import yaml

try:
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, Reader, Writer
    from rosbags.typesys import get_typestore, Stores
except ImportError:  # a ROS shell without pip's rosbags
    pytestmark = pytest.mark.skip(reason='rosbags is not installed (pip install rosbags)')

from pump_friction_ros.app.cli import main  # noqa: I100 (after try)
from pump_friction_ros.bags.reader import BagMeta, mcap_chunk_compression
from pump_friction_ros.bags.replay import replay_bag
from pump_friction_ros.bags.sinks import output_compression
from pump_friction_ros.core.estimator import TorqueEstimator
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.sim.duty_cycle import DutyCycle, simulate_duty_cycle
from pump_friction_ros.sim.sample_bags import write_run
from pump_friction_ros.table.friction_table import build_table

CONFIG = EstimatorConfig()

# What Jazzy's rosbag2 writes for a publisher made with rclpy's QoSProfile(history=KEEP_LAST,
# depth=10, reliability=RELIABLE, durability=VOLATILE), metadata version 9
# (rosbag2_storage/src/rosbag2_storage/qos.cpp, convert<rclcpp::QoS>::encode: policy names
# from rmw's qos_string_conversions.c, durations as {sec, nsec}, unspecified = 0 s).
NODE_QOS_V9 = {
    'history': 'keep_last', 'depth': 10, 'reliability': 'reliable', 'durability': 'volatile',
    'deadline': {'sec': 0, 'nsec': 0}, 'lifespan': {'sec': 0, 'nsec': 0},
    'liveliness': 'system_default', 'liveliness_lease_duration': {'sec': 0, 'nsec': 0},
    'avoid_ros_namespace_conventions': False,
}
OUTPUT_TOPICS = {
    '/torque_estimator/expected_torque': 'std_msgs/msg/Float64',
    '/torque_estimator/friction_torque': 'std_msgs/msg/Float64',
    '/torque_estimator/efficiency': 'std_msgs/msg/Float64',
    '/torque_estimator/residual': 'std_msgs/msg/Float64',
    '/torque_estimator/valve_plate_friction_scale': 'std_msgs/msg/Float64',
    '/diagnostics': 'diagnostic_msgs/msg/DiagnosticArray',
}


@pytest.fixture(scope='module')
def table(paper_params):
    return build_table(paper_params)


@pytest.fixture(scope='module')
def run(table):
    return simulate_duty_cycle(table, DutyCycle(duration_s=2.0), seed=11)


@pytest.fixture(scope='module')
def inputs(tmp_path_factory, run):
    """One 2 s input bag per storage and compression, as rosbag2 would write them."""
    out = tmp_path_factory.mktemp('inputs')
    bags = {}
    for storage in ('sqlite3', 'mcap'):
        bags[storage, 'zstd'] = write_run(run, out / f'{storage}_zstd', storage)
        bags[storage, 'none'] = write_run(run, out / f'{storage}_none', storage, compress=False)
    plain = bags['sqlite3', 'none']
    ts = get_typestore(Stores.ROS2_JAZZY)
    bags['sqlite3', 'message'] = out / 'sqlite3_message'
    writer = Writer(bags['sqlite3', 'message'], version=9)
    writer.set_compression(CompressionMode.MESSAGE, CompressionFormat.ZSTD)
    with Reader(plain) as reader, writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=ts)
                 for c in reader.connections}
        for conn, log_ns, raw in reader.messages():
            writer.write(conns[conn.id], log_ns, raw)
    return bags


def replay(bag, out, table, **kwargs):
    core = TorqueEstimator(CONFIG, table, 70e-6, 'hong_doh_2004')
    return replay_bag(bag, CONFIG, out_bag=out, core=core, **kwargs)


def metadata(bag):
    with open(bag / 'metadata.yaml') as handle:
        return yaml.safe_load(handle)['rosbag2_bagfile_information']


def chunk_compression(bag):
    (mcap,) = bag.glob('*.mcap')
    return mcap_chunk_compression(mcap)


def test_metadata_is_version_9_with_the_nodes_qos_for_every_topic(tmp_path, inputs, table):
    out = tmp_path / 'out'
    replay(inputs['mcap', 'zstd'], out, table)
    info = metadata(out)
    assert info['version'] == 9
    # every key Jazzy's BagMetadata decoder reads for version 9 (rosbag2_storage/yaml.hpp)
    assert isinstance(info['storage_identifier'], str)
    assert isinstance(info['duration']['nanoseconds'], int)
    assert isinstance(info['starting_time']['nanoseconds_since_epoch'], int)
    assert isinstance(info['message_count'], int)
    assert all(isinstance(p, str) for p in info['relative_file_paths'])
    assert isinstance(info['compression_format'], str)
    assert isinstance(info['compression_mode'], str)
    assert all({'path', 'starting_time', 'duration', 'message_count'} <= set(f)
               for f in info['files'])
    assert info['custom_data'] is None or isinstance(info['custom_data'], dict)
    assert isinstance(info['ros_distro'], str)
    topics = {t['topic_metadata']['name']: t['topic_metadata']
              for t in info['topics_with_message_count']}
    assert {name: t['type'] for name, t in topics.items()} == OUTPUT_TOPICS
    for topic in topics.values():
        # v9: a YAML sequence of maps (a v8-style string would fail Jazzy's decoder)
        assert topic['offered_qos_profiles'] == [NODE_QOS_V9]
        assert topic['serialization_format'] == 'cdr'
        assert topic['type_description_hash'].startswith('RIHS01_')


def test_the_storage_holds_the_same_qos(tmp_path, inputs, table):
    ts = get_typestore(Stores.ROS2_JAZZY)
    mcap_out, sqlite_out = tmp_path / 'mcap', tmp_path / 'sqlite3'
    replay(inputs['mcap', 'none'], mcap_out, table)
    replay(inputs['sqlite3', 'none'], sqlite_out, table)
    with Reader(mcap_out) as from_yaml, Reader(next(mcap_out.glob('*.mcap'))) as from_mcap:
        profiles = {c.topic: c.ext.offered_qos_profiles for c in from_yaml.connections}
        assert {c.topic: c.ext.offered_qos_profiles for c in from_mcap.connections} == profiles
        qos = profiles['/diagnostics'][0]
        assert (qos.history.name, qos.depth, qos.reliability.name, qos.durability.name) == (
            'KEEP_LAST', 10, 'RELIABLE', 'VOLATILE')
        assert [c.digest for c in from_yaml.connections] == [
            ts.hash_rihs01(c.msgtype) for c in from_yaml.connections]
    (db3,) = sqlite_out.glob('*.db3')
    with sqlite3.connect(db3) as db:
        rows = db.execute('SELECT name, offered_qos_profiles FROM topics').fetchall()
    assert {name: yaml.safe_load(text) for name, text in rows} == {
        name: [NODE_QOS_V9] for name in OUTPUT_TOPICS}


@pytest.mark.parametrize('storage, compression, files, chunks, fields', [
    ('mcap', 'zstd', '*.mcap', 'zstd', ('', '')),  # chunk compression is not in metadata
    ('mcap', 'none', '*.mcap', '', ('', '')),
    ('sqlite3', 'zstd', '*.db3.zstd', None, ('zstd', 'file')),
    ('sqlite3', 'none', '*.db3', None, ('', '')),
    ('sqlite3', 'message', '*.db3', None, ('zstd', 'message')),
])
def test_output_follows_the_inputs_compression(tmp_path, inputs, table, storage, compression,
                                               files, chunks, fields):
    out = tmp_path / 'out'
    summary = replay(inputs[storage, compression], out, table)
    assert len(list(out.glob(files))) == 1
    if chunks is not None:
        assert chunk_compression(out) == chunks
    info = metadata(out)
    assert (info['compression_format'], info['compression_mode'].lower()) == fields
    with Reader(out) as reader:  # rosbags reads it back, every message
        assert reader.message_count == sum(1 for _ in reader.messages()) > summary.published


@pytest.mark.parametrize('source, requested, storage, chunks, fields', [
    (('sqlite3', 'zstd'), 'none', None, None, ('', '')),
    (('mcap', 'zstd'), 'none', None, '', ('', '')),
    (('sqlite3', 'none'), 'zstd', None, None, ('zstd', 'file')),
    (('mcap', 'none'), 'zstd', None, 'zstd', ('', '')),
    (('sqlite3', 'zstd'), 'auto', 'mcap', 'zstd', ('', '')),
    (('mcap', 'zstd'), 'auto', 'sqlite3', None, ('zstd', 'file')),
])
def test_compression_can_be_chosen(tmp_path, inputs, table, source, requested, storage,
                                   chunks, fields):
    out = tmp_path / 'out'
    replay(inputs[source], out, table, compression=requested, storage=storage)
    if chunks is not None:
        assert chunk_compression(out) == chunks
    assert (metadata(out)['compression_format'], metadata(out)['compression_mode']) == fields
    with Reader(out) as reader:
        assert sum(1 for _ in reader.messages()) == reader.message_count > 0


def test_compression_rules():
    def meta(storage, mode, fmt='zstd'):
        return BagMeta(storage, 0, 1, 1, fmt if mode else '', mode)

    assert output_compression('auto', 'mcap', meta('mcap', 'storage', 'lz4')) == 'storage'
    assert output_compression('auto', 'mcap', meta('mcap', 'file')) == 'file'
    assert output_compression('auto', 'mcap', meta('sqlite3', 'message')) == 'storage'
    assert output_compression('auto', 'sqlite3', meta('sqlite3', 'message')) == 'message'
    assert output_compression('auto', 'sqlite3', meta('mcap', 'storage')) == 'file'
    assert output_compression('auto', 'sqlite3', meta('sqlite3', '')) == ''
    assert output_compression('zstd', 'sqlite3', meta('sqlite3', 'message')) == 'file'
    assert output_compression('none', 'mcap', meta('mcap', 'storage')) == ''
    with pytest.raises(ValueError, match='compression must be one of'):
        output_compression('lz4', 'mcap', meta('mcap', ''))


def test_input_chunk_compression_is_detected(inputs):
    assert chunk_compression(inputs['mcap', 'zstd']) == 'zstd'
    assert chunk_compression(inputs['mcap', 'none']) == ''
    assert mcap_chunk_compression(next(inputs['sqlite3', 'none'].glob('*.db3'))) == ''


def test_cli_compression_option(tmp_path, inputs, capsys, monkeypatch):
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path / 'cache'))
    out = tmp_path / 'out'
    code = main(['replay', str(inputs['mcap', 'zstd']), '--out', str(out), '--compression',
                 'none', '--quiet'])
    assert code == 0, capsys.readouterr().err
    assert chunk_compression(out) == ''
    capsys.readouterr()
    assert main(['replay', str(inputs['mcap', 'zstd']), '--compression', 'lz4']) == 2
    assert "invalid choice: 'lz4'" in capsys.readouterr().err
