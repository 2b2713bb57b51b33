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
Run the evaluation bank: each scenario through the ROS-free core, reduced to one record.

Each scenario is fed to a `TorqueEstimator` sample by sample as the node would see it
(integer-ns stamps; JointState with speed and torque, FluidPressure, oil Temperature when
used; at equal stamps temperature and pressure come before the joint state). The run is
reduced on the fly: alarm entries (OK -> WARN or ERROR) before the onset, the first alarm at
or after it, and the monitor's reading at the end (`read_monitor`), so memory does not grow
with the number of estimates. Scenarios are deterministic per seed: the records are the same
for any number of worker processes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
import math
import os
import time
from typing import NamedTuple

import numpy as np

from .bank_node import node_spec, node_table, pump_and_table, scenario_node, simulated
from .eha_scenarios import draw_eha
from .eha_settings import EhaSettings
from .scenarios import Scenario, SimulatedScenario
from .settings import ALL_FAMILIES, BankSettings, FAMILIES, Family, FAULTS
from .true_pump import true_table
from ..core.attribution import Verdict
from ..core.estimator import TorqueEstimator
from ..core.inputs import InputKind
from ..core.monitor import OK
from ..core.node_parameters import EstimatorConfig, load_estimator_config
from ..paths import config_dir
from ..process_pool import process_map

__all__ = ['BankResult', 'MonitorReading', 'RunRecord', 'base_config', 'baseline_learnt',
           'build_scenarios', 'feed_signals', 'prepare_true_tables', 'read_monitor', 'run_bank',
           'run_scenario', 'valve_plate_truth']

_NS = 1_000_000_000
_CHUNK = 1 << 16  # events converted to Python floats at a time (bounds memory)


class MonitorReading(NamedTuple):
    """What the bank reads from the wear monitor (the one interface it codes against)."""

    level: int  # OK / WARN / ERROR
    attribution: str  # one of settings.ATTRIBUTIONS; 'none' when the level is OK
    vp_scale: float  # valve-plate friction scale [-]
    vp_std: float  # its reported standard deviation [-]
    other_scale: float  # scale of the other friction components [-]
    other_std: float  # its reported standard deviation [-]
    change_start_s: float = math.nan  # where the change the scales describe began [s]
    # at OK, the last alarm's verdict at its height (``last_alarm``), as ``attribution``
    # ('none': none cleared; one the baseline followed was taken for no fault), its onset [s]
    cleared_attribution: str = 'none'
    cleared_onset_s: float = math.nan


def read_monitor(core: TorqueEstimator) -> MonitorReading:
    """
    Read level, attribution and friction scales from the estimator's monitor.

    The only place that knows the monitor's attributes. The attribution is the verdict the
    status message gives (``diagnostics.level_message``): the isolation's single cause; an
    alarm for which no cause stands out yet counts as 'cannot_tell'. Out of alarm, the
    message says the last alarm that cleared, and its verdict: read so too.

    Parameters
    ----------
    core : TorqueEstimator
        The estimator whose ``monitor`` to read.

    Returns
    -------
    MonitorReading
        The reading; attribution 'none' while the level is OK.

    """
    mon = core.monitor
    level = int(mon.level)
    attribution = 'none'
    if level != OK:
        side = 1.0 if mon.cusum_pos_nm_s >= mon.cusum_neg_nm_s else -1.0
        verdict = mon.verdict(side)[0]
        attribution = 'cannot_tell' if verdict == Verdict.NONE else verdict
    last, cleared = mon.last_alarm, 'none'
    if level == OK and last.level != OK and not last.followed:  # a followed one: no fault
        cleared = 'cannot_tell' if last.verdict == Verdict.NONE else last.verdict
    return MonitorReading(level, attribution, mon.theta_vp, mon.valve_plate_scale_std,
                          mon.theta_rest, mon.rest_scale_std, mon.change_start_s, cleared,
                          last.onset_s)


