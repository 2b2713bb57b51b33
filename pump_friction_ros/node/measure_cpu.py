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
CPU cost of the ``torque_estimator`` node next to a bare rclpy node, at 1 kHz input.

A benchmark, not a test: it prints figures and asserts nothing. Run it in a sourced ROS 2
Jazzy shell (``python3 -m pump_friction_ros.node.measure_cpu`` or ``ros2 run pump_friction_ros
measure_node_cpu``); docs/cpu_cost.md says how to read its output.

Each run starts three processes from this module: a publisher (``sensor_msgs/JointState``
at 1 kHz and ``sensor_msgs/FluidPressure`` at 500 Hz, header stamps from the system clock),
the bare reference node (the same two subscriptions and one ``std_msgs/Float64`` publisher,
rclpy's defaults, one Float64 per JointState) and the estimator node (the package's
parameters file). Once the publisher has matched both nodes, the CPU time (user + system,
every thread) of each node process is read from ``/proc/<pid>/stat`` before and after the
publisher's window; the nodes then stop on SIGINT and report what they received. The
figure to compare is CPU time per input message received, estimator over bare, in the same
run: both nodes share the machine, the publisher and the window.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field
import json
import math
import os
import queue
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from typing import Any

__all__ = ['NodeResult', 'RunResult', 'cpu_seconds', 'format_run', 'format_summary', 'main']

TAG = '@measure_cpu'
"""Prefix of the lines the role processes print on stdout for the orchestrator."""
NODES = ('bare', 'estimator')
TOPICS = ('joint_states', 'load_pressure')


def cpu_seconds(pid: int) -> float:
    """
    Return the CPU time a process has used so far, user + system, all its threads.

    Parameters
    ----------
    pid : int
        The process (Linux: read from ``/proc/<pid>/stat``).

    Returns
    -------
    float
        CPU time [s], at the kernel's clock-tick resolution (usually 10 ms).

    """
    with open(f'/proc/{pid}/stat') as handle:
        text = handle.read()
    fields = text[text.rindex(')') + 2:].split()  # the name may hold spaces and ')'
    utime, stime = int(fields[11]), int(fields[12])  # stat fields 14 and 15
    return (utime + stime) / os.sysconf('SC_CLK_TCK')


@dataclass
class NodeResult:
    """What one node process did during a window."""

    cpu_s: float
    received: dict[str, int]
    published: int

    def per_message_us(self) -> float:
        """CPU time per input message received [us]."""
        n = sum(self.received.values())
        return self.cpu_s / n * 1e6 if n else math.nan


@dataclass
class RunResult:
    """One window: what was published, and each node's result."""

    reliable: bool
    window_s: float
    sent: dict[str, int]
    late_ticks: int
    nodes: dict[str, NodeResult] = field(default_factory=dict)

    def ratio(self) -> float:
        """Estimator over bare, CPU time per input message received [-] (NaN if undefined)."""
        bare = self.nodes['bare'].per_message_us()
        return self.nodes['estimator'].per_message_us() / bare if bare > 0.0 else math.nan


def format_run(index: int, run: RunResult) -> str:
    """
    Return the table of one run.

    Parameters
    ----------
    index : int
        Run number (from 1).
    run : RunResult
        The run.

    Returns
    -------
    str
        One line per node: CPU time, messages received and lost, CPU per message.

    """
    qos = 'reliable' if run.reliable else 'best effort'
    lines = [f'run {index} ({qos} inputs, {run.window_s:.1f} s): sent joint_states '
             f'{run.sent["joint_states"]}, load_pressure {run.sent["load_pressure"]}'
             f'{f", {run.late_ticks} ticks late" if run.late_ticks else ""}',
             f'  {"node":<10} {"cpu [s]":>8} {"joint_states":>13} {"load_pressure":>14} '
             f'{"lost":>6} {"cpu/msg [us]":>13} {"published":>10}']
    for name in NODES:
        node = run.nodes[name]
        lost = sum(run.sent[t] - node.received.get(t, 0) for t in TOPICS)
        lines.append(f'  {name:<10} {node.cpu_s:>8.2f} {node.received.get("joint_states", 0):>13}'
                     f' {node.received.get("load_pressure", 0):>14} {lost:>6} '
                     f'{node.per_message_us():>13.1f} {node.published:>10}')
    lines.append('  (published: bare, Float64 messages; estimator, estimates published, 4-5 '
                 'Float64 each)')
    lines.append(f'  estimator / bare, CPU per input message: {run.ratio():.2f}')
    return '\n'.join(lines)


