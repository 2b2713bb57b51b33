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

"""The array forms of the two low-pass stages and the settle gate equal the loops, bit for bit."""

import itertools
import os
import subprocess
import sys

import numpy as np
from pump_friction_ros.blas_threads import BLAS_THREAD_VARIABLES
from pump_friction_ros.core.lowpass import MIN_RUN, run_two_stage, stage_coefficients
from pump_friction_ros.core.settled_residual import SettledResidual
from pump_friction_ros.core.speed_filter import SpeedFilter
import pytest

TAU_S = 0.01


def exact(values):
    """Return a key equal only for identical floats (hex), lists and tuples element-wise."""
    if isinstance(values, float):
        return values.hex()
    if isinstance(values, np.ndarray):
        return exact(values.tolist())
    if isinstance(values, list | tuple):
        return tuple(exact(v) for v in values)
    if isinstance(values, dict):
        return tuple((k, exact(v)) for k, v in values.items())
    return values


def evenly_spaced(rng, n, step_ns=1_000_000):
    """Stamps of one spacing with a few gaps, a second spacing and a clock step back."""
    steps = np.full(n, step_ns, dtype=np.int64)
    steps[n // 2:] = 2 * step_ns  # a second spacing
    steps[[n // 8, n // 3, 3 * n // 5]] = 90_000_000  # gaps: restarts
    steps[4 * n // 5] = -5 * step_ns  # a clock restart
    return np.cumsum(steps) + 10**12


def test_lfilter_recursion_equals_the_scalar_recursion_bit_for_bit():
    rng = np.random.default_rng(3)
    n = 4000
    stamps = np.cumsum(np.full(n, 1_000_000, dtype=np.int64))
    x = rng.normal(0.0, 1.0, n) * 10.0 ** rng.uniform(-3, 3, n)
    start = np.zeros(n, dtype=bool)
    start[[0, 1234, 1235, 3000]] = True
    run = run_two_stage(stamps, x, start, 0, (0.0, 0.0, 0.0), -1, (0.0, 0.0, 0.0), TAU_S)
    assert run is not None
    b, a, c = stage_coefficients(1e-3, TAU_S)
    lp1 = lp2 = x_prev = 0.0
    for i, xi in enumerate(x.tolist()):
        if start[i]:
            lp1 = lp2 = x_prev = xi
        else:
            old = lp1
            lp1 = b * old + (a * x_prev + c * (xi - x_prev))
            lp2 = b * lp2 + (a * old + c * (lp1 - old))
            x_prev = xi
        assert (run.lp1[i].hex(), run.lp2[i].hex()) == (lp1.hex(), lp2.hex()), i


def test_jittered_stamps_are_left_to_the_loop():
    rng = np.random.default_rng(4)
    n = 20 * MIN_RUN
    stamps = np.cumsum(rng.integers(990_000, 1_010_000, n))
    assert run_two_stage(stamps, rng.normal(size=n), np.zeros(n, dtype=bool), 0,
                         (0.0, 0.0, 0.0), -1, (0.0, 0.0, 0.0), TAU_S) is None


@pytest.mark.parametrize('jitter', [False, True], ids=['even', 'jittered'])
def test_speed_filter_chunks_equal_its_samples(jitter, monkeypatch):
    rng = np.random.default_rng(5)
    n = 6000
    stamps = evenly_spaced(rng, n)
    if jitter:
        stamps = stamps + rng.integers(0, 20_000, n)
    speeds = rng.normal(100.0, 50.0, n)
    one, many = SpeedFilter(TAU_S, 50_000_000), SpeedFilter(TAU_S, 50_000_000)
    expected = [one.update(s, x) for s, x in zip(stamps.tolist(), speeds.tolist(), strict=True)]
    looped = []
    real_loop = SpeedFilter._loop
    monkeypatch.setattr(SpeedFilter, '_loop',
                        lambda self, *a: looped.append(1) or real_loop(self, *a))
    cuts = [0, 1, 700, 701, 2999, 4500, n]
    accel, counts = zip(*(many.update_many(stamps[i:j], speeds[i:j])
                          for i, j in itertools.pairwise(cuts)), strict=True)
    assert exact(np.concatenate(accel)) == exact(expected)
    assert int(np.concatenate(counts)[-1]) == one.restarts > 4
    assert exact(vars(many)) == exact(vars(one))
    assert bool(looped) == jitter  # even spacing: the array form did it


def settled_stream(rng, n, jitter):
    """Make samples for `SettledResidual`: steady stretches, NaN torques, filter restarts."""
    stamps = evenly_spaced(rng, n)
    if jitter:
        stamps = stamps + rng.integers(0, 20_000, n)
    restarts = np.cumsum(rng.random(n) < 0.0005)
    diffs = rng.normal(0.0, 0.3, n)
    for at in rng.integers(0, n - 30, 6):
        diffs[at:at + rng.integers(1, 30)] = np.nan  # torque missing for a while
    steady = np.ones(n, dtype=bool)
    for at in rng.integers(0, n - 200, 10):
        steady[at:at + rng.integers(1, 200)] = False
    payloads = (rng.normal(size=n), rng.normal(size=n))
    return stamps, restarts, diffs, steady, payloads


@pytest.mark.parametrize('jitter', [False, True], ids=['even', 'jittered'])
@pytest.mark.parametrize('lookahead_s', [0.0, 0.02, 0.5])
def test_settle_gate_chunks_equal_its_samples(jitter, lookahead_s, monkeypatch):
    rng = np.random.default_rng(6 + int(lookahead_s * 100))
    n = 8000
    stamps, restarts, diffs, steady, payloads = settled_stream(rng, n, jitter)
    one = SettledResidual(TAU_S, 50_000_000, 0.05, lookahead_s)
    many = SettledResidual(TAU_S, 50_000_000, 0.05, lookahead_s)
    expected = []
    for i in range(n):
        got = one.update(int(stamps[i]), int(restarts[i]), float(diffs[i]), bool(steady[i]),
                         tuple(float(p[i]) for p in payloads))
        if got is not None:
            expected.append((i, got))
    looped = []
    real_loop = SettledResidual._loop
    monkeypatch.setattr(SettledResidual, '_loop',
                        lambda self, *a: looped.append(len(a[0])) or real_loop(self, *a))
    cuts = np.unique(np.concatenate(([0, n], rng.integers(0, n, 12))))
    released = []
    for i, j in itertools.pairwise(cuts.tolist()):
        out = many.update_many(stamps[i:j], restarts[i:j], diffs[i:j], steady[i:j],
                               tuple(p[i:j] for p in payloads))
        carried = len(out.carried)
        for k in range(out.positions.size):
            source = int(out.sources[k])
            payload = out.carried[k] if k < carried else \
                tuple(float(p[i + source]) for p in payloads)
            assert (source == -1) == (k < carried)
            released.append((i + int(out.positions[k]),
                             (int(out.stamps_ns[k]), float(out.filtered_nm[k]), payload)))
    assert len(expected) > n // 5
    assert exact(released) == exact(expected)
    assert exact(vars(many)) == exact(vars(one))
    # even spacing: the array form, but for a chunk where the clock steps back or one of
    # a few samples holding several runs
    assert (sum(looped) > 0.9 * n) if jitter else (sum(looped) < 0.5 * n), sum(looped)


def test_entry_layers_ask_for_one_blas_thread_unless_told():
    code = ('import os, pump_friction_ros.{layer}; '
            'print(",".join(os.environ[v] for v in {names}))')
    env = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    for layer in ('node', 'app'):
        out = subprocess.run([sys.executable, '-c', code.format(
            layer=layer, names=BLAS_THREAD_VARIABLES)], env=env, capture_output=True,
            text=True, check=True).stdout.split()
        assert out == [','.join(['1'] * len(BLAS_THREAD_VARIABLES))], layer
    told = dict(env, OPENBLAS_NUM_THREADS='3')
    out = subprocess.run([sys.executable, '-c', code.format(
        layer='app', names=BLAS_THREAD_VARIABLES)], env=told, capture_output=True, text=True,
        check=True).stdout.split()
    assert out[0].split(',')[0] == '3'
