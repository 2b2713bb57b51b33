"""Command line ``pump_friction``: the paper's units (rpm, bar, cSt) live here and only here."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from .errors import PumpFrictionError
from .model import COMPONENTS, PumpModel
from .params import load_pump
from .units import (
    CC_TO_M3,
    MM_TO_M,
    bar_to_pa,
    cst_to_m2_s,
    rpm_to_rad_s,
)

__all__ = ['main']

MAX_SPEED_RPM = 100_000.0
MAX_PRESSURE_BAR = 2_000.0
MAX_VISCOSITY_CST = 10_000.0


class UsageError(PumpFrictionError):
    """A bad command-line argument."""


class _Parser(argparse.ArgumentParser):
    """Argument parser that reports a bad argument in one line and exits with code 2."""

    def error(self, message: str) -> None:
        """Raise `UsageError` instead of printing usage and exiting."""
        raise UsageError(f'{message} (see {self.prog} --help)')


def _bounded_float(name: str, low: float, high: float) -> Callable[[str], float]:
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f'{name} must be a number, got {text!r}') from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f'{name} must be finite, got {text!r}')
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f'{name} must be in [{low:g}, {high:g}], '
                                             f'got {value:g}')
        return value

    return parse


_speed = _bounded_float('--speed-rpm', -MAX_SPEED_RPM, MAX_SPEED_RPM)
_pressure = _bounded_float('--pressure-bar', -MAX_PRESSURE_BAR, MAX_PRESSURE_BAR)
_viscosity = _bounded_float('--viscosity-cst', 1e-3, MAX_VISCOSITY_CST)


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
    from .paper import format_checks, paper_checks

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
    """Revolution-mean torques of one operating point, keyed as in ``torque --json``.

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