def valve_plate_truth(sim: SimulatedScenario, reading: MonitorReading,
                      learnt_s: float = -math.inf) -> float:
    """
    Return the valve-plate factor a reading's scale is held to.

    The scale of a monitor in alarm is its estimate over the change under way, whose sums
    began where the CUSUMs last left zero (``reading.change_start_s``): an intermittent
    fault's truth counts from there (``SimulatedScenario.vp_truth_since``). Otherwise (no
    alarm: the scale is 1 and its interval spans what the detection does not see over the
    recent running; or a fault that stays) the simulation's ``vp_truth``. Either is the
    factor against the healthy pump; the scale is the change from the baseline (1: as at
    commissioning), so where the baseline was learnt after the onset, holding the fault in
    part or whole, the truth is that factor over the one the baseline holds
    (``SimulatedScenario.vp_commissioned``): a pump commissioned worn reads 1, rightly.

    Parameters
    ----------
    sim : SimulatedScenario
        The run's simulation.
    reading : MonitorReading
        The monitor's reading at its end.
    learnt_s : float
        When the baseline was learnt [s] (-inf: before anything changed; inf: never).

    Returns
    -------
    float
        The truth [-].

    """
    truth = sim.vp_truth
    if sim.vp_truth_since is not None and reading.level != OK and \
            math.isfinite(reading.change_start_s):
        truth = sim.vp_truth_since(reading.change_start_s)
    if sim.vp_commissioned is not None and math.isfinite(learnt_s):
        truth /= sim.vp_commissioned(learnt_s)
    return truth


def baseline_learnt(core: TorqueEstimator) -> bool:
    """Return whether the estimator's monitor has learnt its healthy baseline."""
    return core.monitor.baseline is not None


@dataclass(frozen=True)
class RunRecord:
    """One run reduced to its figures (times in s from the start of the run)."""

    scenario_id: str
    family: str
    fault: str
    truth_class: str
    seed: int  # replicate within (family, fault)
    duration_s: float
    onset_s: float  # inf for the nominal pump
    alarm_entries_before_onset: int  # OK -> WARN/ERROR before the onset (whole nominal run)
    first_alarm_s: float  # first sample at or after the onset at WARN or above; nan: none
    final_level: int
    attribution: str
    vp_scale: float
    vp_std: float
    other_scale: float
    other_std: float
    vp_truth: float  # against the pump the baseline holds (`valve_plate_truth`)
    other_truth: float
    other_truth_exact: bool  # False: other_truth is a fitted ratio (one component faulty)
    monitored_fraction: float  # joint-state samples the monitor learnt from
    above_min_speed_fraction: float  # joint-state samples with |speed| >= monitor min speed

    monitored_delay_s: float  # monitored running from the onset to the first alarm; inf: none
    # the issue's floors hold "where the fault's torque exceeds the CUSUM allowance while
    # running" (`floors`); defaults: a record written before these were kept (in scope)
    fault_running_nm: float = math.nan  # mean |torque the fault adds| running [N m]
    allowance_nm: float = math.nan  # the run's CUSUM allowance k [N m]
    warn_nm_s: float = math.nan  # the run's CUSUM WARN threshold h [N m s]
    baseline_learnt_s: float = math.nan  # when the healthy baseline was learnt; inf: never
    # out of alarm at the end, the verdict of the last alarm if it began at or after the
    # onset and cleared (what the status message says of it); 'none' otherwise
    cleared_attribution: str = 'none'

    @property
    def delay_s(self) -> float:
        """Return the detection delay from the onset [s]; inf when not detected."""
        return self.first_alarm_s - self.onset_s if math.isfinite(self.first_alarm_s) \
            else math.inf


@dataclass(frozen=True)
class BankResult:
    """Records of a bank (in scenario order) and how long it took."""

    settings: BankSettings
    seed: int
    workers: int
    records: list[RunRecord]
    runtime_s: float  # wall time
    cpu_s: float  # CPU time of this process and its workers


def base_config() -> EstimatorConfig:
    """
    Read the node's parameters as shipped (``config/torque_estimator.yaml``).

    Returns
    -------
    EstimatorConfig
        The configuration the bank runs the estimator with (and the truth's plant constants).

    """
    return load_estimator_config(config_dir() / 'torque_estimator.yaml')


