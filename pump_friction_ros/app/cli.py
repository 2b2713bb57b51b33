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

"""Command line ``pump_friction``: the paper's units (rpm, bar, cSt) live here and only here."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
import json
import math
import os
import signal
import sys
from typing import TYPE_CHECKING

import numpy as np

from . import data_commands
from .arguments import bounded_float, bounded_int, Parser, SEED
from .baseline_commands import add_baseline_commands
from .console import GuardedStdout, non_utf8_argument
from .. import __version__, MODEL_VERSION
from ..calibration.fit import NAMES as FIT_NAMES
from ..errors import PumpFrictionError
from ..interrupts import (
    committed_outputs,
    raise_if_interrupted,
    sigint_ignored,
    sigint_kept,
    stop_signal,
)
from ..physics.model import COMPONENTS, PumpModel
from ..physics.pump_parameters import load_pump
from ..physics.units import (
    bar_to_pa,
    CC_TO_M3,
    cst_to_m2_s,
    MM_TO_M,
    rad_s_to_rpm,
    rpm_to_rad_s,
)
from ..table.friction_table import TableSpec

if TYPE_CHECKING:
    from ..table.friction_table import FrictionTable

__all__ = ['main']

MAX_SPEED_RPM = 100_000.0
MAX_PRESSURE_BAR = 2_000.0
MAX_VISCOSITY_CST = 10_000.0


_speed = bounded_float('--speed-rpm', -MAX_SPEED_RPM, MAX_SPEED_RPM)
_pressure = bounded_float('--pressure-bar', -MAX_PRESSURE_BAR, MAX_PRESSURE_BAR)
_viscosity = bounded_float('--viscosity-cst', 1e-3, MAX_VISCOSITY_CST)


def _json_number(value: float) -> float | None:
    """Finite floats as they are, NaN as JSON null."""
    value = float(value)
    return value if math.isfinite(value) else None


def _model(args: argparse.Namespace) -> PumpModel:
    return PumpModel(load_pump(args.pump))


def _viscosity_m2_s(args: argparse.Namespace, model: PumpModel) -> float:
    if args.viscosity_cst is None:
        return model.params.oil.viscosity_m2_s
    return cst_to_m2_s(args.viscosity_cst)


def _cmd_paper_check(args: argparse.Namespace) -> int:
    from ..physics.paper import format_checks, paper_checks

    model = _model(args)
    rows = paper_checks(model)
    if args.json:
        print(json.dumps([{'quantity': r.quantity, 'unit': r.unit, 'paper': r.paper,
                           'model': r.model, 'relative_difference': r.relative_difference,
                           'kind': r.kind, 'tolerance': r.tolerance, 'holds': r.holds,
                           'source': r.source, 'note': r.note} for r in rows], indent=2))
    else:
        print(format_checks(rows, model.params.name))
    return 0


def torque_record(model: PumpModel, speed_rad_s: float, pressure_pa: float,
                  viscosity_m2_s: float) -> dict[str, float | None]:
    """
    Revolution-mean torques of one operating point, keyed as in ``torque --json``.

    Parameters
    ----------
    model : PumpModel
        The pump model.
    speed_rad_s : float
        Shaft speed [rad/s].
    pressure_pa : float
        Pressure difference [Pa].
    viscosity_m2_s : float
        Oil kinematic viscosity [m^2/s].

    Returns
    -------
    dict
        Signed torques [N*m] and efficiency [-] (None when undefined).

    """
    res = model.evaluate(speed_rad_s, pressure_pa, viscosity_m2_s)
    record = {'theoretical_nm': res.theoretical_nm[0]}
    record.update({f'{c}_nm': res.component_nm(c)[0] for c in COMPONENTS})
    record.update(friction_nm=res.friction_nm[0], input_nm=res.input_nm[0],
                  efficiency=res.efficiency[0])
    return {k: _json_number(v) for k, v in record.items()}


def _print_record(record: dict[str, float | None], header: str, as_json: bool) -> None:
    if as_json:
        print(json.dumps(record, indent=2))
        return
    print(header)
    for key, value in record.items():
        shown = 'undefined' if value is None else f'{value:.6g}'
        print(f'  {key:<24} {shown}')


def table_record(table: FrictionTable, speed_rad_s: float, pressure_pa: float,
                 viscosity_m2_s: float) -> tuple[dict[str, float | None], int]:
    """
    Torques of one operating point from a friction table, keyed as `torque_record`.

    Parameters
    ----------
    table : FrictionTable
        The table.
    speed_rad_s : float
        Shaft speed [rad/s].
    pressure_pa : float
        Pressure difference [Pa].
    viscosity_m2_s : float
        Oil kinematic viscosity [m^2/s].

    Returns
    -------
    tuple
        The record (signed torques [N*m], efficiency [-] or None) and the lookup flags.

    """
    res = table.lookup(speed_rad_s, pressure_pa, viscosity_m2_s)
    record = {'theoretical_nm': res.theoretical_nm}
    record.update({f'{c}_nm': v for c, v in zip(COMPONENTS, res.components_nm, strict=True)})
    record.update(friction_nm=res.friction_nm, input_nm=res.input_nm, efficiency=res.efficiency)
    return {k: _json_number(v) for k, v in record.items()}, res.flags


def _cmd_torque(args: argparse.Namespace) -> int:
    params = load_pump(args.pump)
    speed, pressure = rpm_to_rad_s(args.speed_rpm), bar_to_pa(args.pressure_bar)
    viscosity = (params.oil.viscosity_m2_s if args.viscosity_cst is None
                 else cst_to_m2_s(args.viscosity_cst))
    if args.table:
        from ..paths import resolve_path
        from ..table.friction_table import describe_flags
        from ..table.table_files import load_table

        table_path = resolve_path(args.table, '--table', must_exist=False)
        record, flags = table_record(load_table(table_path, params), speed, pressure,
                                     viscosity)
        if flags:
            print(f"pump_friction: warning: {describe_flags(flags)}: clamped to the table's "
                  'edge', file=sys.stderr)
        source = f'table {args.table}'
    else:
        record = torque_record(PumpModel(params), speed, pressure, viscosity)
        source = 'full model'
    broken = [key for key, value in record.items() if value is None and key != 'efficiency']
    if broken:  # validation keeps pump files physical; never print a torque as undefined
        raise PumpFrictionError(f'{params.name}: the model gives no finite {", ".join(broken)}'
                                " at this operating point; check the pump file's values")
    _print_record(record, f'{params.name}: {args.speed_rpm:g} rpm, {args.pressure_bar:g} bar, '
                  f'{source} (torques in N*m, signed)', args.json)
    return 0


def _cmd_kinematics(args: argparse.Namespace) -> int:
    model = _model(args)
    geom = model.params.geometry
    res = model.evaluate(rpm_to_rad_s(args.speed_rpm), bar_to_pa(args.pressure_bar),
                         _viscosity_m2_s(args, model), waveforms=True)
    wf = res.waveforms
    record = {
        'stroke_mm': geom.stroke_m / MM_TO_M,
        'displacement_cc': geom.displacement_m3 / CC_TO_M3,
        'head_speed_max_m_s': float(np.abs(wf.head_velocity_m_s[0]).max()),
        'piston_omega_max_rad_s': float(np.linalg.norm(wf.piston_omega_rad_s[0], axis=-1).max()),
        'joint_force_max_n': float(res.joint_force_max_n[0]),
        'head_force_max_n': float(res.head_force_max_n[0]),
    }
    _print_record({k: _json_number(v) for k, v in record.items()},
                  f'{model.params.name}: {args.speed_rpm:g} rpm, {args.pressure_bar:g} bar',
                  args.json)
    return 0


def _cmd_plot(args: argparse.Namespace) -> int:
    from .model_figures import write_model_figures
    from ..staging import looks_like_plots, StagedOutputs

    model = _model(args)
    outputs = StagedOutputs()
    try:  # the folder checked and made first, moved into place whole
        staged = outputs.add(args.out, args.force, True, looks_like=looks_like_plots, flag='--out')
        with staged.writing():
            names = [path.name for path in write_model_figures(model, staged.path)]
        outputs.commit()
    except BaseException:
        outputs.discard()
        raise
    for name in names:
        print(staged.target / name)
    return 0


def _add_pump(parser: argparse.ArgumentParser) -> None:
    parser.add_argument('--pump', metavar='FILE', default=None,
                        help='pump parameter YAML, package://pump_friction_ros/... path or '
                        'shipped set name, e.g. hong_doh_2004_consistent (default: '
                        'hong_doh_2004)')


def _add_viscosity(parser: argparse.ArgumentParser) -> None:
    parser.add_argument('--viscosity-cst', type=_viscosity, default=None, metavar='CST',
                        help="oil kinematic viscosity [cSt] (default: the pump file's)")


def build_parser() -> argparse.ArgumentParser:
    """
    Build the ``pump_friction`` argument parser.

    Returns
    -------
    argparse.ArgumentParser
        Parser with one sub-command per job.

    """
    parser = Parser(prog='pump_friction',
                    description='Bent-axis pump friction model (Hong & Doh 2004).')
    parser.add_argument('--version', action='version',
                        version=f'%(prog)s {__version__} (model {MODEL_VERSION})')
    sub = parser.add_subparsers(dest='command', required=True, parser_class=Parser)

    p = sub.add_parser('paper-check', help="the paper's numbers next to the model's")
    _add_pump(p)
    p.add_argument('--json', action='store_true', help='machine-readable output')
    p.set_defaults(func=_cmd_paper_check)

    p = sub.add_parser('torque', help='revolution-mean torques at one operating point')
    p.add_argument('--speed-rpm', type=_speed, required=True, metavar='N',
                   help='shaft speed [rpm], signed')
    p.add_argument('--pressure-bar', type=_pressure, required=True, metavar='P',
                   help='pressure difference p_A - p_B [bar], signed')
    _add_viscosity(p)
    _add_pump(p)
    p.add_argument('--table', metavar='FILE', default=None,
                   help='answer from this friction table instead of the full model')
    p.add_argument('--json', action='store_true', help='machine-readable output')
    p.set_defaults(func=_cmd_torque)

    p = sub.add_parser('build-table', help='precompute the friction-torque table')
    _add_pump(p)
    p.add_argument('--out', metavar='FILE', default=None,
                   help='output .npz (default: the cache used when no table is given)')
    # above the finely resolved low-speed part of the axis (TableSpec.low_speed_rad_s)
    lowest_rpm = float(math.ceil(rad_s_to_rpm(TableSpec.low_speed_rad_s)))
    p.add_argument('--max-speed-rpm', type=bounded_float('--max-speed-rpm', lowest_rpm,
                                                         MAX_SPEED_RPM), default=12000.0,
                   metavar='N', help='speed envelope [rpm] (default 12000)')
    p.add_argument('--max-pressure-bar', type=bounded_float('--max-pressure-bar', 1.0,
                                                            MAX_PRESSURE_BAR), default=350.0,
                   metavar='P', help='pressure-difference envelope [bar] (default 350)')
    p.add_argument('--viscosity-cst', type=_viscosity, nargs=2, default=None,
                   metavar=('LOW', 'HIGH'),
                   help="viscosity range [cSt], 8 nodes per decade (default: the node's with "
                   'its default parameters, ISO VG 46 from 250 degC to 1000 cSt)')
    p.add_argument('--force', action='store_true', help='replace an existing --out file')
    p.add_argument('--quiet', action='store_true', help='no progress bar')
    p.set_defaults(func=data_commands.cmd_build_table)

    p = sub.add_parser('kinematics', help='stroke, displacement, piston speeds and forces')
    p.add_argument('--speed-rpm', type=_speed, required=True, metavar='N',
                   help='shaft speed [rpm], signed')
    p.add_argument('--pressure-bar', type=_pressure, default=0.0, metavar='P',
                   help='pressure difference [bar] for the forces (default 0)')
    _add_viscosity(p)
    _add_pump(p)
    p.add_argument('--json', action='store_true', help='machine-readable output')
    p.set_defaults(func=_cmd_kinematics)

    p = sub.add_parser('replay', help="the node's outputs from rosbag2 bags")
    p.add_argument('bags', nargs='+', metavar='BAG',
                   help='bag directories (sqlite3 or mcap), or folders holding bags')
    p.add_argument('--params', metavar='FILE', action='append', default=None,
                   help='node parameters file; may be given several times, later files '
                   "overriding earlier ones (default: the node's declared defaults, which "
                   'config/torque_estimator.yaml repeats)')
    p.add_argument('--out', metavar='OUT_BAG', default=None,
                   help='output bag (several bags: a folder, one bag each)')
    p.add_argument('--csv', metavar='FILE', default=None,
                   help='CSV, one row per estimate (several bags: a folder)')
    p.add_argument('--plots', metavar='DIR', default=None, help='folder for PNG plots')
    p.add_argument('--topic-remap', nargs='+', default=[], metavar='OLD:=NEW',
                   help="the node's topic OLD is NEW in the bag")
    p.add_argument('--baseline', metavar='FILE', default=None,
                   help="start the wear monitor from this healthy baseline file (the node's "
                   "baseline_file, or learn-baseline's); every bag starts from it")
    p.add_argument('--storage', choices=('sqlite3', 'mcap'), default=None,
                   help="output bag storage (default: the input's)")
    p.add_argument('--compression', choices=('auto', 'none', 'zstd'), default='auto',
                   help='output bag zstd compression: auto follows the input (default), zstd '
                   'is chunks for mcap and file compression for sqlite3')
    p.add_argument('--force', action='store_true', help='replace existing outputs')
    p.add_argument('--workers', type=int, default=os.cpu_count() or 1, metavar='N',
                   help='parallel local processes for several bags (default: CPU count)')
    p.add_argument('--dask', metavar='ADDRESS', default=None,
                   help='run the bags on this Dask scheduler (extra [fleet])')
    p.add_argument('--quiet', action='store_true', help='no progress bar')
    p.set_defaults(func=data_commands.cmd_replay)

    add_baseline_commands(sub)

    p = sub.add_parser('make-sample-bags', help='write the simulated sample bags')
    p.add_argument('--out', required=True, metavar='DIR', help='output folder')
    p.add_argument('--seed', type=SEED, default=0, metavar='N', help='random seed (default 0)')
    p.add_argument('--duration-s', type=bounded_float('--duration-s', 1.0, 86400.0),
                   default=75.0, metavar='S', help='length of each bag [s] (default 75)')
    _add_pump(p)
    p.set_defaults(func=data_commands.cmd_make_sample_bags)

    p = sub.add_parser('calibrate', help='fit the open friction parameters to data')
    p.add_argument('inputs', nargs='+', metavar='INPUT',
                   help='bench CSV files (speed_rpm, pressure_bar, torque_nm[, viscosity_cst '
                   '| temperature_c]) or rosbag2 bags')
    p.add_argument('--pump', required=True, metavar='BASE.yaml', help='base pump file')
    p.add_argument('--out', required=True, metavar='MY_PUMP.yaml', help='calibrated pump file')
    p.add_argument('--report', metavar='DIR', default=None,
                   help='report.json, report.txt and PNG plots')
    p.add_argument('--fix', nargs='+', default=[], metavar='NAME',
                   help='hold these at their base values: ' + ', '.join(FIT_NAMES))
    p.add_argument('--params', metavar='FILE', action='append', default=None,
                   help='node parameters (bags: topics, filter; oil; inertia and drive loss '
                   'start values); may be given several times, later files overriding')
    p.add_argument('--topic-remap', nargs='+', default=[], metavar='OLD:=NEW',
                   help="bags: the node's topic OLD is NEW in the bag")
    p.add_argument('--whole-record', action='store_true',
                   help='bags: fit friction on every sample, not only near-steady ones')
    p.add_argument('--force', action='store_true', help='replace an existing output file')
    p.set_defaults(func=data_commands.cmd_calibrate)

    p = sub.add_parser('evaluate-monitor', help='scenario bank: false alarms, detection '
                       'delay, attribution and coverage of the wear monitor')
    p.add_argument('--quick', action='store_true', help='the small bank of the test suite '
                   '(default: the benchmark, >= 10 h of nominal running)')
    p.add_argument('--workers', type=bounded_int('--workers', 1, 1024),
                   default=os.cpu_count() or 1, metavar='N',
                   help='parallel processes (default: CPU count); same records for any N')
    p.add_argument('--out', metavar='DIR', default=None,
                   help='folder for records.csv, figures.json, table.md and PNG plots')
    p.add_argument('--force', action='store_true',
                   help="replace an existing --out folder of this command's outputs")
    p.add_argument('--seed', type=SEED, default=0, metavar='N', help='bank seed (default 0)')
    p.add_argument('--quiet', action='store_true', help='no progress bar')
    instead = p.add_mutually_exclusive_group()
    instead.add_argument('--next-morning', action='store_true', help='instead: the cold '
                         'starts without temperature topic again a day later, from the first '
                         "day's state")
    instead.add_argument('--held-out', action='store_true', help='instead: what the bank '
                         'holds out, no number set on it: four realistic duty cycles (ramps, '
                         'jerky moves, long dwells, a thermostat oil without topic) with every '
                         'realistic fault, and five faults (spherical joints, piston heads, '
                         'pressure gain, torque offset, drive loss) on every realistic family')
    p.set_defaults(func=data_commands.cmd_evaluate_monitor)

    p = sub.add_parser('plot', help="PNG figures in the manner of the paper's")
    p.add_argument('--out', required=True, metavar='DIR', help='output folder')
    p.add_argument('--force', action='store_true', help='replace an earlier --out folder of '
                   'PNG figures')
    _add_pump(p)
    p.set_defaults(func=_cmd_plot)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """
    Run the ``pump_friction`` command line.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit code: 0 on success, 2 on a bad argument, input or output, 130 on Ctrl-C, 143
        on SIGTERM.

    """
    argv = list(sys.argv[1:] if argv is None else argv)
    stdout, sys.stdout = sys.stdout, GuardedStdout(sys.stdout)  # a print never stops a write
    try:
        code = _run(argv)
    finally:
        guarded, sys.stdout = sys.stdout, stdout
    lost = guarded.finish() if isinstance(guarded, GuardedStdout) else ''
    return _fail(lost) if lost and code == 0 else code


def _run(argv: list[str]) -> int:
    """Run one command; every failure is one line and an exit code (`main`)."""
    bad = non_utf8_argument(argv)
    if bad:  # it would reach a file's provenance, which is UTF-8 text
        return _fail(f"argument '{bad}' is not valid UTF-8 (a file name in another "
                     'encoding?): rename it')
    try:
        sigint_kept()  # in the try: a Ctrl-C from here on is one line (entry: before)
        args = build_parser().parse_args(argv)
        code = args.func(args)
        raise_if_interrupted()  # a Ctrl-C swallowed where nothing checked: still 130
        return code
    except PumpFrictionError as exc:
        return _fail(str(exc))
    except BrokenPipeError:  # e.g. piped into head
        return 0
    except KeyboardInterrupt:  # every output is staged: discarded on the way up
        return _interrupted()
    except OSError as exc:  # the environment (disk full, permissions) rather than the input
        where = f': {exc.filename}' if exc.filename else ''
        return _fail(f'{exc.strerror or type(exc).__name__}{where}')


def _interrupted() -> int:
    """Report a Ctrl-C (130) or a SIGTERM (143) in one line (`interrupts.sigint_ignored`)."""
    sigint_ignored()  # a Ctrl-C still pending must not kill us while we report the first
    done = committed_outputs()  # complete and in place: said, or they look discarded
    after = f' after writing {", ".join(done)} (complete; nothing else was written)' \
        if done else ''
    if stop_signal() == signal.SIGTERM:
        print(f'pump_friction: terminated{after}', file=sys.stderr)
        return 128 + signal.SIGTERM
    print(f'pump_friction: interrupted{after}', file=sys.stderr)
    return 130


def _fail(message: str) -> int:
    """Print one error line on stderr and return exit code 2."""
    print(f'pump_friction: error: {" ".join(message.split())}', file=sys.stderr)
    return 2


if __name__ == '__main__':
    sys.exit(main())
