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
Figures of the evaluation bank: false alarms, detection delays, attribution, scales, coverage.

`bank_figures` reduces the records to a dict of figures (the place to assert targets on);
`format_table` prints them as one Markdown table; `write_outputs` saves records, figures,
table and the two plots (detection delay against fault size, attribution as a picture).

Definitions
-----------
* A false alarm is an entry into WARN or ERROR (from OK) in a nominal run, per hour of the
  run; entries before the onset of fault runs are counted separately, per hour before onset.
* Detection delay: first sample at WARN or above at or after the onset, minus the onset. A
  run not detected counts as an infinite delay, so a percentile is infinite (shown 'nd')
  when more runs than its complement were missed. Percentiles are by nearest rank: the
  smallest value with at least q % of the runs at or below it.
* Attribution: the monitor's reading at the end of each run; correct as
  `settings.ACCEPTED_ATTRIBUTIONS` says for the run's true fault class.
* Scale error: reported minus true factor at the end of the run. Coverage: the fraction of
  runs whose value +- 1.96 std contains the truth (other friction: only where all other
  components share one true factor).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
import csv
from dataclasses import asdict, fields
import json
import math
from pathlib import Path
from typing import Any

from .bank import BankResult, RunRecord
from .settings import ACCEPTED_ATTRIBUTIONS, ALL_FAMILIES, ATTRIBUTIONS, FAULTS
from ..core.friction_bias import Z95  # the monitor's: its intervals are judged by their own

__all__ = ['bank_figures', 'covers', 'format_table', 'nearest_rank', 'write_outputs']

_ATTRIBUTION_HEAD = {'valve_plate': 'vp', 'other_friction': 'other', 'not_friction': 'not fr',
                     'cannot_tell': '?', 'none': 'none'}


def nearest_rank(values: Iterable[float], q: float) -> float:
    """
    Percentile by nearest rank (inf allowed): smallest x with >= q % of values <= x.

    Parameters
    ----------
    values : iterable of float
        The sample (may hold inf).
    q : float
        Percentile [%], in (0, 100].

    Returns
    -------
    float
        The percentile; NaN for an empty sample.

    """
    ordered = sorted(values)
    if not ordered:
        return math.nan
    return ordered[max(math.ceil(q / 100.0 * len(ordered)), 1) - 1]


def table_order(names: Iterable[str], reference: Sequence[str]) -> list[str]:
    """
    Order names as the table lists them: those in `reference` first, in its order.

    Parameters
    ----------
    names : iterable of str
        The names present (repeats allowed).
    reference : sequence of str
        The table's order (families, faults or classes as the settings list them).

    Returns
    -------
    list of str
        Each name once: the referenced ones in `reference` order, then the others sorted.

    """
    present = set(names)
    return [n for n in reference if n in present] + sorted(present - set(reference))


def _rate(count: float, hours: float) -> float:
    return count / hours if hours > 0.0 else math.nan


def _fraction(flags: list[bool]) -> float:
    return sum(flags) / len(flags) if flags else math.nan


def covers(scale: float, truth: float, std: float) -> bool:
    """
    Return whether a reported scale's 95 % interval holds the truth, its edges included.

    An interval that spans no change until one cause is confirmed ends at 1 exactly, a
    healthy component's truth; the value +- Z95 std reaches it within rounding, so the edge
    is widened by 1e-9 of the half-width (one numpy's last digit is not a miss).

    Parameters
    ----------
    scale, truth : float
        Reported and true scale [-].
    std : float
        Reported std: the 95 % half-width / Z95 [-].

    Returns
    -------
    bool
        True where |scale - truth| <= Z95 std (1 + 1e-9).

    """
    return abs(scale - truth) <= Z95 * std * (1.0 + 1e-9)


def _coverage(readings: list[tuple[float, float, float]]) -> float:
    """Return the share of (scale, truth, std) whose interval holds the truth, of the bounded."""
    return _fraction([covers(*reading) for reading in readings if math.isfinite(reading[2])])