def build_scenarios(settings: BankSettings, seed: int = 0,
                    config: EstimatorConfig | None = None) -> list[Scenario]:
    """
    All scenarios of a bank, onsets drawn from the seed.

    Parameters
    ----------
    settings : BankSettings
        Size of the bank.
    seed : int
        Bank seed: the same seed gives the same scenarios and signals.
    config : EstimatorConfig, optional
        Estimator configuration (default `base_config`).

    Returns
    -------
    list of Scenario
        Family by family, fault by fault, replicate by replicate.

    """
    config = config or base_config()
    scenarios = []
    for family in ALL_FAMILIES if settings.held_out else FAMILIES:
        if settings.families is not None and family.name not in settings.families:
            continue
        size = _Size.of(settings, family)
        if size is None:
            continue
        for fault in FAULTS:
            if not fault.applies_to(family, settings.held_out) or any(
                    names is not None and fault.name not in names
                    for names in (settings.faults, size.faults)):
                continue
            nominal = fault.truth_class == 'nominal'
            for rep in range(size.nominal_seeds if nominal else size.fault_seeds):
                duration = size.nominal_duration_s if nominal else size.fault_duration_s
                draft = Scenario(family, fault, rep, duration, math.inf, size.ramp_s, seed,
                                 config)
                onset = math.inf
                if not nominal:
                    rng = np.random.default_rng([*draft.seed_key, 1])
                    onset = float(rng.uniform(*size.onset_s)) if size.onset_s else \
                        duration * float(rng.uniform(*settings.onset_fraction))
                scenarios.append(Scenario(family, fault, rep, duration, onset, size.ramp_s,
                                          seed, config))
    return scenarios


class _Size(NamedTuple):
    """Run counts and lengths of one family in a bank."""

    nominal_seeds: int
    nominal_duration_s: float
    fault_seeds: int
    fault_duration_s: float
    ramp_s: float
    onset_s: tuple[float, float] | None  # absolute; None: the bank's onset fraction
    faults: tuple[str, ...] | None

    @classmethod
    def of(cls, settings: BankSettings, family: Family) -> _Size | None:
        if not family.realistic:
            return cls(settings.nominal_seeds, settings.nominal_duration_s,
                       settings.fault_seeds, settings.fault_duration_s, settings.ramp_s, None,
                       None)
        eha = settings.eha
        if eha is None:
            return None
        return cls(eha.nominal_seeds, eha.nominal_duration_s, eha.fault_seeds,
                   eha.fault_duration_s, eha.ramp_s, eha.onset_s, eha.faults)


def prepare_true_tables(scenarios: list[Scenario]) -> int:
    """
    Build (or load) the true pumps' tables the realistic scenarios need, once.

    Called before the workers start, so that they find the tables in the disk cache
    instead of each building them.

    Parameters
    ----------
    scenarios : list of Scenario
        The bank's scenarios.

    Returns
    -------
    int
        Distinct true tables.

    """
    variants = set()
    for scenario in scenarios:
        motion = scenario.family.motion
        if isinstance(motion, EhaSettings):
            variants.add((draw_eha(scenario).variant, motion.mismatch))
    for variant, mismatch in variants:
        true_table(variant, mismatch)
    for spec in {node_spec(scenario) for scenario in scenarios}:  # the node's, per oil
        node_table(spec)
    return len(variants)


def feed_signals(core: TorqueEstimator, sim: SimulatedScenario, onset_ns: float
                 ) -> tuple[int, int | None, int, int | None]:
    """
    Feed the signals in stamp order.

    Returns alarm entries before the onset, the first alarm's stamp, the monitored samples
    between the onset and that alarm (or the end), and the stamp of the estimate with which
    the healthy baseline was first learnt (None: never).
    """
    stamps = [np.round(x * 1e9).astype(np.int64)
              for x in (sim.temperature_t_s, sim.pressure_t_s, sim.t_s)]
    kinds = np.concatenate([np.full(s.size, k, dtype=np.int8) for k, s in enumerate(stamps)])
    stamp = np.concatenate(stamps)
    first_value = np.concatenate([sim.temperature_c, sim.pressure_diff_pa, sim.speed_rad_s])
    torque = np.concatenate([np.zeros(stamps[0].size + stamps[1].size), sim.torque_nm])
    order = np.argsort(stamp, kind='stable')  # ties: temperature, pressure, joint state
    on_input = core.on_input  # the node's one entry point, as its callbacks call it
    temperature, pressure, joint = (InputKind.OIL_TEMPERATURE, InputKind.LOAD_PRESSURE,
                                    InputKind.JOINT_STATE)
    previous, before, first, monitored = OK, 0, None, 0
    counts = core.counts
    at_onset = -1
    learnt: int | None = None
    for start in range(0, order.size, _CHUNK):
        part = order[start:start + _CHUNK]
        for ns, kind, value, tq in zip(stamp[part].tolist(), kinds[part].tolist(),
                                       first_value[part].tolist(), torque[part].tolist(),
                                       strict=True):
            if kind == 2:
                est = on_input(joint, ns, value, tq, ns)
                if est is None:
                    continue
                if learnt is None and baseline_learnt(core):
                    learnt = ns
                if at_onset < 0 and ns >= onset_ns:
                    at_onset = counts['monitor_samples']
                level = est.level  # the level the node publishes with this estimate
                if level != previous:
                    if previous == OK and ns < onset_ns:
                        before += 1
                    previous = level
                if level and first is None and ns >= onset_ns:
                    first = ns
                    monitored = counts['monitor_samples'] - at_onset
            elif kind == 1:
                on_input(pressure, ns, value, None, ns)
            else:
                on_input(temperature, ns, value, None, ns)
    if first is None:
        monitored = counts['monitor_samples'] - max(at_onset, 0)
    return before, first, monitored, learnt


