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

"""Sub-commands on data: replay (bags, fleets), sample bags, calibration, monitor bank."""

from __future__ import annotations

import argparse
from contextlib import nullcontext
from pathlib import Path

from ..core.node_parameters import EstimatorConfig
from ..errors import PumpFrictionError, UsageError

__all__ = ['cmd_build_table', 'cmd_calibrate', 'cmd_evaluate_monitor', 'cmd_make_sample_bags',
           'cmd_replay', 'estimator_config']


def cmd_replay(args: argparse.Namespace) -> int:
    """Run ``pump_friction replay``: one bag, or a fleet and its table."""
    from ..bags.fleet import (
        discover_bags,
        fleet_table,
        output_names,
        plan_outputs,
        ReplayJob,
        run_jobs,
    )
    from ..bags.reader import parse_remaps

    config = estimator_config(args)
    remaps = tuple(parse_remaps(args.topic_remap).items())
    if args.workers < 1:
        raise UsageError('--workers must be >= 1')
    bags = discover_bags(args.bags)
    notes: list[str] = []
    configs = [bag_config(bag, args, config, notes) for bag in bags]
    single = len(bags) == 1
    labels = [bag.name for bag in bags] if single else output_names(bags)
    plan = plan_outputs(bags, args.out, args.csv, args.plots)
    baseline = str(Path(args.baseline).expanduser().resolve()) if args.baseline else None
    if baseline is not None:
        from ..core.baseline_file import read_baseline

        read_baseline(Path(baseline))  # unreadable: one line before any bag is replayed
        notes.append(f'the wear monitor started from the baseline file {baseline}')
    jobs = [ReplayJob(bag=str(bag.resolve()), config=cfg, out_bag=out, csv_path=csv,
                      plots_dir=plots, remaps=remaps, storage=args.storage,
                      compression=args.compression, force=args.force,
                      progress=single and not args.quiet and not args.dask, label=label,
                      baseline=baseline)
            for bag, cfg, out, csv, plots, label in zip(bags, configs, plan.out_bags,
                                                        plan.csv_paths, plan.plots_dirs,
                                                        labels, strict=True)]
    try:
        summaries = run_jobs(jobs, workers=args.workers, dask_address=args.dask)
    finally:
        plan.remove_empty()  # folders made for the fleet that no bag wrote into
    if single:
        summary = summaries[0]
        if summary.error:  # one line; the notes (files used, baseline started from) are moot
            raise PumpFrictionError(summary.error)
        for note in notes:
            print(note)
        print(summary.formatted())
        return 0
    for note in notes:
        print(note)
    for summary in summaries:
        if summary.error:
            print(f'{summary.label}: FAILED: {summary.error}')
            continue
        alarm = (f'first alarm {summary.alarm_onset_s:.1f} s' if summary.alarm_s
                 else 'no alarm')
        print(f'{summary.label}: {summary.duration_s:.1f} s, {summary.estimates} estimates, '
              f'{alarm}, valve-plate scale {summary.final_valve_plate_scale:.3f} at the end'
              + ''.join(f', {kind} {path}' for kind, path in summary.outputs.items())
              + summary.skipped() + (f', {summary.stale_note()}' if summary.stale_ticks
                                     else ''))
    print()
    print(fleet_table(summaries))
    failed = [s.label for s in summaries if s.error]
    if failed:  # the table says why: the error line says that it did
        raise PumpFrictionError(f'{len(failed)} of {len(summaries)} bags failed: '
                                f'{", ".join(failed)} (why: above)')
    return 0


def bag_config(bag: Path, args: argparse.Namespace, config: EstimatorConfig,
               notes: list[str]) -> EstimatorConfig:
    """
    Return a bag's node parameters: its own ``node_params.yaml``, then the ``--params`` files.

    The parameters of the installation a bag was recorded on travel with the bag
    (`config.BAG_PARAMS_FILE` in its folder); files given with ``--params`` override them.
    Said in the output, so that nothing changes the model silently.

    Parameters
    ----------
    bag : Path
        The bag folder.
    args : argparse.Namespace
        The command line (``params``).
    config : EstimatorConfig
        The parameters without the bag's file.
    notes : list of str
        Gets a line saying which files were used, printed with the replay's summary.

    Returns
    -------
    EstimatorConfig
        The parameters to replay the bag with.

    """
    from ..core.node_parameters import BAG_PARAMS_FILE, load_estimator_config

    own = bag / BAG_PARAMS_FILE
    if not (own.exists() or own.is_symlink()):  # a folder or a dangling link: an error below
        return config
    given = f', then {", ".join(map(str, args.params))}' if args.params else ''
    notes.append(f'{bag}: node parameters from {own} (recorded with the bag){given}')
    return load_estimator_config([own, *(args.params or [])])