def _median(values: list[float]) -> float:
    ordered = sorted(values)
    n = len(ordered)
    if n == 0:
        return math.nan
    return ordered[n // 2] if n % 2 else 0.5 * (ordered[n // 2 - 1] + ordered[n // 2])


def _alarm_figures(records: list[RunRecord], families: list[str], nominal: bool) -> dict:
    out: dict[str, dict[str, float]] = {'hours': {}, 'count': {}, 'rate': {}}
    for family in [*families, 'all']:
        runs = [r for r in records if (r.truth_class == 'nominal') == nominal
                and family in (r.family, 'all')]
        hours = sum(r.duration_s if nominal else r.onset_s for r in runs) / 3600.0
        count = sum(r.alarm_entries_before_onset for r in runs)
        out['hours'][family], out['count'][family] = hours, count
        out['rate'][family] = _rate(count, hours)
    return out


def bank_figures(records: Sequence[RunRecord]) -> dict[str, Any]:
    """
    Reduce a bank's records to its figures.

    Parameters
    ----------
    records : sequence of RunRecord
        The runs.

    Returns
    -------
    dict
        Keys (per family: a dict with the family names and 'all'; per fault: a dict with
        the fault names, each per family unless said):

        * ``runs``, ``simulated_hours``;
        * ``nominal_hours``, ``false_alarms``, ``false_alarms_per_hour`` (per family);
        * ``pre_onset_hours``, ``pre_onset_false_alarms``,
          ``pre_onset_false_alarms_per_hour`` (per family, fault runs);
        * ``monitored_fraction``, ``above_min_speed_fraction`` (per family, mean of runs);
        * ``fault_runs``, ``detected``, ``not_detected``, ``delay_p50_s``, ``delay_p90_s``
          (per fault and family; delays inf when too many runs were missed);
        * ``confusion`` (per fault: count per attribution), ``confusion_by_class`` (per
          true class), ``attribution_correct_rate`` (per class), ``vp_attribution_rate``
          (valve-plate faults attributed to the valve plate), ``vp_attribution_by_family``
          (the same per family);
        * ``vp_scale_error_median``, ``vp_scale_error_p90_abs``,
          ``other_scale_error_median``, ``other_scale_error_p90_abs``, ``coverage_vp``,
          ``coverage_other`` (per fault, and 'all'); ``coverage_vp_by_family`` (all runs of
          each family); a coverage is of the bounded intervals: an interval without an upper
          end (std ``inf``: the healthy level may be nothing, ``healthy_level``) holds any
          truth and says nothing, and is counted apart (``unbounded_vp_by_family``); the
          scale errors and coverages are of the runs whose baseline was learnt (a run's
          scale without one is the pump against the model, not a change from it): the
          others are counted apart (``unlearnt_by_family``);
        * ``floors``: the issue's floors on the fault runs in their scope
          (`floors.floor_figures`).

    """
    records = list(records)
    families = table_order((r.family for r in records), [f.name for f in ALL_FAMILIES])
    faults = table_order((r.fault for r in records), [f.name for f in FAULTS])
    classes = table_order((r.truth_class for r in records), list(ACCEPTED_ATTRIBUTIONS))
    nominal = _alarm_figures(records, families, nominal=True)
    pre = _alarm_figures(records, families, nominal=False)
    fig: dict[str, Any] = {
        'runs': len(records),
        'simulated_hours': sum(r.duration_s for r in records) / 3600.0,
        'nominal_hours': nominal['hours'], 'false_alarms': nominal['count'],
        'false_alarms_per_hour': nominal['rate'],
        'pre_onset_hours': pre['hours'], 'pre_onset_false_alarms': pre['count'],
        'pre_onset_false_alarms_per_hour': pre['rate'],
    }
    for key in ('monitored_fraction', 'above_min_speed_fraction'):
        fig[key] = {}
        for family in [*families, 'all']:
            values = [getattr(r, key) for r in records if family in (r.family, 'all')]
            fig[key][family] = sum(values) / len(values) if values else math.nan
    by_fault = {f: [r for r in records if r.fault == f] for f in faults}
    detection: dict[str, dict] = {k: {} for k in ('fault_runs', 'detected', 'not_detected',
                                                  'delay_p50_s', 'delay_p90_s',
                                                  'monitored_delay_p90_s')}
    for fault, runs in by_fault.items():
        if runs[0].truth_class == 'nominal':
            continue
        for key in detection:
            detection[key][fault] = {}
        for family in [*families, 'all']:
            delays = [r.delay_s for r in runs if family in (r.family, 'all')]
            missed = sum(math.isinf(d) for d in delays)
            detection['fault_runs'][fault][family] = len(delays)
            detection['detected'][fault][family] = len(delays) - missed
            detection['not_detected'][fault][family] = missed
            detection['delay_p50_s'][fault][family] = nearest_rank(delays, 50.0)
            detection['delay_p90_s'][fault][family] = nearest_rank(delays, 90.0)
            detection['monitored_delay_p90_s'][fault][family] = nearest_rank(
                [r.monitored_delay_s for r in runs if family in (r.family, 'all')], 90.0)
    fig.update(detection)
    fig['confusion'] = {f: {a: sum(r.attribution == a for r in runs) for a in ATTRIBUTIONS}
                        for f, runs in by_fault.items()}
    fig['confusion_by_class'] = {c: {a: sum(r.attribution == a for r in records
                                            if r.truth_class == c) for a in ATTRIBUTIONS}
                                 for c in classes}
    fig['attribution_correct_rate'] = {
        c: _fraction([r.attribution in ACCEPTED_ATTRIBUTIONS[c] for r in records
                      if r.truth_class == c]) for c in classes}
    fig['vp_attribution_rate'] = fig['attribution_correct_rate'].get('valve_plate', math.nan)
    fig['vp_attribution_by_family'] = {
        family: _fraction([r.attribution == 'valve_plate' for r in records
                           if r.truth_class == 'valve_plate' and family in (r.family, 'all')])
        for family in [*families, 'all']}
    changes = [r for r in records if r.baseline_learnt_s != math.inf]
    fig['coverage_vp_by_family'] = {
        family: _coverage([(r.vp_scale, r.vp_truth, r.vp_std) for r in changes
                           if family in (r.family, 'all')]) for family in [*families, 'all']}
    fig['unbounded_vp_by_family'] = {
        family: sum(not math.isfinite(r.vp_std) for r in changes
                    if family in (r.family, 'all')) for family in [*families, 'all']}
    fig['unlearnt_by_family'] = {
        family: sum(r.baseline_learnt_s == math.inf for r in records
                    if family in (r.family, 'all')) for family in [*families, 'all']}
    groups = {f: [r for r in runs if r.baseline_learnt_s != math.inf]
              for f, runs in {**by_fault, 'all': records}.items()}
    vp_err = {f: [r.vp_scale - r.vp_truth for r in runs] for f, runs in groups.items()}
    other = {f: [r for r in runs if r.other_truth_exact] for f, runs in groups.items()}
    other_err = {f: [r.other_scale - r.other_truth for r in runs] for f, runs in other.items()}
    fig['vp_scale_error_median'] = {f: _median(e) for f, e in vp_err.items()}
    fig['vp_scale_error_p90_abs'] = {f: nearest_rank(map(abs, e), 90.0)
                                     for f, e in vp_err.items()}
    fig['other_scale_error_median'] = {f: _median(e) for f, e in other_err.items()}
    fig['other_scale_error_p90_abs'] = {f: nearest_rank(map(abs, e), 90.0)
                                        for f, e in other_err.items()}
    fig['coverage_vp'] = {f: _coverage([(r.vp_scale, r.vp_truth, r.vp_std) for r in runs])
                          for f, runs in groups.items()}
    fig['coverage_other'] = {
        f: _coverage([(r.other_scale, r.other_truth, r.other_std) for r in runs])
        for f, runs in other.items()}
    from .floors import floor_figures  # (it reads the records with `nearest_rank`)

    fig['floors'] = floor_figures(records)
    return fig


def _num(value: float, digits: int = 1) -> str:
    if math.isnan(value):
        return '-'
    return 'nd' if math.isinf(value) else f'{value:.{digits}f}'


def _signed(value: float) -> str:
    return '-' if math.isnan(value) else f'{value:+.2f}'


def _percent(value: float) -> str:
    return '-' if math.isnan(value) else f'{100.0 * value:.0f} %'


def format_table(figures: dict[str, Any], result: BankResult | None = None) -> str:
    """
    Format the bank's figures as one Markdown table, with a legend and the run time.

    Parameters
    ----------
    figures : dict
        From `bank_figures`.
    result : BankResult, optional
        The bank (settings, seed, workers and run time for the footer).

    Returns
    -------
    str
        The table.

    """
    families = [f for f in figures['false_alarms_per_hour'] if f != 'all']
    labels = {f.name: f.label for f in ALL_FAMILIES}
    head = ['case', 'runs', 'all', *(labels.get(f, f) for f in families),
            *(_ATTRIBUTION_HEAD[a] for a in ATTRIBUTIONS), 'vp err', 'vp abs err p90',
            'other err', 'cov vp', 'cov other']
    rows: list[list[str]] = []

    def alarm_row(name: str, prefix: str, runs: int) -> list[str]:
        rate, count = figures[f'{prefix}false_alarms_per_hour'], figures[f'{prefix}false_alarms']
        hours = figures['pre_onset_hours' if prefix else 'nominal_hours']
        cells = [f'{_num(rate[f], 2)} ({count[f]})' for f in ['all', *families]]
        cells[0] = f'{_num(rate["all"], 2)} ({count["all"]} in {hours["all"]:.2f} h)'
        return [name, str(runs), *cells]

    conf = figures['confusion']
    nominal_faults = [f for f in conf if f not in figures['fault_runs']]
    n_nominal = sum(sum(conf[f].values()) for f in nominal_faults)
    n_faulty = figures['runs'] - n_nominal
    for fault in nominal_faults:
        rows.append(alarm_row(f'{fault}: false alarms/h', '', n_nominal) + [
            str(conf[fault][a]) for a in ATTRIBUTIONS] + _scale_cells(figures, fault))
    rows.append(alarm_row('fault runs, before onset: false alarms/h', 'pre_onset_', n_faulty)
                + [''] * (len(ATTRIBUTIONS) + 5))
    rows.append(['monitored / above min speed', str(figures['runs']), *(
        f'{_percent(figures["monitored_fraction"][f])} / '
        f'{_percent(figures["above_min_speed_fraction"][f])}' for f in ['all', *families])]
        + [''] * (len(ATTRIBUTIONS) + 5))
    unbounded = figures.get('unbounded_vp_by_family', {})
    unlearnt = figures.get('unlearnt_by_family', {})

    def apart(family: str) -> str:
        notes = [f'{n} {what}' for n, what in ((unbounded.get(family), 'unbounded'),
                                               (unlearnt.get(family), 'never learnt')) if n]
        return f' ({", ".join(notes)})' if notes else ''

    for name, key in (('valve-plate faults named vp', 'vp_attribution_by_family'),
                      ('cov vp, all runs', 'coverage_vp_by_family')):
        rows.append([name, str(figures['runs']), *(_percent(figures[key][f]) + (
            apart(f) if key.startswith('cov') else '') for f in ['all', *families])]
            + [''] * (len(ATTRIBUTIONS) + 5))
    for fault, per_family in figures['delay_p50_s'].items():
        cells = []
        for family in ['all', *families]:
            missed = figures['not_detected'][fault][family]
            cell = f'{_num(per_family[family])}/{_num(figures["delay_p90_s"][fault][family])}'
            monitored = figures['monitored_delay_p90_s'][fault][family]
            cell += f' [{_num(monitored)}]' if math.isfinite(monitored) else ''
            cells.append(cell + (f' ({missed} nd)' if missed else ''))
        rows.append([f'{fault}: delay p50/p90 [mon p90] s',
                     str(figures['fault_runs'][fault]['all']),
                     *cells, *(str(conf[fault][a]) for a in ATTRIBUTIONS),
                     *_scale_cells(figures, fault)])
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(head)]

    def line(cells: list[str]) -> str:
        return '| ' + ' | '.join(c.ljust(w) for c, w in zip(cells, widths, strict=True)) + ' |'

    out = [line(head), '|' + '|'.join('-' * (w + 2) for w in widths) + '|',
           *(line(r) for r in rows)]
    legend = ('Columns all..: false alarms per hour (entries into WARN/ERROR; count in '
              'brackets), or detection delay from onset p50/p90 [s] (in square brackets: p90 '
              'of the monitored running in that delay) (nearest rank; nd = not '
              'detected, counted as infinite). vp..none: attribution at the end of the runs. '
              'err: reported - true scale at the end, median; cov: runs whose value +- 1.96 '
              'std holds the truth (other: where all other components share one factor; '
              'an intermittent fault: the factor the isolation memory holds at the end), of the '
              'runs whose interval has an upper end (one without, std inf, holds any truth: '
              'counted apart, "n unbounded"); the valve-plate truth is against the pump the '
              'baseline holds (learnt after an onset: the fault over what it held then), and '
              'a run '
              'whose baseline was never learnt, its scale the pump against the model and not '
              'a change, is left out of err and cov ("n never learnt"). '
              f'Correct attribution: {_rates(figures["attribution_correct_rate"])}.')
    out += ['', legend]
    if result is not None:
        held = ', what it holds out' if result.settings.held_out else ''
        out.append(f'Bank {result.settings.name!r}{held}, seed {result.seed}: '
                   f'{figures["runs"]} runs,'
                   f' {figures["simulated_hours"]:.2f} h simulated '
                   f'({figures["nominal_hours"]["all"]:.2f} h nominal), '
                   f'{result.runtime_s:.0f} s on {result.workers} worker(s) '
                   f'({result.cpu_s:.0f} s CPU).')
    from .floors import format_floors

    floors = format_floors(figures['floors']) if 'floors' in figures else ''
    if floors:
        out += ['', floors]
    return '\n'.join(out)


