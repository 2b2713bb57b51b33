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
Helper processes stop whatever signal handling their parent has (issue: colcon test hung).

In a pytest process where rclpy ran, SIGTERM has rclpy's handler and does not end a forked
child. Each test here runs the replay in a child process whose SIGTERM handler does nothing,
as rclpy's would, and bounds it with ``join(60)``: a hang fails the test instead of blocking
the suite.
"""

import collections
import fcntl
import multiprocessing
import os
from pathlib import Path
import signal
import sys
import termios
import time

import pytest

try:
    import rosbags  # noqa: F401
except ImportError:  # a ROS shell without pip's rosbags
    pytestmark = pytest.mark.skip(reason='rosbags is not installed (pip install rosbags)')

from pump_friction_ros.bags import fleet, reader, replay, sinks, sources  # noqa: I100
from pump_friction_ros.bags.fleet import ReplayJob, run_jobs
from pump_friction_ros.bags.replay import replay_bag
from pump_friction_ros.bags.sources import ProcessSource
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.errors import BagError, OutputError
from pump_friction_ros.sim.sample_bags import make_sample_bags

if not sys.platform.startswith('linux'):
    pytestmark = pytest.mark.skip(reason='pipe and signal details checked on Linux')

CONFIG = EstimatorConfig()
BOUND_S = 60.0


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    cache = tmp_path_factory.mktemp('cache')
    old = os.environ.get('XDG_CACHE_HOME')
    os.environ['XDG_CACHE_HOME'] = str(cache)  # the workers inherit it
    try:
        yield make_sample_bags(tmp_path_factory.mktemp('bags'), seed=2, duration_s=12.0)
    finally:
        if old is None:
            os.environ.pop('XDG_CACHE_HOME', None)
        else:
            os.environ['XDG_CACHE_HOME'] = old


def ignore_sigterm():
    """Install a SIGTERM handler that does nothing, as rclpy's does for a forked child."""
    signal.signal(signal.SIGTERM, lambda *_: None)


def wait_until_pipe_full(source, timeout_s=30.0):
    """
    Wait until the reader has filled its pipe: it is then blocked in ``send``.

    The kernel fills a pipe page by page, so a blocked writer leaves it within a page of its
    capacity; the level must also hold still for a while.
    """
    fd = source._conn.fileno()
    capacity = fcntl.fcntl(fd, fcntl.F_GETPIPE_SZ)
    end = time.monotonic() + timeout_s
    levels = collections.deque(maxlen=5)
    while time.monotonic() < end:
        levels.append(int.from_bytes(fcntl.ioctl(fd, termios.FIONREAD, b'\0\0\0\0'),
                                     sys.byteorder))
        if len(levels) == 5 and len(set(levels)) == 1 and levels[0] > capacity - 4096:
            return True
        time.sleep(0.05)
    return False


def record_stops(ended):
    """Make the replay's ``stop_process`` record each helper's exit code after it."""
    original = sources.stop_process

    def stop_and_record(proc, timeout_s=sources.JOIN_TIMEOUT_S):
        started = time.monotonic()
        original(proc, timeout_s)
        ended.append((proc.exitcode, round(time.monotonic() - started, 1)))

    sources.stop_process = sinks.stop_process = fleet.stop_process = stop_and_record


def run_bounded(target, *args):
    """Run ``target(*args, conn)`` in a child process; return what it sends, within BOUND_S."""
    ctx = multiprocessing.get_context()
    mine, theirs = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=target, args=(*args, theirs))  # not daemonic: may have helpers
    proc.start()
    theirs.close()
    got = mine.recv() if mine.poll(BOUND_S) else None
    proc.join(BOUND_S)
    if proc.is_alive():
        proc.kill()
        proc.join(5.0)
        pytest.fail(f'{target.__name__} did not end within {BOUND_S:.0f} s (a hang)')
    assert proc.exitcode == 0, f'{target.__name__} exited with {proc.exitcode}'
    assert got is not None, f'{target.__name__} sent nothing'
    return got


def refuse_output_while_the_reader_is_blocked(bag, out, conn):
    ignore_sigterm()
    ended = []
    record_stops(ended)
    blocked = []
    open_source = replay.open_source

    def open_and_wait(*args, **kwargs):
        source = open_source(*args, **kwargs)
        blocked.append(isinstance(source, ProcessSource) and wait_until_pipe_full(source))
        return source

    replay.open_source = open_and_wait
    try:
        replay_bag(bag, CONFIG, out_bag=out)
        error = ''
    except (BagError, OutputError) as exc:
        error = str(exc)
    conn.send((error, blocked, ended, [p.pid for p in multiprocessing.active_children()]))