def estimator_config(args: argparse.Namespace) -> EstimatorConfig:
    """Return the node parameters: ``--params`` files (later ones override) over defaults."""
    from ..core.node_parameters import load_estimator_config

    return load_estimator_config(args.params or None)


def cmd_make_sample_bags(args: argparse.Namespace) -> int:
    """Run ``pump_friction make-sample-bags``."""
    from ..sim.sample_bags import make_sample_bags

    for path in make_sample_bags(args.out, seed=args.seed, pump_file=args.pump,
                                 duration_s=args.duration_s):
        print(path)
    return 0


def cmd_calibrate(args: argparse.Namespace) -> int:
    """Run ``pump_friction calibrate``."""
    from ..bags.reader import parse_remaps
    from ..calibration import calibrate

    config = estimator_config(args)
    result = calibrate(args.inputs, args.pump, args.out, report_dir=args.report, fix=args.fix,
                       config=config, remaps=parse_remaps(args.topic_remap),
                       steady_only=not args.whole_record, force=args.force)
    print(result.formatted())
    return 0


def cmd_evaluate_monitor(args: argparse.Namespace) -> int:
    """Run ``pump_friction evaluate-monitor``: the wear monitor's evaluation bank."""
    from ..evaluation.command import evaluate_monitor

    return evaluate_monitor(quick=args.quick, workers=args.workers, out=args.out,
                            seed=args.seed, progress=not args.quiet,
                            next_morning=args.next_morning, force=args.force,
                            held_out=args.held_out)


def cmd_build_table(args: argparse.Namespace) -> int:
    """Run ``pump_friction build-table``: into the cache, or into ``--out``."""
    from ..physics.pump_parameters import load_pump
    from ..physics.units import bar_to_pa, cst_to_m2_s, rpm_to_rad_s
    from ..progress import ProgressBar
    from ..staging import StagedOutputs
    from ..table.friction_table import build_table, TableSpec
    from ..table.table_files import cached_table_path

    params = load_pump(args.pump)
    base = TableSpec(max_speed_rad_s=rpm_to_rad_s(args.max_speed_rpm),
                     max_pressure_pa=bar_to_pa(args.max_pressure_bar))
    if args.viscosity_cst is None:  # what the node builds with its default parameters
        from ..core.oil_range import table_spec_for

        spec = table_spec_for(EstimatorConfig(), params.oil.viscosity_m2_s, base)
    else:
        low_cst, high_cst = args.viscosity_cst
        if not low_cst < high_cst:  # said in the units given, not after conversion
            raise UsageError(f'argument --viscosity-cst: LOW must be below HIGH, got {low_cst:g} '
                             f'{high_cst:g} (see pump_friction build-table --help)')
        spec = base.covering(cst_to_m2_s(low_cst), cst_to_m2_s(high_cst))
    outputs = StagedOutputs()
    try:
        if args.out:  # checked and made before the build; moved into place at the end
            staged = outputs.add(args.out, args.force, False, flag='--out')
            out, path = staged.target, staged.path
        else:  # the cache is rebuilt in place (it is a cache; saved atomically)
            out = path = cached_table_path(params, spec)
        with ProgressBar('building table', enabled=not args.quiet) as bar:
            table = build_table(params, spec, progress=bar)
        with staged.writing() if args.out else nullcontext():
            table.save(path)
        outputs.commit()
    except BaseException:
        outputs.discard()
        raise
    shape = 'x'.join(str(n) for n in table.torque_nm.shape[:-1])
    print(f'{out}: {shape} grid (mode x speed x pressure x viscosity), '
          f'{table.metadata["build_seconds"]:.2f} s, pump {params.name} '
          f'sha256 {params.sha256[:12]}')
    return 0
