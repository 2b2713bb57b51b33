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
The node process stops cleanly as ROS users stop it: Ctrl-C (twice: launch forwards one), SIGTERM.

Real rclpy in a child process; skipped with the reason where rclpy is missing.
"""

import os
from pathlib import Path
import signal
import subprocess
import sys
import time

from pump_friction_ros.table.friction_table import build_table
import pytest

pytest.importorskip('rclpy', reason='rclpy is not importable: install the Jazzy wheels '
                    '(tools/test.sh) or source ROS 2 Jazzy')

REPO = Path(__file__).resolve().parents[1]
PARAMS = REPO / 'config' / 'torque_estimator.yaml'
STARTED = b'pump hong_doh_2004'


@pytest.fixture(scope='module')
def table_file(tmp_path_factory, paper_params):
    return str(build_table(paper_params).save(tmp_path_factory.mktemp('t') / 'table.npz'))


def start_node(table_file, tmp_path):
    env = dict(os.environ, RCUTILS_LOGGING_BUFFERED_STREAM='0', PYTHONUNBUFFERED='1',
               ROS_LOG_DIR=str(tmp_path / 'log'))
    env['PYTHONPATH'] = os.pathsep.join([str(REPO), env.get('PYTHONPATH', '')])
    proc = subprocess.Popen(
        [sys.executable, '-m', 'pump_friction_ros.node', '--ros-args',
         '--params-file', str(PARAMS), '-p', f'table_file:={table_file}'],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    seen = b''
    end = time.monotonic() + 60.0
    while STARTED not in seen and time.monotonic() < end:
        line = proc.stderr.readline()
        if not line:
            break
        seen += line
    assert STARTED in seen, seen.decode(errors='replace')
    return proc


@pytest.mark.parametrize('signals, gap_s', [
    ((signal.SIGINT,), 0.0),
    ((signal.SIGINT, signal.SIGINT), 0.0),  # a terminal's Ctrl-C, then launch's own SIGINT
    ((signal.SIGINT, signal.SIGINT), 0.002),
    ((signal.SIGINT, signal.SIGINT), 0.02),
    ((signal.SIGINT, signal.SIGINT, signal.SIGINT), 0.005),
    ((signal.SIGTERM,), 0.0),
    ((signal.SIGTERM, signal.SIGTERM), 0.002),
    ((signal.SIGINT, signal.SIGTERM), 0.002),  # launch escalates to SIGTERM
], ids=lambda v: '-'.join(s.name for s in v) if isinstance(v, tuple) else f'{v * 1e3:g}ms')
def test_node_exits_0_with_one_line_on_signals(table_file, tmp_path, signals, gap_s):
    proc = start_node(table_file, tmp_path)
    for sig in signals:
        os.killpg(proc.pid, sig)  # to the whole process group, as a terminal sends it
        time.sleep(gap_s)
    try:
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    text = err.decode(errors='replace')
    assert proc.returncode == 0, text
    assert 'Traceback' not in text and 'KeyboardInterrupt' not in text, text
    stops = [line for line in text.splitlines() if 'stopping' in line]
    assert len(stops) == 1, text
    assert signals[0].name in stops[0]


def wait_until_mapped(pid, library, timeout_s=60.0):
    """Wait until a native library is mapped into a process (it has begun importing it)."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        try:
            if library in Path(f'/proc/{pid}/maps').read_text():
                return True
        except OSError:
            return False
        time.sleep(0.001)
    return False


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='/proc is Linux')
@pytest.mark.parametrize('delay_s', [0.0, 0.05, 0.2, 0.5])
def test_a_signal_during_start_up_stops_it_cleanly(table_file, tmp_path, delay_s):
    """SIGINT while the node imports rclpy and the messages, initialises, builds itself."""
    env = dict(os.environ, RCUTILS_LOGGING_BUFFERED_STREAM='0', PYTHONUNBUFFERED='1',
               ROS_LOG_DIR=str(tmp_path / 'log'))
    env['PYTHONPATH'] = os.pathsep.join([str(REPO), env.get('PYTHONPATH', '')])
    proc = subprocess.Popen(
        [sys.executable, '-m', 'pump_friction_ros.node', '--ros-args', '--params-file',
         str(PARAMS), '-p', f'table_file:={table_file}'],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    # numpy's core library maps only once the entry point has installed its handler and
    # begun the heavy imports (a signal before that reaches Python's own start-up)
    assert wait_until_mapped(proc.pid, '_multiarray_umath')
    time.sleep(delay_s)
    os.killpg(proc.pid, signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    text = err.decode(errors='replace')
    assert proc.returncode == 0, text
    assert 'Traceback' not in text and 'KeyboardInterrupt' not in text, text
    assert len([line for line in text.splitlines() if 'stopping on SIGINT' in line]) == 1, text


@pytest.mark.parametrize('override, named', [
    ('use_sim_time:=1', 'use_sim_time'),  # rclpy's own parameter: a bool given as an integer
    ('max_stamp_lead_s:=1', 'max_stamp_lead_s'),  # a double given as an integer
    ('output_decimation:=0', 'output_decimation'),  # out of its range
])
def test_a_refused_start_up_exits_1_with_one_line_naming_the_parameter(
        table_file, tmp_path, override, named):
    env = dict(os.environ, RCUTILS_LOGGING_BUFFERED_STREAM='0', PYTHONUNBUFFERED='1',
               ROS_LOG_DIR=str(tmp_path / 'log'))
    env['PYTHONPATH'] = os.pathsep.join([str(REPO), env.get('PYTHONPATH', '')])
    proc = subprocess.run(
        [sys.executable, '-m', 'pump_friction_ros.node', '--ros-args', '--params-file',
         str(PARAMS), '-p', f'table_file:={table_file}', '-p', override],
        env=env, capture_output=True, timeout=60)
    lines = proc.stderr.decode(errors='replace').splitlines()
    assert proc.returncode == 1, lines
    assert len(lines) == 1 and lines[0].startswith('torque_estimator: cannot start:'), lines
    assert named in lines[0]


@pytest.mark.parametrize('arguments', [
    ['--params-file', '{tmp}/missing.yaml'],
    ['--params-file', '{tmp}/broken.yaml'],  # YAML that does not parse
    ['-r', '__ns:=not.a.namespace'],
    ['--params-files', '{tmp}/missing.yaml'],  # a typo: rclpy's UnknownROSArgsError
])
def test_a_command_line_rcl_refuses_exits_1_with_our_line_and_no_traceback(tmp_path, arguments):
    """rclpy.init fails (rcl logs its own line first): one line of ours, no traceback."""
    (tmp_path / 'broken.yaml').write_text('torque_estimator: [\n')
    env = dict(os.environ, ROS_LOG_DIR=str(tmp_path / 'log'))
    env['PYTHONPATH'] = os.pathsep.join([str(REPO), env.get('PYTHONPATH', '')])
    proc = subprocess.run(
        [sys.executable, '-m', 'pump_friction_ros.node', '--ros-args',
         *[a.format(tmp=tmp_path) for a in arguments]],
        env=env, capture_output=True, timeout=60)
    text = proc.stderr.decode(errors='replace')
    ours = [line for line in text.splitlines() if line.startswith('torque_estimator:')]
    assert proc.returncode == 1, text
    assert 'Traceback' not in text and len(ours) == 1, text
    assert ours[0].startswith(('torque_estimator: cannot start: failed to initialize rcl',
                               'torque_estimator: cannot start: unknown --ros-args')), text


def test_a_malformed_parameter_request_is_dropped_and_the_node_goes_on(table_file, tmp_path):
    """
    A SetParameters request of an unknown value type: logged, dropped; the node serves on.

    Jazzy's parameter service converts the request outside its ``try``, so the ``ValueError``
    leaves ``spin_once``: under ``Executor.spin`` any peer could end the node with it.
    """
    from rcl_interfaces.msg import Parameter, ParameterValue
    from rcl_interfaces.srv import GetParameters, SetParameters
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    proc = start_node(table_file, tmp_path)
    rclpy.init()
    probe = rclpy.create_node('malformed_request_probe')
    ex = SingleThreadedExecutor()
    ex.add_node(probe)
    try:
        setter = probe.create_client(SetParameters, '/torque_estimator/set_parameters')
        getter = probe.create_client(GetParameters, '/torque_estimator/get_parameters')
        assert setter.wait_for_service(timeout_sec=30.0)
        assert getter.wait_for_service(timeout_sec=30.0)
        bad = SetParameters.Request(parameters=[
            Parameter(name='stale_timeout_s', value=ParameterValue(type=99))])
        for _ in range(2):  # twice: the node survives each and counts them
            setter.call_async(bad)
            ex.spin_once(timeout_sec=0.5)
        asked = getter.call_async(GetParameters.Request(names=['stale_timeout_s']))
        ex.spin_until_future_complete(asked, timeout_sec=30.0)
        assert asked.done() and proc.poll() is None
        assert asked.result().values[0].double_value > 0.0  # the value is unchanged
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
        ex.shutdown()
        probe.destroy_node()
        rclpy.try_shutdown()
    text = err.decode(errors='replace')
    assert proc.returncode == 0, text
    assert 'Traceback' not in text, text
    raised = [line for line in text.splitlines() if 'a callback raised ValueError' in line]
    assert len(raised) == 2 and '(2 such error(s) so far)' in raised[1], text
    assert len([line for line in text.splitlines() if 'stopping on SIGINT' in line]) == 1, text


WITHOUT_ROS = """
import sys
sys.modules['rclpy'] = None  # a shell where ROS 2 is not sourced: import rclpy fails
from pump_friction_ros.node.{module} import main
sys.exit(main({argv}))
"""


@pytest.mark.parametrize(('module', 'argv', 'words'), [
    ('__main__', '[]', 'torque_estimator: cannot start: '),
    ('measure_cpu', "['--runs', '1']", 'measure_node_cpu: '),
])
def test_without_ros_sourced_the_commands_say_so_in_one_line(tmp_path, module, argv, words):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO),
                                                       os.environ.get('PYTHONPATH', '')]))
    proc = subprocess.run([sys.executable, '-c', WITHOUT_ROS.format(module=module, argv=argv)],
                          env=env, capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    assert 'Traceback' not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(words), proc.stderr
    assert 'source /opt/ros/jazzy/setup.bash' in lines[0]