def run_scenario(scenario: Scenario) -> RunRecord:
    """
    Simulate one scenario, feed it to a fresh estimator, reduce it to a record.

    Parameters
    ----------
    scenario : Scenario
        What to run.

    Returns
    -------
    RunRecord
        The run's figures.

    """
    sim = simulated(scenario)
    core = scenario_node(scenario)
    onset_ns = scenario.onset_s * 1e9
    before, first, monitored, learnt = feed_signals(core, sim, onset_ns)
    period_s = float(sim.t_s[1] - sim.t_s[0])
    reading = read_monitor(core)
    fault = scenario.fault
    return RunRecord(
        scenario_id=scenario.scenario_id, family=scenario.family.name, fault=fault.name,
        truth_class=fault.truth_class, seed=scenario.replicate,
        duration_s=scenario.duration_s, onset_s=scenario.onset_s,
        alarm_entries_before_onset=before,
        first_alarm_s=math.nan if first is None else first / _NS,
        final_level=reading.level, attribution=reading.attribution,
        vp_scale=reading.vp_scale, vp_std=reading.vp_std, other_scale=reading.other_scale,
        other_std=reading.other_std,
        vp_truth=valve_plate_truth(sim, reading, math.inf if learnt is None else learnt / _NS),
        other_truth=sim.other_truth,
        other_truth_exact=sim.other_truth_exact,
        monitored_fraction=core.counts['monitor_samples'] / sim.t_s.size,
        above_min_speed_fraction=sim.above_min_speed_fraction,
        monitored_delay_s=math.inf if first is None else monitored * period_s,
        fault_running_nm=sim.fault_running_nm, allowance_nm=core.config.cusum_drift_nm,
        warn_nm_s=core.config.cusum_warn_nm_s,
        baseline_learnt_s=math.inf if learnt is None else learnt / _NS,
        cleared_attribution=reading.cleared_attribution
        if reading.cleared_onset_s >= scenario.onset_s else 'none')


def run_bank(settings: BankSettings, workers: int = 1, seed: int = 0,
             config: EstimatorConfig | None = None,
             progress: Callable[[int, int], None] | None = None) -> BankResult:
    """
    Run every scenario of a bank, in this process or in ``workers`` processes.

    Parameters
    ----------
    settings : BankSettings
        Size of the bank (`settings.QUICK`, `settings.FULL` or your own).
    workers : int
        Worker processes (1: in this process).
    seed : int
        Bank seed.
    config : EstimatorConfig, optional
        Estimator configuration (default `base_config`).
    progress : callable, optional
        Called with (runs done, runs in all) after each run.

    Returns
    -------
    BankResult
        Records in scenario order (identical for any ``workers``) and the wall time.

    """
    if workers < 1:
        raise ValueError('workers must be >= 1')
    scenarios = build_scenarios(settings, seed, config)
    pump_and_table()  # build / load the tables once, before any worker starts
    prepare_true_tables(scenarios)
    start, cpu_start = time.perf_counter(), _cpu_s()
    records: list[RunRecord] = []
    if workers == 1 or len(scenarios) <= 1:
        for scenario in scenarios:
            records.append(run_scenario(scenario))
            if progress:
                progress(len(records), len(scenarios))
    else:
        records = process_map(run_scenario, scenarios, min(workers, len(scenarios)),
                              (lambda done: progress(done, len(scenarios))) if progress
                              else None)
    return BankResult(settings, seed, workers, records, time.perf_counter() - start,
                      _cpu_s() - cpu_start)


def _cpu_s() -> float:
    """CPU time of this process and of its waited-for children [s]."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system