def format_summary(runs: list[RunResult]) -> str:
    """
    Return the ratio over all runs, per QoS.

    Parameters
    ----------
    runs : list of RunResult
        The runs.

    Returns
    -------
    str
        Median, lowest and highest ratio for each QoS measured.

    """
    lines = []
    for reliable in (False, True):
        ratios = [r.ratio() for r in runs if r.reliable == reliable]
        ratios = [x for x in ratios if not math.isnan(x)] or ratios
        if ratios:
            lines.append(f'{"reliable" if reliable else "best effort"}: estimator / bare = '
                         f'{statistics.median(ratios):.2f} (median of {len(ratios)}; '
                         f'{min(ratios):.2f} to {max(ratios):.2f})')
    return '\n'.join(lines)


# -- the orchestrator -------------------------------------------------------------------


class _Child:
    """A role process whose tagged stdout lines are read by a thread into a queue."""

    def __init__(self, role: str, args: argparse.Namespace, reliable: bool) -> None:
        cmd = [sys.executable, '-m', 'pump_friction_ros.node.measure_cpu', '--role', role,
               '--window-s', str(args.window_s), '--rate-hz', str(args.rate_hz),
               '--start-timeout-s', str(args.start_timeout_s)]
        if reliable:
            cmd.append('--reliable')
        for item in args.estimator_param:
            cmd += ['--estimator-param', item]
        self.role = role
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True, bufsize=1)
        self._lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            if line.startswith(TAG):
                self._lines.put(line[len(TAG):].strip())
            else:
                sys.stderr.write(f'[{self.role}] {line}')
        self._lines.put(None)

    def expect(self, word: str, timeout_s: float) -> str:
        """Wait for the tagged line starting with ``word``; return the rest of it."""
        end = time.monotonic() + timeout_s
        while True:
            try:
                line = self._lines.get(timeout=max(end - time.monotonic(), 0.0))
            except queue.Empty:
                raise TimeoutError(f'{self.role}: no "{word}" within {timeout_s:.0f} s') \
                    from None
            if line is None:
                raise RuntimeError(f'{self.role} ended (exit code {self.proc.wait()}) before '
                                   f'"{word}"')
            if line.startswith(word):
                return line[len(word):].strip()

    def send(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line + '\n')
        self.proc.stdin.flush()

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


def _run_once(args: argparse.Namespace, reliable: bool) -> RunResult:
    children: dict[str, _Child] = {}
    try:
        for name in NODES:
            children[name] = _Child(name, args, reliable)
        for name in NODES:
            children[name].expect('ready', args.start_timeout_s)
        publisher = children['publisher'] = _Child('publisher', args, reliable)
        publisher.expect('matched', args.start_timeout_s)
        time.sleep(args.settle_s)
        before = {name: cpu_seconds(children[name].proc.pid) for name in NODES}
        publisher.send('go')
        sent = json.loads(publisher.expect('published', args.window_s + 60.0))
        time.sleep(args.drain_s)  # let the nodes finish what is queued
        after = {name: cpu_seconds(children[name].proc.pid) for name in NODES}
        run = RunResult(reliable, args.window_s, sent['sent'], sent['late_ticks'])
        for name in NODES:
            children[name].proc.send_signal(signal.SIGINT)
            report = json.loads(children[name].expect('received', 30.0))
            run.nodes[name] = NodeResult(after[name] - before[name], report['received'],
                                         report['published'])
        return run
    finally:
        for child in children.values():
            child.stop()