def table_record(table, speed_rad_s: float, pressure_pa: float,
                 viscosity_m2_s: float) -> tuple[dict[str, float | None], int]:
    """Torques of one operating point from a friction table, keyed as `torque_record`.

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
        from .table import describe_flags, load_table

        record, flags = table_record(load_table(args.table, params), speed, pressure, viscosity)
        if flags:
            print(f'pump_friction: warning: {describe_flags(flags)}: clamped to the table\'s '
                  'edge', file=sys.stderr)
        source = f'table {args.table}'
    else:
        record = torque_record(PumpModel(params), speed, pressure, viscosity)
        source = 'full model'
    _print_record(record, f'{params.name}: {args.speed_rpm:g} rpm, {args.pressure_bar:g} bar, '
                  f'{source} (torques in N*m, signed)', args.json)
    return 0


def _cmd_build_table(args: argparse.Namespace) -> int:
    from . import MODEL_VERSION
    from .progress import ProgressBar
    from .table import TableSpec, build_table, cache_dir

    params = load_pump(args.pump)
    spec = TableSpec(max_speed_rad_s=rpm_to_rad_s(args.max_speed_rpm),
                     max_pressure_pa=bar_to_pa(args.max_pressure_bar),
                     min_viscosity_m2_s=cst_to_m2_s(args.viscosity_cst[0]),
                     max_viscosity_m2_s=cst_to_m2_s(args.viscosity_cst[1]))
    out = Path(args.out) if args.out else (
        cache_dir() / f'{params.name}-{params.sha256[:16]}-m{MODEL_VERSION}.npz')
    with ProgressBar('building table', enabled=not args.quiet) as bar:
        table = build_table(params, spec, progress=bar)
    table.save(out)
    shape = 'x'.join(str(n) for n in table.torque_nm.shape[:-1])
    print(f'{out}: {shape} grid (mode x speed x pressure x viscosity), '
          f'{table.metadata["build_seconds"]:.2f} s, pump {params.name} '
          f'sha256 {params.sha256[:12]}')
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
    from .plots import write_model_figures

    model = _model(args)
    for path in write_model_figures(model, Path(args.out)):
        print(path)
    return 0


def _cmd_replay(args: argparse.Namespace) -> int:
    from .bags import parse_remaps
    from .config import load_estimator_config
    from .params import config_dir
    from .replay import ReplayJob, discover_bags, fleet_table, run_jobs

    config = load_estimator_config(args.params or config_dir() / 'torque_estimator.yaml')
    remaps = tuple(parse_remaps(args.topic_remap).items())
    bags = discover_bags(args.bags)
    single = len(bags) == 1
    if args.workers < 1:
        raise UsageError('--workers must be >= 1')

    def target(base: str | None, bag: Path, suffix: str) -> str | None:
        if base is None:
            return None
        return base if single else str(Path(base) / f'{bag.name}{suffix}')

    jobs = [ReplayJob(bag=str(bag), config=config, out_bag=target(args.out, bag, ''),
                      csv_path=target(args.csv, bag, '.csv'),
                      plots_dir=target(args.plots, bag, ''), remaps=remaps,
                      storage=args.storage, force=args.force,
                      progress=single and not args.quiet and not args.dask)
            for bag in bags]
    summaries = run_jobs(jobs, workers=args.workers, dask_address=args.dask)
    if single:
        summary = summaries[0]
        if summary.error:
            raise PumpFrictionError(summary.error)
        print(summary.format())
        return 0
    for summary in summaries:
        print(summary.format().splitlines()[0] if summary.error else
              f'{summary.bag}: {summary.duration_s:.1f} s, {summary.estimates} estimates, '
              f'alarm {summary.alarm_s:.1f} s, max valve-plate scale '
              f'{summary.max_valve_plate_scale:.3f}')
    print()
    print(fleet_table(summaries))
    return 2 if any(s.error for s in summaries) else 0


def _cmd_make_sample_bags(args: argparse.Namespace) -> int:
    from .samples import make_sample_bags

    for path in make_sample_bags(args.out, seed=args.seed, pump_file=args.pump,
                                 duration_s=args.duration_s):
        print(path)
    return 0


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from .bags import parse_remaps
    from .calibrate import calibrate
    from .config import load_estimator_config
    from .params import config_dir

    config = load_estimator_config(args.params or config_dir() / 'torque_estimator.yaml')
    result = calibrate(args.inputs, args.pump, args.out, report_dir=args.report, fix=args.fix,
                       config=config, remaps=parse_remaps(args.topic_remap),
                       steady_only=not args.whole_record, force=args.force)
    print(result.format())
    return 0


def _add_pump(parser: argparse.ArgumentParser) -> None:
    parser.add_argument('--pump', metavar='FILE', default=None,
                        help='pump parameter YAML (default: config/pumps/hong_doh_2004.yaml)')


def _add_viscosity(parser: argparse.ArgumentParser) -> None:
    parser.add_argument('--viscosity-cst', type=_viscosity, default=None, metavar='CST',
                        help='oil kinematic viscosity [cSt] (default: the pump file\'s)')


def build_parser() -> argparse.ArgumentParser:
    """Build the ``pump_friction`` argument parser.

    Returns
    -------
    argparse.ArgumentParser
        Parser with one sub-command per job.
    """
    parser = _Parser(prog='pump_friction',
                     description='Bent-axis pump friction model (Hong & Doh 2004).')
    sub = parser.add_subparsers(dest='command', required=True, parser_class=_Parser)

    p = sub.add_parser('paper-check', help='the paper\'s numbers next to the model\'s')
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
    p.add_argument('--max-speed-rpm', type=_bounded_float('--max-speed-rpm', 100.0,
                                                          MAX_SPEED_RPM), default=12000.0,
                   metavar='N', help='speed envelope [rpm] (default 12000)')
    p.add_argument('--max-pressure-bar', type=_bounded_float('--max-pressure-bar', 1.0,
                                                             MAX_PRESSURE_BAR), default=350.0,
                   metavar='P', help='pressure-difference envelope [bar] (default 350)')
    p.add_argument('--viscosity-cst', type=_viscosity, nargs=2, default=[10.0, 100.0],
                   metavar=('LOW', 'HIGH'), help='viscosity range [cSt] (default 10 100)')
    p.add_argument('--quiet', action='store_true', help='no progress bar')
    p.set_defaults(func=_cmd_build_table)

    p = sub.add_parser('kinematics', help='stroke, displacement, piston speeds and forces')
    p.add_argument('--speed-rpm', type=_speed, required=True, metavar='N',
                   help='shaft speed [rpm], signed')
    p.add_argument('--pressure-bar', type=_pressure, default=0.0, metavar='P',
                   help='pressure difference [bar] for the forces (default 0)')
    _add_viscosity(p)
    _add_pump(p)
    p.add_argument('--json', action='store_true', help='machine-readable output')
    p.set_defaults(func=_cmd_kinematics)

    p = sub.add_parser('replay', help='the node\'s outputs from rosbag2 bags')
    p.add_argument('bags', nargs='+', metavar='BAG',
                   help='bag directories (sqlite3 or mcap), or folders holding bags')
    p.add_argument('--params', metavar='FILE', default=None,
                   help='node parameters file (default: the package\'s '
                   'config/torque_estimator.yaml, as the launch file uses)')
    p.add_argument('--out', metavar='OUT_BAG', default=None,
                   help='output bag (several bags: a folder, one bag each)')
    p.add_argument('--csv', metavar='FILE', default=None,
                   help='CSV, one row per estimate (several bags: a folder)')
    p.add_argument('--plots', metavar='DIR', default=None, help='folder for PNG plots')
    p.add_argument('--topic-remap', nargs='+', default=[], metavar='OLD:=NEW',
                   help='the node\'s topic OLD is NEW in the bag')
    p.add_argument('--storage', choices=('sqlite3', 'mcap'), default=None,
                   help='output bag storage (default: the input\'s)')
    p.add_argument('--force', action='store_true', help='replace existing outputs')
    p.add_argument('--workers', type=int, default=os.cpu_count() or 1, metavar='N',
                   help='parallel local processes for several bags (default: CPU count)')
    p.add_argument('--dask', metavar='ADDRESS', default=None,
                   help='run the bags on this Dask scheduler (extra [fleet])')
    p.add_argument('--quiet', action='store_true', help='no progress bar')
    p.set_defaults(func=_cmd_replay)

    p = sub.add_parser('make-sample-bags', help='write the simulated sample bags')
    p.add_argument('--out', required=True, metavar='DIR', help='output folder')
    p.add_argument('--seed', type=int, default=0, metavar='N', help='random seed (default 0)')
    p.add_argument('--duration-s', type=_bounded_float('--duration-s', 1.0, 86400.0),
                   default=75.0, metavar='S', help='length of each bag [s] (default 75)')
    _add_pump(p)
    p.set_defaults(func=_cmd_make_sample_bags)

    p = sub.add_parser('calibrate', help='fit the open friction parameters to data')
    p.add_argument('inputs', nargs='+', metavar='INPUT',
                   help='bench CSV files (speed_rpm, pressure_bar, torque_nm[, viscosity_cst '
                   '| temperature_c]) or rosbag2 bags')
    p.add_argument('--pump', required=True, metavar='BASE.yaml', help='base pump file')
    p.add_argument('--out', required=True, metavar='MY_PUMP.yaml', help='calibrated pump file')
    p.add_argument('--report', metavar='DIR', default=None, help='report.json and PNG plots')
    p.add_argument('--fix', nargs='+', default=[], metavar='NAME',
                   help='hold these at their base values (see README)')
    p.add_argument('--params', metavar='FILE', default=None,
                   help='node parameters (bags: topics, filter; oil; inertia and drive loss '
                   'start values)')
    p.add_argument('--topic-remap', nargs='+', default=[], metavar='OLD:=NEW')
    p.add_argument('--whole-record', action='store_true',
                   help='bags: fit friction on every sample, not only near-steady ones')
    p.add_argument('--force', action='store_true', help='replace an existing output file')
    p.set_defaults(func=_cmd_calibrate)

    p = sub.add_parser('plot', help='PNG figures in the manner of the paper\'s')
    p.add_argument('--out', required=True, metavar='DIR', help='output folder')
    _add_pump(p)
    p.set_defaults(func=_cmd_plot)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``pump_friction`` command line.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit code: 0 on success, 2 on a bad argument or input file.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        return args.func(args)
    except PumpFrictionError as exc:
        print(f'pump_friction: error: {exc}', file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. piped into head
        return 0


if __name__ == '__main__':
    sys.exit(main())