def test_refused_output_with_the_reader_blocked_on_a_full_pipe_ends(tmp_path, bags):
    out = tmp_path / 'out'
    out.mkdir()  # exists: the replay refuses it after opening the bag
    error, blocked, ended, children = run_bounded(
        refuse_output_while_the_reader_is_blocked, str(bags[0]), str(out))
    assert 'output exists' in error
    assert blocked == [True]  # the reader was blocked in send() when the replay refused
    # it ended by itself when its pipe closed, within the first join's timeout: not by the
    # terminate or the kill after it (the whole replay's time, table building included,
    # says nothing of that on a loaded machine)
    assert [code for code, _ in ended] == [0]
    assert all(wait_s < sources.JOIN_TIMEOUT_S for _, wait_s in ended), ended
    assert children == []


def terminate_a_reader(bag, conn):
    ignore_sigterm()  # inherited by the reader unless it restores the default
    source = ProcessSource(bag, CONFIG, None)
    wait_until_pipe_full(source)
    source._proc.terminate()
    source._proc.join(10.0)
    code = source._proc.exitcode
    source.close()
    conn.send(code)


def test_a_helper_ends_on_sigterm_even_if_its_parent_ignores_it(bags):
    assert run_bounded(terminate_a_reader, str(bags[1])) == -signal.SIGTERM


def fail_mid_replay(bag, out, conn):
    ignore_sigterm()
    ended = []
    record_stops(ended)
    reader._CHUNK_MESSAGES = 1000  # many chunks: the reader is blocked a few ahead of the core
    calls = []

    class Exploding(replay.TorqueEstimator):

        def on_chunk(self, kinds, *args):
            calls.extend([1] * len(kinds))  # the replay feeds the core a chunk at a time
            if len(calls) >= 5000:  # the writer and the reader are both running then
                raise RuntimeError('core failed')
            return super().on_chunk(kinds, *args)

    core = replay.estimator_from_config(CONFIG)
    core.__class__ = Exploding
    try:
        replay_bag(bag, CONFIG, out_bag=out, core=core)
        error = ''
    except RuntimeError as exc:
        error = str(exc)
    leftovers = sorted(p.name for p in Path(out).parent.iterdir())
    conn.send((error, ended, leftovers, [p.pid for p in multiprocessing.active_children()]))


def test_a_replay_failing_mid_run_stops_both_helpers_by_closing_their_pipes(tmp_path, bags):
    error, ended, leftovers, children = run_bounded(fail_mid_replay, str(bags[1]),
                                                    str(tmp_path / 'out'))
    assert error == 'core failed'
    assert [code for code, _ in ended] == [0, 0]  # writer, then reader: each by itself
    assert leftovers == [] and children == []


class SlowCore(replay.TorqueEstimator):
    """A core that takes about 20 s for a 12 s bag: a replay that is surely still running."""

    def on_chunk(self, kinds, *args):
        time.sleep(0.001 * len(kinds))  # a millisecond per message
        return super().on_chunk(kinds, *args)


def interrupt_a_fleet(bags, out, conn):
    ignore_sigterm()  # the workers inherit it unless they set their own
    ended = []
    record_stops(ended)
    stop_and_record = fleet.stop_process

    def ctrl_c_after_the_first_bag(proc, *args):
        stop_and_record(proc, *args)
        if len(ended) == 1:
            raise KeyboardInterrupt  # as if Ctrl-C arrived now

    fleet.stop_process = ctrl_c_after_the_first_bag
    replay_one = fleet.replay_bag

    def slow_when_asked(bag, config, **kwargs):  # the workers are forked: they see it
        if 'slow' in kwargs['out_bag']:
            core = replay.estimator_from_config(config)
            core.__class__ = SlowCore
            kwargs['core'] = core
        return replay_one(bag, config, **kwargs)

    fleet.replay_bag = slow_when_asked
    jobs = [ReplayJob(bag=str(b), config=CONFIG, out_bag=str(Path(out) / name))
            for b, name in zip(bags + bags[:1], ('0_fast', '1_slow', '2_slow'), strict=True)]
    try:
        run_jobs(jobs, workers=2)
        interrupted = False
    except KeyboardInterrupt:
        interrupted = True
    leftovers = sorted(p.name for p in Path(out).iterdir()) if Path(out).exists() else []
    conn.send((interrupted, ended, leftovers, [p.pid for p in multiprocessing.active_children()]))


