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
Valve-plate wear monitor: a healthy baseline, a CUSUM on the change from it, and isolation.

The monitor takes the *settled* residual (``settled_residual``): measured minus expected
torque, aligned in time, in the friction direction (times the sign of the speed, so that
"more friction" is positive in both directions), only in steady running. It averages it
over windows of ``attribution_window_s`` of monitored running (one direction each, the
steady stretches between transients joined; a window of fewer than `MIN_WINDOW_SAMPLES`
is dropped), and each window mean is one measurement:

1. **Commissioning.** ``baseline_learn_s`` of stationary monitored running teach the
   installation's healthy signature (``baseline``): friction levels, drive loss, torque
   offset and gain against the model, the effective rotor inertia, and the window noise.
   Stationary: the fits of its two halves agree (``_learn``); while the oil warms up they
   do not, and learning goes on. No alarm is raised meanwhile (the diagnostics say that the
   baseline is being learnt); the published scales are the fit's, against the model.
2. **Detection.** The change d = e - e_hat from the baseline's prediction, less the
   baseline's own uncertainty there (d shrunk towards 0 by ``cusum_baseline_sigmas``
   times the prediction's standard deviation: at an operating point commissioning never
   saw, the extrapolation error is not a change) and by what the oil's temperature does
   to the torque (``oil_allowance``: the viscosity's band where it is assumed, the drive's
   torque constant drifting, on its side), projected on each cause's signature
   (z_j = s_j d / rms(s_j), in N m at a typical operating point), feeds a two-sided CUSUM
   per cause weighted by time, so that the thresholds do not depend on the rates:
   S+ = max(0, S+ + (z - k) T) and S- = max(0, S- + (-z - k) T), in N m s (T the window's
   running); S+ and S- reported are the largest of the causes'. (One sum on d
   would miss a torque-gain change, which raises d when pumping and lowers it when
   motoring.) WARN when max(S+, S-) reaches ``cusum_warn_nm_s``, ERROR at
   ``cusum_error_nm_s``; a level clears only below ``cusum_clear_ratio`` times its
   threshold (hysteresis). The sums are capped at `CUSUM_CAP_RATIO` times the ERROR
   threshold. An EWMA of d gives the diagnostics a smoothed view. Without the temperature
   topic a fall of a friction, as the isolation names it, is the oil thinning: the baseline
   follows it down instead of alarming (``oil_follow``); with it, a change that a drift of
   the torque measurement with T - T_0, reading high as the oil warms, explains clearly
   better than any step is that drift, learnt instead (``gain_follow``). Without it, after
   more than ``warm_up_pause_s`` without monitored running (a pause, a restart the next
   morning) the oil may be cold: the change is not judged until it settles
   (``warm_up_hold``).
3. **Isolation** (``attribution``): which single change explains d since the CUSUM left
   zero, and the valve-plate and other friction scales relative to the healthy pump. The
   last alarm, its verdict with it, is kept after it clears (``last_alarm``).

`state_dict` / `load_state_dict` carry everything learnt (the baseline's sums, the sums,
the level), so that the node keeps it across restarts (``baseline_file``).

Longer than 500 lines because `WearMonitor.update_many` is `WearMonitor.update`'s lean loop
written out, its window sums in locals, beside the scalar path whose results it must give
bit for bit (``test_chunk_path``).
"""

from __future__ import annotations

import math

import numpy as np

from .attribution import AttributionSettings, DETECTED_CAUSES, FaultIsolation, signature_matrix
from .baseline import Baseline, baseline_regressors, N_TERMS
from .commissioning import Commissioning
from .gain_follow import GainFollow
from .last_alarm import LastAlarm
from .monitor_report import MonitorReport
from .monitor_state import ERROR, MonitorPersistence, MonitorSettings, MonitorTrace, OK, WARN
from .oil_allowance import OilAllowance
from .oil_follow import OilFollow
from .signatures import joints_signature, undetectable_change
from .warm_up_hold import WarmUpHold

__all__ = ['ERROR', 'LEVEL_NAMES', 'MIN_WINDOW_SAMPLES', 'OK', 'STALE', 'WARN',
           'MonitorSettings', 'MonitorTrace', 'WearMonitor']

_TORQUE_GAIN = DETECTED_CAUSES.index('torque_gain')
_UNSEEN_CAP = 1e6
"""The undetectable change published where no CUSUM moves with a cause [-]: any size."""

STALE = 3
CUSUM_CAP_RATIO = 1.2
"""The sums are capped at this times the ERROR threshold, so that after a repair the level
clears in a bounded time (about (1.2 - clear ratio x warn / error) x error / k seconds of
monitored running); the node's ~/reset_monitor service re-learns at once."""
LEVEL_NAMES = {OK: 'OK', WARN: 'WARN', ERROR: 'ERROR', STALE: 'STALE'}
MIN_WINDOW_SAMPLES = 10
"""A window with fewer monitored samples (a short burst between reversals) is not a
measurement: its mean would carry more of the reversal than of the steady friction."""


