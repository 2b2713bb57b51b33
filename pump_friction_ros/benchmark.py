"""Benchmarks, run as ``python -m pump_friction_ros.benchmark [SECTION ...]``.

Each figure is printed with a baseline measured in the same run on the same machine, and
the ratio between them, so numbers from different machines can be compared. Timings are
the best of several repeats (the least disturbed by other load).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

from .model import PumpModel
from .params import load_pump
from .units import BAR_TO_PA, RPM_TO_RAD_S

__all__ = ['best_time_s', 'main']


def best_time_s(func: Callable[[], object], repeat: int = 5, number: int = 1) -> float:
    """Best wall time of ``number`` calls, over ``repeat`` repeats, per call.

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


SECTIONS: dict[str, Callable[[], None]] = {'model': bench_model}


def main(argv: list[str] | None = None) -> int:
    """Run the benchmarks.

    Parameters
    ----------
    argv : list of str, optional
        Section names (default: all).

    Returns
    -------
    int
        Exit code 0.
    """
    parser = argparse.ArgumentParser(prog='python -m pump_friction_ros.benchmark',
                                     description=__doc__.splitlines()[0])
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