def _orchestrate(args: argparse.Namespace) -> int:
    modes = {'best_effort': [False], 'reliable': [True], 'both': [False, True]}[args.qos]
    print(f'measure_cpu: {args.runs} run(s) per QoS, {args.window_s:.0f} s windows, '
          f'JointState {args.rate_hz:.0f} Hz + FluidPressure {args.rate_hz / 2:.0f} Hz; '
          f'RMW_IMPLEMENTATION={os.environ.get("RMW_IMPLEMENTATION", "(default)")}, '
          f'ROS_DISTRO={os.environ.get("ROS_DISTRO", "?")}, {os.cpu_count()} CPUs, '
          f'Python {sys.version.split()[0]}', flush=True)
    runs = []
    for reliable in modes:
        for _ in range(args.runs):
            runs.append(_run_once(args, reliable))
            print(format_run(len(runs), runs[-1]), flush=True)
    print(format_summary(runs))
    return 0


# -- the role processes (need rclpy) ----------------------------------------------------


def _tell(word: str, payload: Any = None) -> None:
    text = f'{TAG} {word}' + ('' if payload is None else ' ' + json.dumps(payload))
    print(text, flush=True)


def _input_qos(reliable: bool) -> Any:
    from .torque_estimator import input_qos  # the estimator's own choice, for every role

    return input_qos(reliable)


def _spin_and_report(node: Any, report: Any) -> None:
    """Spin with rclpy's global executor (as ``main`` does) until SIGINT; print ``report()``."""
    import rclpy
    from rclpy.executors import ExternalShutdownException

    _tell('ready')
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        _tell('received', report())
        node.destroy_node()
        rclpy.try_shutdown()


def _role_bare(args: argparse.Namespace) -> None:
    """Run the reference: two subscriptions and one Float64 publisher, rclpy's defaults."""
    import rclpy
    from rclpy.node import Node
    from sensor_msgs.msg import FluidPressure, JointState
    from std_msgs.msg import Float64

    rclpy.init()
    node = Node('bare_reference')
    qos = _input_qos(args.reliable)
    received = dict.fromkeys(TOPICS, 0)
    published = [0]
    pub = node.create_publisher(Float64, '~/speed', 10)

    def on_joint(msg: JointState) -> None:
        received['joint_states'] += 1
        pub.publish(Float64(data=msg.velocity[0] if len(msg.velocity) else 0.0))
        published[0] += 1

    def on_pressure(msg: FluidPressure) -> None:
        received['load_pressure'] += 1

    node.create_subscription(JointState, 'joint_states', on_joint, qos)
    node.create_subscription(FluidPressure, 'load_pressure', on_pressure, qos)
    _spin_and_report(node, lambda: {'received': received, 'published': published[0]})


def _role_estimator(args: argparse.Namespace) -> None:
    """Run the node as the package runs it, from its parameters file."""
    import rclpy

    from .torque_estimator import TorqueEstimatorNode
    from ..core.inputs import InputKind
    from ..physics.pump_parameters import config_dir

    # its own baseline file: the benchmark's synthetic running must not touch a real one
    state = tempfile.TemporaryDirectory(prefix='measure_cpu_')
    ros_args = ['--ros-args', '--params-file', str(config_dir() / 'torque_estimator.yaml'),
                '-p', f'reliable_inputs:={"true" if args.reliable else "false"}',
                '-p', f'baseline_file:={state.name}/baseline.yaml']
    for item in args.estimator_param:
        ros_args += ['-p', item]
    rclpy.init(args=ros_args)
    node = TorqueEstimatorNode()

    def report() -> dict[str, Any]:
        counts = node.core.counts
        return {'received': {'joint_states': node.received[InputKind.JOINT_STATE],
                             'load_pressure': node.received[InputKind.LOAD_PRESSURE]},
                'published': math.ceil(counts['estimates'] / node.config.output_decimation),
                'counts': counts}

    _spin_and_report(node, report)