@pytest.mark.skipif(multiprocessing.get_start_method() != 'fork',
                    reason='the slow job is patched into forked workers')
def test_an_interrupted_fleet_stops_its_workers_and_leaves_no_partial_output(tmp_path, bags):
    interrupted, ended, leftovers, children = run_bounded(interrupt_a_fleet, bags,
                                                          str(tmp_path / 'out'))
    assert interrupted
    assert children == []
    # the fast bag ended normally; the slow one, still running, was told to stop (SIGTERM,
    # the worker's own handler: exit code 143) and did at once, not after the bounded wait
    assert [code for code, _ in ended] == [0, 128 + signal.SIGTERM]
    assert ended[1][1] < sources.JOIN_TIMEOUT_S
    assert leftovers == ['0_fast']  # the stopped replay discarded its staged output


def sigterm_while_held(conn):
    from pump_friction_ros.interrupts import sigint_held
    events = []
    signal.signal(signal.SIGTERM, lambda signum, frame: events.append('terminated'))
    with sigint_held():
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.05)  # the signal is pending, not handled
        events.append('still held')
    events.append('released')
    conn.send(events)


def test_a_sigterm_during_a_held_moment_is_delivered_after_it():
    # a worker stopped while it moves its output into place exits once it is there
    assert run_bounded(sigterm_while_held) == ['still held', 'terminated', 'released']


def sigterm_to_another_thread_while_held(conn):
    import threading

    from pump_friction_ros.interrupts import sigint_held, sigint_kept, stop_signal
    sigint_kept()  # the command's SIGTERM: a Ctrl-C
    events = []
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)  # started before the hold: it does not block
    other.start()
    try:
        with sigint_held():
            signal.pthread_kill(other.ident, signal.SIGTERM)  # a thread the mask misses
            time.sleep(0.05)
            events.append('still held')
        events.append('released')
    except KeyboardInterrupt:
        events.append('interrupted')
    stop.set()
    other.join()
    conn.send((events, stop_signal()))


def test_a_sigterm_that_reaches_another_thread_during_a_held_moment_waits_for_its_end():
    # numpy's BLAS threads are such threads: the signal's Python handler runs in the main
    # thread whichever thread received it, and the mask covers the main thread only
    events, came = run_bounded(sigterm_to_another_thread_while_held)
    assert (events, came) == (['still held', 'interrupted'], signal.SIGTERM)


def report_mask(conn):
    conn.send(sorted(signal.pthread_sigmask(signal.SIG_BLOCK, [])))


def start_under_the_hold_with_another_default(method, conn):
    from pump_friction_ros.interrupts import sigint_held
    multiprocessing.set_start_method(method, force=True)
    ctx = sources.process_context()
    mine, theirs = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=report_mask, args=(theirs,))
    with sigint_held():
        proc.start()
    theirs.close()
    mask = mine.recv() if mine.poll(BOUND_S) else None
    proc.join(BOUND_S)
    conn.send((ctx.get_start_method(), mask))


@pytest.mark.parametrize('method', ['forkserver', 'spawn'])
def test_helpers_start_with_ctrl_c_held_whatever_the_default_start_method(method):
    # Python 3.14 starts processes from a forkserver by default on Linux: its children do
    # not inherit the parent thread's blocked signals, and a Ctrl-C before the helper's own
    # handler would raise in it. The helpers fork, and a child starts with both held
    started, mask = run_bounded(start_under_the_hold_with_another_default, method)
    assert started == 'fork'
    assert {signal.SIGINT, signal.SIGTERM} <= set(mask)


def test_fleet_workers_ignore_ctrl_c_and_results_keep_job_order(tmp_path, bags):
    jobs = [ReplayJob(bag=str(b), config=CONFIG) for b in bags * 2]
    summaries = run_jobs(jobs, workers=3)
    assert [s.bag for s in summaries] == [j.bag for j in jobs]
    assert all(not s.error and s.estimates == 12000 for s in summaries)
