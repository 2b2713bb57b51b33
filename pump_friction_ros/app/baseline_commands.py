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

"""Sub-commands on the healthy baseline file: ``learn-baseline`` and ``reset-baseline``."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from ..errors import BaselineError, OutputError, UsageError

__all__ = ['add_baseline_commands', 'cmd_learn_baseline', 'cmd_reset_baseline']


def add_baseline_commands(sub: Any) -> None:
    """
    Add ``learn-baseline`` and ``reset-baseline`` to the ``pump_friction`` sub-parsers.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The main parser's sub-parsers (one-line errors, no abbreviations).

    """
    p = sub.add_parser('learn-baseline', help="the wear monitor's healthy baseline file "
                       'from healthy bags')
    p.add_argument('bags', nargs='+', metavar='BAG',
                   help='healthy bags of one installation, in time order (or folders of '
                   'them)')
    p.add_argument('--params', metavar='FILE', action='append', default=None,
                   help="the node's parameters files, as for replay (later files override); "
                   'the node must run with the same ones to use the baseline')
    p.add_argument('--out', required=True, metavar='FILE',
                   help="baseline file to write (the node's baseline_file)")
    p.add_argument('--baseline', metavar='FILE', default=None,
                   help='go on learning from this baseline file')
    p.add_argument('--topic-remap', nargs='+', default=[], metavar='OLD:=NEW',
                   help="the node's topic OLD is NEW in the bags")
    p.add_argument('--force', action='store_true', help='replace an existing --out file')
    p.add_argument('--quiet', action='store_true', help='no progress bar')
    p.set_defaults(func=cmd_learn_baseline)

    p = sub.add_parser('reset-baseline', help='move a baseline file aside (.bak) so that the '
                       'node re-learns it after a repair')
    p.add_argument('file', metavar='FILE', help='the baseline file')
    p.add_argument('--force', action='store_true',
                   help='move it aside even when it is unreadable or not a baseline file')
    p.set_defaults(func=cmd_reset_baseline)


def cmd_learn_baseline(args: argparse.Namespace) -> int:
    """
    Run ``pump_friction learn-baseline``: replay healthy bags, write the baseline file.

    The bags are replayed in the order given through one wear monitor, as if the node had
    run through them with restarts in between (each bag's own ``node_params.yaml``, then
    the ``--params`` files, as the replay does); they must agree on the provenance.

    Parameters
    ----------
    args : argparse.Namespace
        The command line.

    Returns
    -------
    int
        0.

    """
    from .data_commands import bag_config, estimator_config
    from ..bags.fleet import discover_bags, refuse_repeats
    from ..bags.reader import parse_remaps
    from ..bags.replay import replay_bag
    from ..core.baseline_disk import writable_folder
    from ..core.baseline_file import (
        baseline_document,
        provenance,
        provenance_differences,
        read_baseline,
        restore_baseline,
        write_baseline,
    )
    from ..core.estimator_setup import estimator_from_config
    from ..interrupts import note_committed
    from ..staging import refuse_at_inputs

    out = Path(args.out).expanduser().absolute()
    if out.is_dir():
        raise OutputError(f'--out {out} is a folder; give the baseline file')
    if out.exists() and not args.force:
        raise OutputError(f'--out {out} exists (--force replaces it)')
    config = estimator_config(args)
    remaps = parse_remaps(args.topic_remap)
    bags = discover_bags(args.bags)
    refuse_repeats(bags)  # learnt twice, its running would weigh double
    refuse_at_inputs('--out', out, bags)  # --force would write into a bag
    writable_folder(out)  # before the bags are replayed: a bad path fails at once
    document: dict[str, Any] | None = None
    source = Path(args.baseline) if args.baseline else None
    if source is not None:
        document = read_baseline(source)
    # the time learnt up to: each bag should begin after it (header stamps, which the file
    # holds, may lead the log times by max_stamp_lead_s)
    learnt_until_ns = int(document['learnt'].get('last_stamp_ns') or 0) if document else 0
    lead_ns = round(config.max_stamp_lead_s * 1e9)
    created = str(document.get('created_utc', '')) if document else ''
    origin = 'pump_friction learn-baseline ' + ' '.join(str(b.resolve()) for b in bags)
    reference: tuple[Path, dict[str, Any]] | None = None
    notes: list[str] = []
    status = ''  # the baseline's after the last bag
    for bag in bags:
        cfg = bag_config(bag, args, config, notes)
        core = estimator_from_config(cfg)
        here = provenance(core)
        if reference is None:
            reference = (bag, here)
        else:
            differences = provenance_differences(reference[1], here)
            if differences:
                raise UsageError(f'{bag}: other pump, table or parameters than {reference[0]}:'
                                 f' {"; ".join(differences)}; learn one baseline per '
                                 'installation')
        if document is not None:
            restore_baseline(core, document, source or bags[0])
        summary = replay_bag(bag, cfg, remaps=remaps, progress=not args.quiet, core=core)
        if summary.span_ns[0] + lead_ns < learnt_until_ns:  # sim time from 0 each run, a
            # copy of a bag: learnt from all the same (a simulation's runs are not repeats)
            notes.append(f'note: {bag} begins at {summary.span_ns[0] * 1e-9:.3f} s, before '
                         f'what was learnt ends ({source}: {learnt_until_ns * 1e-9:.3f} s); '
                         'learnt from all the same: if it is a copy of running already '
                         'learnt, that running weighs double')
        learnt_until_ns = max(learnt_until_ns, summary.span_ns[1])
        document, source = baseline_document(core, created, origin), bag
        alarm = ('; WARN or ERROR while learning: is this bag healthy?'
                 if summary.warn_intervals or summary.error_intervals else '')
        print(f'{bag}: {summary.duration_s:.1f} s, {summary.counts.get("monitor_samples", 0)} '
              f'monitored samples{summary.skipped()}{alarm}')
        status = core.monitor.baseline_status()
    for note in notes:
        print(note)
    learnt = document['learnt'] if document else {'samples': 0}
    if document is None or not learnt['samples']:
        raise BaselineError('nothing learnt: no monitored running in the bags (|speed| above '
                            'monitor_min_speed_rad_s, with a measured torque)')
    write_baseline(out, document)
    note_committed(out)
    first, last = learnt['first_stamp_ns'] * 1e-9, learnt['last_stamp_ns'] * 1e-9
    print(f'{out}: {learnt["samples"]} monitored samples, stamps {first:.3f} to {last:.3f} s, '
          f'pump {document["provenance"]["pump"]["name"]}: {status}')
    return 0


def cmd_reset_baseline(args: argparse.Namespace) -> int:
    """
    Run ``pump_friction reset-baseline``: move the file aside, so the node re-learns.

    Parameters
    ----------
    args : argparse.Namespace
        The command line.

    Returns
    -------
    int
        0.

    """
    from ..core.baseline_disk import archive_baseline
    from ..core.baseline_file import read_baseline
    from ..interrupts import note_committed

    path = Path(args.file).expanduser().absolute()
    if not path.is_file():
        raise BaselineError(f'baseline file not found: {path}' if not path.exists()
                            else f'{path} is not a file')
    try:
        read_baseline(path)
    except BaselineError as exc:
        if not args.force:
            raise BaselineError(f'{exc}; --force moves it aside all the same') from None
    archived = archive_baseline(path)
    if archived is None:
        raise BaselineError(f'baseline file not found: {path} (it went away before it was '
                            'moved aside)')
    note_committed(archived)
    print(f'{path} moved to {archived}: the node learns a new baseline from its next start '
          '(a running node: call its ~/reset_monitor service instead, or it writes its '
          'state back)')
    return 0
