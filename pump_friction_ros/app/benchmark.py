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
Benchmarks, run as ``python -m pump_friction_ros.app.benchmark [SECTION ...]``.

Each figure is printed with a baseline measured in the same run on the same machine, and
the ratio between them, so numbers from different machines can be compared. Timings are
the best of several repeats (the least disturbed by other load).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
import time

import numpy as np

from ..physics.model import PumpModel
from ..physics.pump_parameters import load_pump
from ..physics.units import BAR_TO_PA, RPM_TO_RAD_S

__all__ = ['best_time_s', 'main']


def best_time_s(func: Callable[[], object], repeat: int = 5, number: int = 1) -> float:
    """
    Best wall time of ``number`` calls, over ``repeat`` repeats, per call.

    Parameters
    ----------
    func : callable
        Function to time.
    repeat : int
        Repeats; the minimum is kept.
    number : int
        Calls per repeat.

    Returns
    -------
    float
        Seconds per call [s].

    """
    best = float('inf')
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            func()
        best = min(best, (time.perf_counter() - start) / number)
    return best


def _row(label: str, value: str, baseline: str = '', ratio: str = '') -> None:
    print(f'  {label:<52} {value:>14} {baseline:>16} {ratio:>10}')


def bench_model() -> None:
    """Full model: one operating point, and a 100 x 50 speed-pressure grid."""
    params = load_pump()
    model = PumpModel(params, n_angles=360)
    n_pistons = params.geometry.n_pistons
    print(f'model ({params.name}): 360 shaft angles x {n_pistons} pistons, all components')
    print('  baseline: np.cross over an array of the same (points x angles x 3) shape, i.e. '
          'the cost of one vector operation')
    _row('', 'time', 'baseline', 'ratio')

    single = best_time_s(lambda: model.evaluate(1000.0, 300 * BAR_TO_PA), repeat=20, number=5)
    a = np.random.default_rng(0).standard_normal((1, 360, 3))
    cross1 = best_time_s(lambda: np.cross(a, a), repeat=20, number=20)
    _row('one operating point (target <= 2 ms)', f'{single * 1e3:.3f} ms',
         f'{cross1 * 1e6:.1f} us', f'{single / cross1:.0f}x')
    print(f'  -> {single / 2e-3:.2f} of the 2 ms budget')

    speeds = np.linspace(0.0, 12000.0, 100) * RPM_TO_RAD_S
    pressures = np.linspace(0.0, 350.0, 50) * BAR_TO_PA
    sp, pr = np.meshgrid(speeds, pressures, indexing='ij')
    grid = best_time_s(lambda: model.evaluate(sp, pr), repeat=3)
    b = np.random.default_rng(0).standard_normal((sp.size, 360, 3))
    cross_grid = best_time_s(lambda: np.cross(b, b), repeat=3)
    _row('100 speeds x 50 pressures grid (target <= 1 s)', f'{grid:.3f} s',
         f'{cross_grid * 1e3:.1f} ms', f'{grid / cross_grid:.0f}x')
    print(f'  -> {grid / 1.0:.2f} of the 1 s budget; '
          f'{grid / sp.size * 1e6:.0f} us per operating point')


def bench_table() -> None:
    """Friction table: build time; scalar and vectorised lookups against scipy's RGI."""
    from scipy.interpolate import RegularGridInterpolator

    from ..table.friction_table import build_table

    params = load_pump()
    start = time.perf_counter()
    table = build_table(params)
    build = time.perf_counter() - start
    shape = 'x'.join(str(n) for n in table.torque_nm.shape)
    print(f'table ({params.name}): {shape} (mode x speed x pressure x viscosity x component)')
    print(f'  built in {build:.2f} s (target: a few seconds)')
    print('  baseline: scipy.interpolate.RegularGridInterpolator (linear) on the same grid and '
          'values (one mode, 4 components)')
    rgi = RegularGridInterpolator((table.speed_axis_rad_s, table.pressure_axis_pa,
                                   table.viscosity_axis_m2_s), table.torque_nm[0])
    _row('', 'ours', 'RGI', 'speed-up')
    speed, pressure, viscosity = 523.0, 137e5, 53e-6
    point = np.array([[speed, pressure, viscosity]])
    t_rgi = best_time_s(lambda: rgi(point), repeat=5, number=2000)
    t_mag = best_time_s(lambda: table.magnitudes(speed, pressure, viscosity), repeat=5,
                        number=20000)
    t_lookup = best_time_s(lambda: table.lookup(speed, pressure, viscosity), repeat=5,
                           number=20000)
    _row('scalar: component torques, per call (target >= 25x)', f'{t_mag * 1e6:.2f} us',
         f'{t_rgi * 1e6:.1f} us', f'{t_rgi / t_mag:.0f}x')
    _row('scalar: signed torques + theoretical + efficiency', f'{t_lookup * 1e6:.2f} us',
         f'{t_rgi * 1e6:.1f} us', f'{t_rgi / t_lookup:.0f}x')
    rng = np.random.default_rng(0)
    n = 1_000_000
    pts = np.column_stack([rng.uniform(0.0, table.speed_axis_rad_s[-1], n),
                           rng.uniform(0.0, table.pressure_axis_pa[-1], n),
                           rng.uniform(table.viscosity_axis_m2_s[0],
                                       table.viscosity_axis_m2_s[-1], n)])
    t_rgi_v = best_time_s(lambda: rgi(pts), repeat=2)
    t_vec = best_time_s(lambda: table.magnitudes_array(pts[:, 0], pts[:, 1], pts[:, 2]),
                        repeat=3)
    _row('vector: 1 M points, points per second (target >= 3x)', f'{n / t_vec / 1e6:.2f} M/s',
         f'{n / t_rgi_v / 1e6:.2f} M/s', f'{t_rgi_v / t_vec:.1f}x')