class WearMonitor(MonitorPersistence, MonitorReport):
    """
    Stateful wear monitor; feed it one settled friction-direction sample at a time.

    Parameters
    ----------
    config : MonitorSettings
        Tuning of the detection: ``ewma_*``, ``cusum_*``, ``baseline_learn_s`` and
        ``baseline_settle_time_constant_s``.
    attribution : AttributionSettings
        Tuning of the baseline fit and the isolation.
    drive_loss_nm : float
        The configured drive loss [N m] (part of the torque-gain signature).
    viscosity_assumed : bool
        The oil viscosity is a parameter, not measured (changes the valve-plate verdict).
    rotor_inertia_kg_m2 : float
        The configured rotor inertia [kg m^2] (part of the torque-gain signature).
    oil : OilAllowance, optional
        What the oil's temperature does to the torque without a fault (``oil_allowance``);
        None: nothing.

    """

    def __init__(self, config: MonitorSettings, attribution: AttributionSettings,
                 drive_loss_nm: float = 0.0, viscosity_assumed: bool = False,
                 rotor_inertia_kg_m2: float = 0.0, oil: OilAllowance | None = None) -> None:
        self.settings = config
        self._oil = oil
        self._unseen_nm = 0.0  # k and the baseline's margin (`_set_signatures`) [N m]
        self._tau = config.ewma_time_constant_s
        self._k = config.cusum_drift_nm
        self._sigmas = config.cusum_baseline_sigmas
        self._h_warn = config.cusum_warn_nm_s
        self._h_error = config.cusum_error_nm_s
        self._clear = config.cusum_clear_ratio
        self._cap = CUSUM_CAP_RATIO * config.cusum_error_nm_s
        self._window_s = attribution.attribution_window_s
        self._drive_loss = drive_loss_nm
        self._inertia = rotor_inertia_kg_m2
        self._floor = attribution.scale_systematic_std
        prior = ((attribution.scale_prior_std,) * 2 + (attribution.offset_prior_std_nm,) * 2
                 + (attribution.torque_gain_prior_std, attribution.inertia_prior_std_kg_m2))
        self.commissioning = Commissioning(prior, config.baseline_learn_s,
                                           0.5 * config.cusum_drift_nm,
                                           config.baseline_settle_time_constant_s)
        self.isolation = FaultIsolation(attribution, viscosity_assumed)
        self._follow = OilFollow() if viscosity_assumed else None  # the oil thinning
        self._hold = WarmUpHold(prior, config.baseline_learn_s, 0.5 * config.cusum_drift_nm,
                                config.baseline_settle_time_constant_s,
                                config.warm_up_pause_s) if viscosity_assumed else None
        self._gain_follow = None if viscosity_assumed else GainFollow(  # the drive's k_t
            config.torque_constant_drift_max_per_k, attribution.isolation_memory_s)
        self.reset()

    # -- state ----------------------------------------------------------------------------

    def reset(self) -> None:
        """Forget everything, the baseline included (after a repair): learn afresh."""
        self.samples = 0
        self.windows = 0
        self.commissioning.reset()
        self.baseline: Baseline | None = None
        for follow in (self._follow, self._gain_follow):
            if follow is not None:
                follow.reset()
        if self._hold is not None:
            self._hold.forget()
        self.isolation.reset()
        self.last_alarm = LastAlarm()  # kept after it clears; a repair forgets it
        self._reset_detection()
        self._open(0.0)

    def _reset_detection(self, points: bool = True) -> None:
        """Restart the detection; ``points``: forget the recent points too (new signatures)."""
        if points:
            n = len(DETECTED_CAUSES)  # the signatures' products over running, and that
            self._recent_s2 = np.zeros((n, n))  # running, both forgotten as the isolation's
            self._recent_s = 0.0
        self.ewma_nm = 0.0
        self._var = 0.0
        self._pos = np.zeros(len(DETECTED_CAUSES))  # a CUSUM per cause, each side
        self._neg = np.zeros(len(DETECTED_CAUSES))
        self.cusum_pos_nm_s = 0.0
        self.cusum_neg_nm_s = 0.0
        self._allowance_nm_s = 0.0  # the oil allowances taken off, summed over running
        self._gain_allowance_nm_s = 0.0
        self._allowance_s = 0.0
        self._set_signatures()
        self.level = OK
        self.alarm_onset_s = math.nan
        self.change_start_s = math.nan  # the close of the first window of the change under way
        self._publish_fit()

    def _open(self, sign: float) -> None:
        self._sign = sign
        self._n = 0
        self._time = 0.0
        self._se = self._svp = self._so = self._sth = self._sa = 0.0
        self._sw = self._sv = 0.0  # |speed| and viscosity: the oil allowances
        self._sj = 0.0  # the spherical joints' friction: their signature (isolation only)

    # -- samples --------------------------------------------------------------------------

    def update(self, t_s: float, dt_s: float, residual_nm: float, valve_plate_nm: float,
               other_nm: float, theoretical_nm: float, sign: float,
               accel_rad_s2: float = 0.0, speed_abs_rad_s: float = 0.0,
               viscosity_m2_s: float = math.nan, joints_nm: float = 0.0) -> int:
        """
        Take one settled sample.

        Parameters
        ----------
        t_s : float
            Sample time [s].
        dt_s : float
            Monitored time since the previous sample the monitor took [s] (0 after a gap).
        residual_nm : float
            Settled residual, friction direction [N m].
        valve_plate_nm : float
            Modelled valve-plate friction magnitude [N m].
        other_nm : float
            Modelled friction magnitude of the bearing, joints and piston heads [N m].
        theoretical_nm : float
            Theoretical torque V_g dp / 2 pi from the measured pressure [N m].
        sign : float
            Direction of rotation, +1 or -1.
        accel_rad_s2 : float
            Filtered acceleration the residual's inertia part was computed with [rad/s^2].
        speed_abs_rad_s : float
            |Speed| [rad/s] (the oil allowance's viscous friction).
        viscosity_m2_s : float
            The viscosity the expected torque was computed with [m^2/s] (with the
            temperature topic it gives the oil temperature; NaN: not known).
        joints_nm : float
            Modelled spherical joints' friction magnitude, a part of ``other_nm`` [N m]
            (the isolation's joints cause; 0: none, never named).

        Returns
        -------
        int
            The level after this sample (OK, WARN or ERROR).

        """
        self.samples += 1
        if sign != self._sign:
            self._close(t_s)
            self._open(sign)
        self._n += 1
        self._time += dt_s
        self._se += residual_nm
        self._svp += valve_plate_nm
        self._so += other_nm
        self._sth += theoretical_nm * sign
        self._sa += accel_rad_s2 * sign
        self._sw += speed_abs_rad_s
        self._sv += viscosity_m2_s
        self._sj += joints_nm
        if self._time >= self._window_s:
            self._close(t_s)
            self._open(sign)
        return self.level

    def update_many(self, t_s: list[float], dt_s: list[float], residual_nm: list[float],
                    valve_plate_nm: list[float], other_nm: list[float],
                    theoretical_nm: list[float], sign: list[float],
                    accel_rad_s2: list[float] | None = None,
                    speed_abs_rad_s: list[float] | None = None,
                    viscosity_m2_s: list[float] | None = None,
                    joints_nm: list[float] | None = None) -> MonitorTrace:
        """
        Take many settled samples in order: `update` for each, in one lean loop.

        The same operations in the same order as `update`: results and state are identical
        to calling it sample by sample.

        Parameters
        ----------
        t_s, dt_s, residual_nm : list of float
            Per sample, as `update` takes them [s, s, N m].
        valve_plate_nm, other_nm, theoretical_nm : list of float
            Per sample, as `update` takes them [N m].
        sign : list of float
            Direction of rotation per sample, +1 or -1.
        accel_rad_s2 : list of float, optional
            Filtered acceleration per sample [rad/s^2] (None: 0).
        speed_abs_rad_s, viscosity_m2_s, joints_nm : list of float, optional
            Per sample, as `update` takes them [rad/s, m^2/s, N m] (None: 0, NaN and 0).

        Returns
        -------
        MonitorTrace
            The monitor's state after each sample.

        """
        window = self._window_s
        cur_sign, n, time = self._sign, self._n, self._time
        se, svp, so, sth, sa = self._se, self._svp, self._so, self._sth, self._sa
        sw, sv, sj = self._sw, self._sv, self._sj
        accel = [0.0] * len(t_s) if accel_rad_s2 is None else accel_rad_s2
        speeds = [0.0] * len(t_s) if speed_abs_rad_s is None else speed_abs_rad_s
        viscosity = [math.nan] * len(t_s) if viscosity_m2_s is None else viscosity_m2_s
        joints = [0.0] * len(t_s) if joints_nm is None else joints_nm
        # the state changes only when a window closes: kept as (from sample i, state) runs
        runs = [(0, self._trace_state())]
        for i, (t, dt, r, vp, other, th, sgn, a, w, nu, jt) in enumerate(zip(
                t_s, dt_s, residual_nm, valve_plate_nm, other_nm, theoretical_nm, sign, accel,
                speeds, viscosity, joints, strict=True)):
            if sgn != cur_sign:
                self._sign, self._n, self._time = cur_sign, n, time
                self._se, self._svp, self._so, self._sth, self._sa = se, svp, so, sth, sa
                self._sw, self._sv, self._sj = sw, sv, sj
                self._close(t)
                cur_sign, n, time, se, svp, so, sth, sa = sgn, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
                sw = sv = sj = 0.0
                runs.append((i, self._trace_state()))
            n += 1
            time += dt
            se += r
            svp += vp
            so += other
            sth += th * sgn
            sa += a * sgn
            sw += w
            sv += nu
            sj += jt
            if time >= window:
                self._sign, self._n, self._time = cur_sign, n, time
                self._se, self._svp, self._so, self._sth, self._sa = se, svp, so, sth, sa
                self._sw, self._sv, self._sj = sw, sv, sj
                self._close(t)
                n, time, se, svp, so, sth, sa = 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
                sw = sv = sj = 0.0
                runs.append((i, self._trace_state()))
        total = len(t_s)
        self.samples += total
        self._sign, self._n, self._time = cur_sign, n, time
        self._se, self._svp, self._so, self._sth, self._sa = se, svp, so, sth, sa
        self._sw, self._sv, self._sj = sw, sv, sj
        columns: tuple[list, ...] = ([], [], [], [], [], [], [])
        for (start, state), (end, _) in zip(runs, [*runs[1:], (total, ())], strict=True):
            if end > start:
                for column, value in zip(columns, state, strict=True):
                    column.extend([value] * (end - start))
        return MonitorTrace(*columns)

    def _trace_state(self) -> tuple[int, float, float, float, float, float, float]:
        return (self.level, self.cusum_pos_nm_s, self.cusum_neg_nm_s, self.theta_vp,
                self.theta_rest, self.valve_plate_scale_std, self.rest_scale_std)

    # -- windows --------------------------------------------------------------------------

    def _close(self, t_s: float) -> None:
        """Take the open window's mean as one measurement, if it holds enough samples."""
        n, duration = self._n, self._time
        if n < MIN_WINDOW_SAMPLES or not duration > 0.0:
            return
        inv = 1.0 / n
        h = baseline_regressors(self._svp * inv, self._so * inv, self._sth * inv, self._sign,
                                self._sa * inv)
        e = self._se * inv
        weight = duration / self._window_s
        self.windows += 1
        baseline = self.baseline
        oil = self._oil
        temperature = oil.temperature_c(self._sv * inv) if oil is not None else math.nan
        if baseline is None:
            self._learn(h, e, weight, duration, t_s, temperature)
            return
        sig = self._m @ h
        d = e - baseline.predict(h)
        if self._gain_follow is not None:  # the measurement's drift learnt (``gain_follow``)
            d -= self._gain_follow.term_nm(sig, temperature, baseline.temperature_c)
        if self._hold is not None and self._hold.holds(h, d, weight, duration, t_s):
            self._publish_fit()  # (released: the oil may have been seen moving)
            return  # after a start or a pause, the oil may be cold (``warm_up_hold``)
        prediction_var = baseline.prediction_var(h)
        var = baseline.window_var_nm2 / weight + prediction_var
        a = 1.0 - math.exp(-duration / self._tau)
        dev = d - self.ewma_nm
        self.ewma_nm += a * dev
        self._var += a * (dev * dev - self._var)
        # a CUSUM per cause on d projected on its signature (in N m at a typical point of
        # commissioning: a change of any cause's shape drives its own sum), d shrunk by the
        # baseline's own uncertainty here (extrapolating beyond commissioning is no change)
        # and by what the oil's temperature does to the torque (``oil_allowance``)
        viscous = low = high = 0.0
        if oil is not None:  # (the band's change at the installation's friction levels)
            coef = baseline.coefficients
            viscous = oil.window_nm(self._sw * inv, 1.0 + float(coef[0]), 1.0 + float(coef[1]))
            low, high = oil.gain_interval_nm((self._sth + self._svp + self._so) * inv,
                                             temperature, baseline.temperature_c)
        self._allowance_nm_s += viscous * duration
        self._gain_allowance_nm_s += 0.5 * (high - low) * duration
        self._allowance_s += duration
        keep = math.exp(-duration / self.isolation.settings.isolation_memory_s)
        self._recent_s2 = keep * self._recent_s2 + duration * np.outer(sig, sig)
        self._recent_s = keep * self._recent_s + duration
        margin = self._sigmas * math.sqrt(prediction_var) + viscous
        high += margin
        low -= margin
        shrunk = d - high if d > high else (d - low if d < low else 0.0)
        z = sig * shrunk / self._norm
        k, cap = self._k, self._cap
        self._pos = np.clip(self._pos + (z - k) * duration, 0.0, cap)
        self._neg = np.clip(self._neg + (-z - k) * duration, 0.0, cap)
        self.cusum_pos_nm_s = float(self._pos.max())
        self.cusum_neg_nm_s = float(self._neg.max())
        drift = math.nan  # a k_t drift too small to be learnt, fitted with the change's size
        if self._gain_follow is not None and self._gain_follow.max_per_k > 0.0:
            drift = float(sig[_TORQUE_GAIN]) * (temperature - baseline.temperature_c)
        changing = self.cusum_pos_nm_s > 0.0 or self.cusum_neg_nm_s > 0.0
        if not changing or math.isnan(self.change_start_s):  # the isolation's sums start
            self.change_start_s = t_s if changing else math.nan
        self.isolation.add(sig, d, 1.0 / var, duration, changing, drift, viscous,
                           joints_signature(baseline, self._sj * inv))
        if self._gain_follow is not None:  # every window: a drift shows before the change
            self._gain_follow.add(sig, d, 1.0 / var, duration,
                                  temperature - baseline.temperature_c)
        level = self._level(max(self.cusum_pos_nm_s, self.cusum_neg_nm_s))
        if level > OK and self._followed(temperature, baseline.temperature_c):
            self.last_alarm.end(t_s, 'oil' if self._follow is not None else 'drift')
            self.isolation.reset()  # (a drift learnt keeps the signatures, the oil's not)
            self._reset_detection(points=self.baseline is not baseline)
            return
        if level != self.level:
            if self.level == OK:
                self.alarm_onset_s = t_s
            elif level == OK:
                self.alarm_onset_s = math.nan
                self.last_alarm.end(t_s)
            self.level = level
        self._undetectable = self._unseen(self._allowance_s)
        self.isolation.bias.set_prior(self._undetectable)  # a bias it does not see (its bound)
        self._publish_fit()
        if self.level != OK:
            self.last_alarm.during(self.alarm_onset_s, self.level, max(self.cusum_pos_nm_s,
                                   self.cusum_neg_nm_s), *self.verdict(1.0), self.theta_vp,
                                   self.valve_plate_scale_std)

    def _followed(self, temperature_c: float, reference_c: float) -> bool:
        """Follow a change that is the oil's, not the pump's; return whether (no alarm)."""
        if self._follow is not None and self.cusum_neg_nm_s > self.cusum_pos_nm_s:
            followed = self._follow.follow(self.isolation, self.fit)  # the oil thinning
            if followed is not None:
                self.baseline = followed
            return followed is not None
        return self._gain_follow is not None and self._gain_follow.follow(
            self.isolation, temperature_c, reference_c, self.last_alarm.verdict_under_way)

    def _learn(self, h: np.ndarray, e_nm: float, weight: float, duration_s: float,
               t_s: float, temperature_c: float) -> None:
        """Add a commissioning window; complete the baseline once learnt and stationary."""
        if self.commissioning.add(h, e_nm, weight, duration_s, t_s, temperature_c):
            self.baseline = self.fit  # (nothing followed: only `reset` leads back here)
            self._reset_detection()
            if self._hold is not None:  # a pause is counted from the last window learnt
                self._hold.reset(t_s)
        else:
            self._publish_fit()

    def _set_signatures(self) -> None:
        """Make the causes' signature matrix and its RMS per cause over commissioning."""
        if self.baseline is None:
            self._m = np.zeros((len(DETECTED_CAUSES), N_TERMS))
            self._norm = np.ones(len(DETECTED_CAUSES))
            self._undetectable = np.zeros(len(DETECTED_CAUSES))
            self._unseen_nm = 0.0
            return
        self._m = signature_matrix(self.baseline, self._drive_loss, self._inertia)
        weight = max(self.learner.weight, 1e-300)
        second = self._m @ self.learner.a @ self._m.T / weight
        self._norm = np.sqrt(np.maximum(np.diag(second), 1e-12))
        # the change the CUSUMs do not see (`undetectable_change`)
        prediction_std = math.sqrt(max(float(np.trace(self.baseline.covariance
                                                      @ self.learner.a)) / weight, 0.0))
        self._unseen_nm = self._k + self._sigmas * prediction_std
        self._undetectable = self._unseen(self._allowance_s)
        self.isolation.bias.set_prior(self._undetectable)

    def _unseen(self, running_s: float) -> np.ndarray:
        """Return the undetectable change per cause, with the allowances' mean since."""
        margin = self._unseen_nm - self._k
        if running_s > 0.0:
            margin += (self._allowance_nm_s + self._gain_allowance_nm_s) / running_s
        return undetectable_change(self._k, self._norm, margin, self._recent_s2,
                                   self._recent_s, _UNSEEN_CAP)

    def _publish_fit(self) -> None:
        """Publish the scales: the fit against the model while learning, then the change."""
        floor = self._floor
        if self.baseline is not None:  # the change from it (none under way: 1 +- unseen)
            self.theta_vp, self.valve_plate_scale_std, self.theta_rest, self.rest_scale_std = \
                self.isolation.scales(self.baseline, self._undetectable, self.level != OK,
                                      self.oil_moved)
            return
        coef, std = self.fit.coefficients, self.fit.std()
        self.theta_vp = 1.0 + float(coef[0])
        self.theta_rest = 1.0 + float(coef[1])
        self.valve_plate_scale_std = math.hypot(float(std[0]), floor)
        self.rest_scale_std = math.hypot(float(std[1]), floor)

    def _level(self, s: float) -> int:
        if s >= self._h_error or (self.level == ERROR and s > self._clear * self._h_error):
            return ERROR
        if s >= self._h_warn or (self.level >= WARN and s > self._clear * self._h_warn):
            return WARN
        return OK
