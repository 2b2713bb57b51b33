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
The issue's floors, on the runs they are stated for, and why the others are not.

Issue #17 states its detection and naming floors "per family where the fault's torque
exceeds the CUSUM allowance while running". A fault run is **in scope** where

* the torque the fault adds at its full size, averaged over the running samples after the
  onset (``RunRecord.fault_running_nm``, from the simulation's truth), exceeds the run's
  CUSUM allowance k (``allowance_nm``): at or below it a CUSUM's input does not exceed k on
  average, by design (the issue's condition);
* and the healthy baseline was learnt before the onset (``baseline_learnt_s``; this
  module's condition, not the issue's: a fault that commissioning saw is part of the
  healthy signature, not a change from it, and a baseline never learnt detects nothing).

`floor_figures` counts, per fault and family, the runs in scope and the reason for each
run out of it, and states the floors (`settings.FLOORS`) on the runs in scope:

* the p90 of the monitored running from the onset to detection, beside a reference
  figure, h / (dT - k): the running a CUSUM needs to reach its WARN threshold h on a
  constant input dT, the fault's running torque (the monitor's sums run on the residual
  projected on each cause's signature, with the baseline's margin taken off: a guide to
  the order of magnitude, not a bound);
* valve-plate faults named valve plate, and `cannot tell` (shares of the runs in scope,
  an undetected run counting as not named);
* other faults named valve plate, and each named as its class should be
  (``settings.ACCEPTED_ATTRIBUTIONS``: a torque-constant change `not friction`).

`format_floors` prints them as a Markdown table. A record without the fields (written
before they were kept) counts as in scope.
"""

from __future__ import annotations

from collections.abc import Sequence
import math
from typing import Any

from .bank import RunRecord
from .report import nearest_rank, table_order
from .settings import ACCEPTED_ATTRIBUTIONS, ALL_FAMILIES, FAULTS, FLOORS

__all__ = ['floor_figures', 'format_floors', 'in_scope', 'reference_delay_s', 'scope_reason']


def scope_reason(record: RunRecord) -> str:
    """
    Return why a fault run is outside the floors' scope, or '' where it is inside.

    Parameters
    ----------
    record : RunRecord
        A run (the nominal pump's runs have no scope: 'nominal').

    Returns
    -------
    str
        '' (in scope), 'nominal', 'never learnt' (no healthy baseline by the end),
        'learnt late' (the baseline was learnt after the onset: the fault is in it) or
        'below k' (the fault's running torque is at or below the allowance). Unknown
        fields (NaN) do not take a run out.

    """
    if record.truth_class == 'nominal':
        return 'nominal'
    if record.baseline_learnt_s == math.inf:
        return 'never learnt'
    if record.baseline_learnt_s > record.onset_s:
        return 'learnt late'
    if record.fault_running_nm <= record.allowance_nm:
        return 'below k'
    return ''


def in_scope(record: RunRecord) -> bool:
    """Return whether a fault run is one the issue's floors are stated for."""
    return scope_reason(record) == ''


def reference_delay_s(record: RunRecord) -> float:
    """
    Return the running a CUSUM needs to reach WARN on a constant input of the fault [s].

    A sum fed dT - k per second of running, dT the fault's running torque and k the
    allowance, reaches the WARN threshold h after h / (dT - k): a reference for the
    detection delays (the monitor's sums run on the residual projected on each cause's
    signature, less the baseline's margin; a fault above its mean in places is seen
    sooner), not a bound.

    Parameters
    ----------
    record : RunRecord
        A fault run.

    Returns
    -------
    float
        h / (dT - k) [s]; inf where dT <= k, NaN where dT or h is unknown.

    """
    excess = record.fault_running_nm - record.allowance_nm
    if math.isnan(excess) or math.isnan(record.warn_nm_s):
        return math.nan
    return record.warn_nm_s / excess if excess > 0.0 else math.inf


def _p90(values: list[float]) -> float:
    return nearest_rank([v for v in values if not math.isnan(v)], 90.0)


def floor_figures(records: Sequence[RunRecord]) -> dict[str, Any]:
    """
    Reduce a bank's fault runs to the floors on the runs in scope.

    Parameters
    ----------
    records : sequence of RunRecord
        The runs (nominal runs are left out).

    Returns
    -------
    dict
        ``faults`` -> fault -> family (and 'all') -> dict with ``runs``, ``in_scope``,
        ``never_learnt``, ``learnt_late``, ``below_k``, ``not_detected`` (in scope),
        ``monitored_delay_p90_s`` (in scope; inf where more than a tenth were missed),
        ``reference_delay_p90_s`` (the same percentile of `reference_delay_s`, in scope, where
        known), ``named`` (in scope, named as its class should be), ``named_vp`` (in
        scope, named valve plate), ``cannot_tell`` (in scope), ``fault_nm_min`` /
        ``fault_nm_max`` (the fault's running torque over all the runs [N m]);
        ``classes`` -> fault -> its true class; ``families``: 'all' and the families, in
        table order. Named: as ``settings.ACCEPTED_ATTRIBUTIONS``
        accepts for the fault's class.

    """
    faults = [r for r in records if r.truth_class != 'nominal']
    families = table_order({r.family for r in faults}, [f.name for f in ALL_FAMILIES])
    names = table_order({r.fault for r in faults}, [f.name for f in FAULTS])
    out: dict[str, Any] = {'faults': {}, 'classes': {}, 'families': ['all', *families]}
    for name in names:
        runs = [r for r in faults if r.fault == name]
        out['classes'][name] = runs[0].truth_class
        out['faults'][name] = {}
        for family in out['families']:
            mine = [r for r in runs if family in (r.family, 'all')]
            if not mine:
                continue
            reasons = [scope_reason(r) for r in mine]
            scoped = [r for r, why in zip(mine, reasons, strict=True) if not why]
            torques = [r.fault_running_nm for r in mine if math.isfinite(r.fault_running_nm)]
            right = ACCEPTED_ATTRIBUTIONS[mine[0].truth_class]
            out['faults'][name][family] = {
                'runs': len(mine), 'in_scope': len(scoped),
                'never_learnt': reasons.count('never learnt'),
                'learnt_late': reasons.count('learnt late'),
                'below_k': reasons.count('below k'),
                'not_detected': sum(not math.isfinite(r.first_alarm_s) for r in scoped),
                'monitored_delay_p90_s': _p90([r.monitored_delay_s for r in scoped]),
                'reference_delay_p90_s': _p90([reference_delay_s(r) for r in scoped]),
                'named': sum(r.attribution in right for r in scoped),
                'named_vp': sum(r.attribution == 'valve_plate' for r in scoped),
                # out of alarm at the end, named so by the last alarm, which cleared
                'cleared_named': sum(r.cleared_attribution in right for r in scoped),
                'cleared_vp': sum(r.cleared_attribution == 'valve_plate' for r in scoped),
                'cannot_tell': sum(r.attribution == 'cannot_tell' for r in scoped),
                'fault_nm_min': min(torques, default=math.nan),
                'fault_nm_max': max(torques, default=math.nan),
            }
    return out


def _cell(c: dict[str, Any], kind: str) -> str:
    if kind == 'scope':
        reasons = ('never_learnt', 'learnt_late', 'below_k')
        why = [f'{c[k]} {k.replace("_", " ")}' for k in reasons if c[k]]
        return f'{c["in_scope"]}/{c["runs"]}' + (f' ({", ".join(why)})' if why else '')
    if kind == 'torque':
        low, high = c['fault_nm_min'], c['fault_nm_max']
        return '-' if math.isnan(low) else f'{low:.3f}-{high:.3f}'
    if not c['in_scope']:
        return '-'
    if kind == 'delay':
        p90, reference = c['monitored_delay_p90_s'], c['reference_delay_p90_s']
        text = 'nd' if math.isinf(p90) else f'{p90:.1f}'
        text += f' ({c["not_detected"]} nd)' if c['not_detected'] else ''
        return text + ('' if math.isnan(reference) else f' [{reference:.1f}]')
    if kind == 'named':
        text = f'{c["named"]}/{c["in_scope"]}'
        text += f' ({c["cannot_tell"]} ?)' if c['cannot_tell'] else ''
        return text + (f' +{c["cleared_named"]} cleared' if c['cleared_named'] else '')
    text = f'{c["named_vp"]}/{c["in_scope"]}'
    return text + (f' +{c["cleared_vp"]} cleared' if c['cleared_vp'] else '')


def _row(per_family: dict[str, Any], families: list[str], first: str, label: str,
         kind: str) -> list[str]:
    return [first, label, *(_cell(per_family[f], kind) if f in per_family else ''
                            for f in families)]


def format_floors(floors: dict[str, Any]) -> str:
    """
    Format `floor_figures` as one Markdown table with its legend.

    Parameters
    ----------
    floors : dict
        From `floor_figures`.

    Returns
    -------
    str
        The table ('' where the bank has no fault runs).

    """
    table = floors['faults']
    if not table:
        return ''
    labels = {f.name: f.label for f in ALL_FAMILIES}
    families = floors['families']
    head = ['fault', 'floor on the runs in scope', *(labels.get(f, f) for f in families)]
    rows = []
    for name, per_family in table.items():
        rows.append(_row(per_family, families, name, 'in scope of runs', 'scope'))
        rows.append(_row(per_family, families, '', 'fault torque running, N m', 'torque'))
        rows.append(_row(per_family, families, '', 'mon p90 s (nd) [h/(dT-k)]', 'delay'))
        if floors['classes'][name] == 'valve_plate':
            rows.append(_row(per_family, families, '', 'named vp (? cannot tell)', 'named'))
        else:
            rows.append(_row(per_family, families, '', 'named right (? cannot tell)', 'named'))
            rows.append(_row(per_family, families, '', 'named vp', 'vp'))
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(head)]

    def line(cells: list[str]) -> str:
        return '| ' + ' | '.join(c.ljust(w) for c, w in zip(cells, widths, strict=True)) + ' |'

    delays = ', '.join(f'{name} <= {value:g} s' for name, value in
                       FLOORS.monitored_delay_p90_s)
    legend = ('In scope: the torque the fault adds at its full size, averaged over running '
              "after the onset, above the CUSUM allowance k (the issue's floors hold "
              '"where the fault\'s torque exceeds the CUSUM allowance while running"), and '
              'the healthy baseline learnt before the onset (ours: a fault commissioning saw '
              'is in the baseline). Out: "never learnt", "learnt late", "below k". mon p90: '
              'monitored running from the onset to the first alarm (nearest rank); in '
              "square brackets the same percentile of h / (fault torque - k), a CUSUM's "
              'running to WARN on a constant input (a reference, not a bound). Named: of '
              'the runs in scope, undetected ones not named, by the verdict at the end; '
              '"+n cleared": n more runs out of alarm at the end whose last alarm, cleared, '
              f'was named so (the status message says it). Floors: {delays}; '
              f'>= {FLOORS.named:.0%} named vp, <= {FLOORS.cannot_tell:.0%} cannot tell; no '
              'other fault named vp; each other fault named as its class.')
    return '\n'.join([line(head), '|' + '|'.join('-' * (w + 2) for w in widths) + '|',
                      *(line(r) for r in rows), '', legend])