def _role_publisher(args: argparse.Namespace) -> None:
    """Publish JointState at ``rate_hz`` and FluidPressure at half of it, for ``window_s``."""
    from builtin_interfaces.msg import Time
    import rclpy
    from rclpy.duration import Duration
    from sensor_msgs.msg import FluidPressure, JointState

    rclpy.init()
    node = rclpy.create_node('measure_cpu_publisher')
    qos = _input_qos(args.reliable)
    joint_pub = node.create_publisher(JointState, '/joint_states', qos)
    pressure_pub = node.create_publisher(FluidPressure, '/load_pressure', qos)
    end = time.monotonic() + args.start_timeout_s
    while (joint_pub.get_subscription_count() < len(NODES) or
           pressure_pub.get_subscription_count() < len(NODES)):
        if time.monotonic() > end:
            raise TimeoutError('the nodes were not matched')
        time.sleep(0.05)
    _tell('matched')
    if sys.stdin.readline().strip() != 'go':
        return
    joint = JointState(name=['pump_shaft'], position=[0.0], velocity=[300.0], effort=[9.0])
    pressure = FluidPressure(fluid_pressure=100e5, variance=0.0)
    period = 1.0 / args.rate_hz
    ticks = round(args.window_s * args.rate_hz)
    sent = dict.fromkeys(TOPICS, 0)
    late = 0
    start = time.monotonic()
    for k in range(ticks):
        delay = start + k * period - time.monotonic()
        if delay > 0.0:
            time.sleep(delay)
        elif delay < -period:
            late += 1
        sec, nanosec = divmod(time.time_ns(), 1_000_000_000)
        stamp = Time(sec=sec, nanosec=nanosec)
        t = k * period
        joint.header.stamp = stamp
        joint.velocity = [300.0 + 20.0 * math.sin(math.pi * t)]  # 0.5 Hz, +-20 rad/s
        joint.effort = [9.0 + 0.5 * math.sin(math.pi * t)]
        joint_pub.publish(joint)
        sent['joint_states'] += 1
        if k % 2 == 0:
            pressure.header.stamp = stamp
            pressure_pub.publish(pressure)
            sent['load_pressure'] += 1
    for pub in (joint_pub, pressure_pub):  # reliable: until every message is acknowledged
        pub.wait_for_all_acked(Duration(seconds=5.0))
    _tell('published', {'sent': sent, 'late_ticks': late})
    node.destroy_node()
    rclpy.try_shutdown()


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog='measure_node_cpu',
        description='CPU time per input message of torque_estimator next to a bare rclpy '
                    'node (1 kHz JointState + 500 Hz FluidPressure). Needs a sourced ROS 2 '
                    'Jazzy; prints figures, asserts nothing.')
    p.add_argument('--qos', choices=('best_effort', 'reliable', 'both'), default='both',
                   help='input QoS of the publisher and both nodes (default both)')
    p.add_argument('--runs', type=int, default=3, metavar='N',
                   help='runs per QoS, fresh processes each (default 3)')
    p.add_argument('--window-s', type=float, default=20.0, metavar='S',
                   help='publishing window [s] (default 20)')
    p.add_argument('--rate-hz', type=float, default=1000.0, metavar='HZ',
                   help='JointState rate [Hz]; FluidPressure at half (default 1000)')
    p.add_argument('--settle-s', type=float, default=2.0, metavar='S',
                   help='idle time after discovery, before the window [s] (default 2)')
    p.add_argument('--drain-s', type=float, default=0.5, metavar='S',
                   help='time after the window before the CPU is read [s] (default 0.5)')
    p.add_argument('--start-timeout-s', type=float, default=300.0, metavar='S',
                   help='time allowed for start-up and discovery [s] (default 300: the '
                   'first start may build the friction table)')
    p.add_argument('--estimator-param', action='append', default=[], metavar='NAME:=VALUE',
                   help='extra parameter of the estimator node (repeatable)')
    p.add_argument('--role', choices=('publisher', 'bare', 'estimator'), default=None,
                   help=argparse.SUPPRESS)
    p.add_argument('--reliable', action='store_true', help=argparse.SUPPRESS)
    return p


def main(argv: list[str] | None = None) -> int:
    """
    Run the benchmark (console script ``measure_node_cpu``), or one of its role processes.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0, or 1 without rclpy.

    """
    args = _parser().parse_args(argv)
    try:
        import rclpy  # noqa: F401  (the role processes use it; here: is it there?)
    except ImportError as exc:  # a shell without ROS 2 sourced
        print(f'measure_node_cpu: {exc}: the benchmark runs ROS 2 Jazzy nodes (source '
              '/opt/ros/jazzy/setup.bash)', file=sys.stderr)
        return 1
    roles = {'publisher': _role_publisher, 'bare': _role_bare, 'estimator': _role_estimator}
    if args.role is not None:
        roles[args.role](args)
        return 0
    return _orchestrate(args)


if __name__ == '__main__':
    sys.exit(main())