def bench_estimator() -> None:
    """Estimator core: cost of one joint-state sample (lookup, derivative, residual, monitor)."""
    from ..core.estimator import TorqueEstimator
    from ..core.inputs import InputKind
    from ..core.node_parameters import EstimatorConfig
    from ..sim.duty_cycle import DutyCycle, simulate_duty_cycle
    from ..table.friction_table import build_table

    params = load_pump()
    table = build_table(params)
    run = simulate_duty_cycle(table, DutyCycle(duration_s=20.0), seed=1)
    stamps = np.round(run.t_s * 1e9).astype(np.int64).tolist()
    speed, torque = run.speed_rad_s.tolist(), run.torque_nm.tolist()
    n = len(stamps)
    print(f'estimator core: {n} joint-state samples of a simulated duty cycle (1 kHz)')
    print('  baseline: the bare scalar table lookup (FrictionTable.magnitudes) for the same '
          'samples')

    joint, pressure = InputKind.JOINT_STATE, InputKind.LOAD_PRESSURE

    def run_core() -> None:
        core = TorqueEstimator(EstimatorConfig(), table, params.oil.viscosity_m2_s)
        on_input = core.on_input
        for k in range(n):
            on_input(pressure, stamps[k], 100e5)
            on_input(joint, stamps[k], speed[k], torque[k])

    def run_pressure_only() -> None:
        core = TorqueEstimator(EstimatorConfig(), table, params.oil.viscosity_m2_s)
        on_input = core.on_input
        for k in range(n):
            on_input(pressure, stamps[k], 100e5)

    def run_lookup() -> None:
        lookup = table.magnitudes
        for k in range(n):
            lookup(abs(speed[k]), 100e5, 46e-6, False)

    per_sample = (best_time_s(run_core, repeat=3) - best_time_s(run_pressure_only, repeat=3)) / n
    lookup = best_time_s(run_lookup, repeat=3) / n
    _row('', 'core', 'lookup', 'ratio')
    _row('one joint-state sample (target <= 20 us)', f'{per_sample * 1e6:.1f} us',
         f'{lookup * 1e6:.2f} us', f'{per_sample / lookup:.1f}x')
    print(f'  -> {per_sample * 1e3 * 100:.2f} % of one core at 1 kHz '
          '(rclpy itself: ~45 % per 1 kHz JointState subscription on Jazzy)')


def bench_replay() -> None:
    """Replay of the wear sample bag against rosbags' own read-and-deserialise loop."""
    from pathlib import Path
    import shutil
    import tempfile

    from rosbags.highlevel import AnyReader

    from ..bags.replay import replay_bag
    from ..core.estimator_setup import estimator_from_config
    from ..core.node_parameters import load_estimator_config
    from ..physics.pump_parameters import config_dir

    bag = config_dir().parent / 'bags' / 'eha_valve_plate_wear'
    if not bag.exists():
        print(f'replay: sample bag not found at {bag}; skipped')
        return
    config = load_estimator_config([config_dir() / 'torque_estimator.yaml',
                                    bag.parent / 'eha_params.yaml'])  # the bags' pump
    estimator_from_config(config)  # warm the table cache outside the timings

    def rosbags_loop() -> None:
        with AnyReader([bag]) as reader:
            for conn, _, raw in reader.messages():
                reader.deserialize(raw, conn.msgtype)

    tmp = Path(tempfile.mkdtemp(prefix='pump_friction_bench_'))

    def replay(out: bool) -> None:
        shutil.rmtree(tmp / 'out', ignore_errors=True)
        replay_bag(bag, config, out_bag=tmp / 'out' if out else None,
                   core=estimator_from_config(config))

    try:
        base = best_time_s(rosbags_loop, repeat=3)
        bare = best_time_s(lambda: replay(False), repeat=3)
        full = best_time_s(lambda: replay(True), repeat=3)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    with AnyReader([bag]) as reader:
        count = reader.message_count
    print(f'replay of {bag.name} ({count} messages, mcap)')
    print('  baseline: rosbags AnyReader reading and deserialising every message')
    _row('', 'replay', 'rosbags loop', 'speed-up')
    _row('estimates only (target >= 2x)', f'{bare:.2f} s', f'{base:.2f} s',
         f'{base / bare:.2f}x')
    _row('estimates + output bag (target >= 1.5x)', f'{full:.2f} s', f'{base:.2f} s',
         f'{base / full:.2f}x')