def _rates(rates: dict[str, float]) -> str:
    return ', '.join(f'{c} {_percent(v)}' for c, v in rates.items())


def _scale_cells(figures: dict[str, Any], fault: str) -> list[str]:
    return [_signed(figures['vp_scale_error_median'][fault]),
            _num(figures['vp_scale_error_p90_abs'][fault], 2),
            _signed(figures['other_scale_error_median'][fault]),
            _percent(figures['coverage_vp'][fault]), _percent(figures['coverage_other'][fault])]


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ('inf' if value > 0 else '-inf')
    return value


def write_outputs(result: BankResult, figures: dict[str, Any], table: str,
                  out_dir: Path) -> list[Path]:
    """
    Write ``records.csv``, ``figures.json``, ``table.md`` and the two PNG plots.

    Parameters
    ----------
    result : BankResult
        The bank.
    figures : dict
        From `bank_figures`.
    table : str
        From `format_table`.
    out_dir : Path
        Folder (created).

    Returns
    -------
    list of Path
        The files written.

    """
    out_dir.mkdir(parents=True, exist_ok=True)
    records_path = out_dir / 'records.csv'
    with records_path.open('w', newline='', encoding='utf-8') as handle:
        writer = csv.writer(handle)
        writer.writerow([f.name for f in fields(RunRecord)])
        for record in result.records:
            writer.writerow(list(asdict(record).values()))
    figures_path = out_dir / 'figures.json'
    figures_path.write_text(json.dumps(_jsonable(figures), indent=1) + '\n', encoding='utf-8')
    table_path = out_dir / 'table.md'
    table_path.write_text(table + '\n', encoding='utf-8')
    from .plots import write_bank_plots

    return [records_path, figures_path, table_path,
            *write_bank_plots(result.records, figures, out_dir)]