def bench_isolation() -> None:
    """Fault isolation: cost of one attribution window, before a change and during one."""
    from ..core.attribution import AttributionSettings, FaultIsolation
    from ..core.change_stats import ChangeStats
    from ..core.node_parameters import EstimatorConfig, settings_view

    config = EstimatorConfig()
    duration_s = config.attribution_window_s
    n = 2000  # windows: 500 s of monitored running, a change in the second half
    rng = np.random.default_rng(1)
    speed, load = rng.uniform(100.0, 900.0, n), rng.uniform(0.5, 6.0, n)
    sig = np.column_stack([0.01 + 4e-4 * speed, 0.06 + 2e-4 * speed, load, -load,
                           np.ones(n), np.ones(n)])
    d = 0.4 * sig[:, 0] * (np.arange(n) >= n // 2) + rng.normal(0.0, 0.01, n)
    windows = [(sig[k], float(d[k]), float(30.0 * sig[k, 2]), k >= n // 2) for k in range(n)]
    undetectable = np.full(6, 0.2)
    keep = float(np.exp(-duration_s / config.isolation_memory_s))
    print(f'isolation: {n} attribution windows of {duration_s} s, a valve-plate change from '
          'the middle on')
    print('  baseline: the single-cause GLR sums alone (ChangeStats.add and .glr) per window')

    def run() -> FaultIsolation:
        isolation = FaultIsolation(settings_view(config, AttributionSettings), False)
        for s, d_nm, u_nm, on in windows:
            isolation.add(s, d_nm, 1e4, duration_s, on, u_nm)
            isolation.bias.set_prior(undetectable)
        return isolation

    def run_sums() -> None:
        stats = ChangeStats(6)
        for s, d_nm, *_ in windows:
            stats.add(s, d_nm, 1e4, keep, duration_s, 0.0)
            stats.glr()

    isolation = run()
    add = best_time_s(run, repeat=5) / n
    verdict = best_time_s(isolation.verdict, repeat=5, number=200)
    sums = best_time_s(run_sums, repeat=5) / n
    _row('', 'isolation', 'GLR sums', 'ratio')
    _row('the sums of one window (every window)', f'{add * 1e6:.1f} us', f'{sums * 1e6:.1f} us',
         f'{add / sums:.1f}x')
    _row('one verdict in a change (bias, drift, choice)', f'{verdict * 1e6:.1f} us',
         f'{sums * 1e6:.1f} us', f'{verdict / sums:.1f}x')
    print(f'  -> {(add + 3.0 * verdict) / duration_s * 100:.3f} % of one core at one window '
          f'per {duration_s} s of running, with the 1-3 verdicts a window asks for during a '
          "change (the scales, the oil's and the gain's follow)")


SECTIONS: dict[str, Callable[[], None]] = {'model': bench_model, 'table': bench_table,
                                           'estimator': bench_estimator,
                                           'isolation': bench_isolation,
                                           'replay': bench_replay}


def main(argv: list[str] | None = None) -> int:
    """
    Run the benchmarks.

    Parameters
    ----------
    argv : list of str, optional
        Section names (default: all).

    Returns
    -------
    int
        Exit code 0.

    """
    parser = argparse.ArgumentParser(prog='python -m pump_friction_ros.app.benchmark',
                                     description=__doc__.strip().splitlines()[0])
    parser.add_argument('sections', nargs='*', metavar='SECTION',
                        help=f'sections to run (default: all of {", ".join(SECTIONS)})')
    args = parser.parse_args(argv)
    unknown = sorted(set(args.sections) - set(SECTIONS))
    if unknown:
        parser.error(f'unknown section(s) {", ".join(unknown)}; choose from '
                     f'{", ".join(SECTIONS)}')
    for name in args.sections or SECTIONS:
        SECTIONS[name]()
        print()
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
