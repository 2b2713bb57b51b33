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
Closed-loop position-controlled EHA: setpoints, loops, cylinder and load, at a fixed step.

The pump (displacement V_g) drives an equal-area cylinder of area A; leakage C, so the
cylinder speed is v = (V_g omega / (2 pi) - C dp) / A = r omega - C dp / A with
r = V_g / (2 pi A). Its load is F = m a + c v + k (x - x_mid) + m g s (m with the payload),
and the pressure difference is dp = F / A (the pump's flow is the cylinder's: no
compressibility). The position loop (P or PI, with the setpoint's speed fed forward)
commands the pump speed; the command is limited in size and slew rate; the speed loop is a
first-order lag of bandwidth w_b, integrated exactly over each step with the command held,
so the speed, its derivative a = w_b (command - speed) at the sample, and the angle are
exact for that command. The drive delivers whatever torque this takes (the torque the
motor needs is computed from the result in ``eha_scenarios``). Leakage is taken with the
pressure of the step before (semi-implicit). A plain loop over steps in Python floats:
about 1 us of work per line and step, ~3 s per simulated half hour.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from .eha_settings import CylinderSettings, LoadSettings, LoopSettings, SetpointSettings

__all__ = ['ClosedLoopRun', 'Plant', 'Setpoints', 'draw_plant', 'make_setpoints',
           'simulate_closed_loop']


@dataclass(frozen=True)
class Plant:
    """One drawn actuator: cylinder, load and loops (SI)."""

    displacement_m3: float
    area_m2: float
    stroke_m: float
    leakage_m3_s_pa: float
    mass_kg: float
    payload_kg: float
    gravity_sine: float
    gravity_m_s2: float
    spring_n_m: float
    damping_n_s_m: float
    position_gain_1_s: float
    integral_gain_1_s2: float
    integral_limit_rad_s: float
    velocity_feedforward: bool
    speed_bandwidth_rad_s: float
    slew_rad_s2: float
    max_speed_rad_s: float
    step_s: float

    @property
    def metres_per_rad(self) -> float:
        """Cylinder travel per pump revolution angle, r = V_g / (2 pi A) [m/rad]."""
        return self.displacement_m3 / (2.0 * math.pi * self.area_m2)

    @property
    def mid_m(self) -> float:
        """Mid-stroke, where the spring is relaxed [m]."""
        return 0.5 * self.stroke_m

    def static_force_n(self, position_m: float, payload_kg: float = 0.0) -> float:
        """Return the load at rest, gravity and spring, at a position [N]."""
        return (self.mass_kg + payload_kg) * self.gravity_m_s2 * self.gravity_sine + \
            self.spring_n_m * (position_m - self.mid_m)


def _draw(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.uniform(*bounds))


def draw_plant(cylinder: CylinderSettings, load: LoadSettings, loop: LoopSettings,
               displacement_m3: float, rng: np.random.Generator) -> Plant:
    """
    Draw one actuator from its ranges.

    Parameters
    ----------
    cylinder, load, loop : settings
        Ranges of the cylinder, its load and the loops.
    displacement_m3 : float
        The pump's displacement per revolution [m^3].
    rng : numpy.random.Generator
        The scenario's stream.

    Returns
    -------
    Plant
        Gravity with payload plus spring scaled down to ``load.max_static_pressure_pa``.

    """
    area, stroke = _draw(rng, cylinder.area_m2), _draw(rng, cylinder.stroke_m)
    leakage = _draw(rng, cylinder.leakage_m3_s_pa)
    mass, payload = _draw(rng, load.mass_kg), _draw(rng, load.payload_kg)
    sine = _draw(rng, load.gravity_sine)
    spring_pa, damping_pa = _draw(rng, load.spring_pressure_pa), _draw(rng,
                                                                       load.damping_pressure_pa)
    kp = _draw(rng, loop.position_gain_1_s)
    ki = _draw(rng, loop.integral_ratio) * kp * kp
    bandwidth = 2.0 * math.pi * _draw(rng, loop.speed_bandwidth_hz)
    slew, max_speed = _draw(rng, loop.slew_rad_s2), _draw(rng, loop.max_speed_rad_s)
    static_pa = (mass + payload) * load.gravity_m_s2 * abs(sine) / area + spring_pa
    if static_pa > load.max_static_pressure_pa:  # keep the pressure inside the tables
        scale = load.max_static_pressure_pa / static_pa
        sine, spring_pa = sine * scale, spring_pa * scale
    max_cyl_speed = displacement_m3 * max_speed / (2.0 * math.pi * area)
    return Plant(displacement_m3, area, stroke, leakage, mass, payload, sine,
                 load.gravity_m_s2, spring_pa * area / (0.5 * stroke),
                 damping_pa * area / max_cyl_speed, kp, ki,
                 loop.integral_limit_fraction * max_speed, loop.velocity_feedforward,
                 bandwidth, slew, max_speed, loop.step_s)


@dataclass(frozen=True)
class Setpoints:
    """Position setpoint, its speed (feedforward) and the payload carried, per step."""

    position_m: np.ndarray
    speed_m_s: np.ndarray
    payload_kg: np.ndarray
    moves: int


def _target(s: SetpointSettings, plant: Plant, now: float, move: int,
            rng: np.random.Generator) -> float:
    low, high = s.margin_fraction * plant.stroke_m, (1.0 - s.margin_fraction) * plant.stroke_m
    if rng.random() < s.small_move_probability:
        step = _draw(rng, s.small_move_fraction) * plant.stroke_m * (
            1.0 if rng.random() < 0.5 else -1.0)
        return float(np.clip(now + step, low, high))
    if s.pick_place:
        zone = s.zone_fraction * plant.stroke_m
        return _draw(rng, (low, low + zone) if move % 2 == 0 else (high - zone, high))
    return _draw(rng, (low, high))


def make_setpoints(s: SetpointSettings, plant: Plant, n: int, rng: np.random.Generator
                   ) -> Setpoints:
    """
    Make the setpoint of ``n`` steps: moves (steps or ramps) to targets, dwells between.

    A step jumps by at most ``s.step_max_fraction`` of the stroke; a ramp is a cycloidal
    profile (bell-shaped speed) whose peak speed is drawn and whose peak acceleration stays
    within half the speed command's slew limit, so the loop follows it without overshoot.

    Pick-and-place: targets alternate between the pick zone (the stroke's start) and the
    place zone (its end); the gripper closes half-way through the dwell at the pick and
    opens half-way through the dwell at the place, so the payload is carried in between.

    Parameters
    ----------
    s : SetpointSettings
        Move and dwell ranges.
    plant : Plant
        The actuator (stroke, max speed, step).
    n : int
        Number of steps.
    rng : numpy.random.Generator
        The scenario's stream.

    Returns
    -------
    Setpoints
        Arrays of ``n`` values.

    """
    dt = plant.step_s
    end = n * dt
    max_cyl = plant.metres_per_rad * plant.max_speed_rad_s
    knots_t, knots_x = [0.0], [plant.mid_m]
    carry_t: list[float] = []  # gripper close / open times
    now, move, holding = 0.0, 0, False
    accel = 0.5 * plant.metres_per_rad * plant.slew_rad_s2  # profiles stay inside the slew
    while knots_t[-1] < end:
        start_x = knots_x[-1]
        target = _target(s, plant, start_x, move, rng)
        move += 1
        if rng.random() < s.step_probability:  # a step: the feedforward has nothing to add
            limit = s.step_max_fraction * plant.stroke_m
            target = start_x + float(np.clip(target - start_x, -limit, limit))
            knots_t.append(knots_t[-1] + 1e-3 * dt)
            knots_x.append(target)
        else:  # cycloidal ramp: x_a + d (u - sin(2 pi u) / (2 pi)), u = (t - t_a) / T
            distance = target - start_x
            peak = _draw(rng, s.ramp_speed_fraction) * max_cyl
            duration = max(2.0 * abs(distance) / peak,
                           math.sqrt(2.0 * math.pi * abs(distance) / accel), 2.0 * dt)
            u = np.linspace(0.0, 1.0, max(int(duration / dt), 2) + 1)[1:]
            knots_t.extend((knots_t[-1] + duration * u).tolist())
            knots_x.extend((start_x + distance * (u - np.sin(2.0 * np.pi * u) / (2.0 * np.pi))
                            ).tolist())
        now = knots_t[-1]
        dwell = _draw(rng, s.dwell_s)
        knots_t.append(now + dwell)
        knots_x.append(target)
        if s.pick_place and (move % 2 == 1) != holding:
            carry_t.append(now + 0.5 * dwell)
            holding = not holding
    t = np.arange(n) * dt
    kt, kx = np.array(knots_t), np.array(knots_x)
    position = np.interp(t, kt, kx)
    if plant.velocity_feedforward:  # the setpoint's speed: slope of the knot segment
        slope = np.diff(kx) / np.diff(kt)
        slope[np.diff(kt) < dt] = 0.0  # steps
        seg = np.clip(np.searchsorted(kt, t, side='right') - 1, 0, slope.size - 1)
        speed = slope[seg]
    else:
        speed = np.zeros(n)
    # gripper events alternate close / open: carried where an odd number of them has passed
    carried = np.searchsorted(np.array(carry_t), t, side='right') % 2 == 1
    return Setpoints(position, speed, np.where(carried, plant.payload_kg, 0.0), move)


@dataclass(frozen=True)
class ClosedLoopRun:
    """The true trajectory, one value per step (SI)."""

    t_s: np.ndarray
    speed_rad_s: np.ndarray
    accel_rad_s2: np.ndarray  # d(speed)/dt at the sample
    angle_rad: np.ndarray  # shaft angle, integral of the speed
    position_m: np.ndarray
    cylinder_speed_m_s: np.ndarray
    pressure_diff_pa: np.ndarray  # F / A
    force_n: np.ndarray
    speed_command_rad_s: np.ndarray  # after the size and slew limits


def simulate_closed_loop(plant: Plant, setpoints: Setpoints, start_m: float | None = None
                         ) -> ClosedLoopRun:
    """
    Integrate the actuator through its setpoints (module docstring).

    Parameters
    ----------
    plant : Plant
        The actuator.
    setpoints : Setpoints
        One value per step; their count sets the run's.
    start_m : float, optional
        Initial position [m] (default: the first setpoint), at rest.

    Returns
    -------
    ClosedLoopRun
        The trajectory.

    """
    n = setpoints.position_m.size
    dt, r, area = plant.step_s, plant.metres_per_rad, plant.area_m2
    wb = plant.speed_bandwidth_rad_s
    decay = math.exp(-wb * dt)
    held = -math.expm1(-wb * dt) / wb  # integral over a step of the decaying part
    kp, ki, ilim = plant.position_gain_1_s, plant.integral_gain_1_s2, \
        plant.integral_limit_rad_s * r
    wmax, slew = plant.max_speed_rad_s, plant.slew_rad_s2 * dt
    leak_a = plant.leakage_m3_s_pa / area
    mass, grav = plant.mass_kg, plant.gravity_m_s2 * plant.gravity_sine
    spring, damping, mid = plant.spring_n_m, plant.damping_n_s_m, plant.mid_m
    xs, ff, load = (a.tolist() for a in (setpoints.position_m, setpoints.speed_m_s,
                                         setpoints.payload_kg))
    x = xs[0] if start_m is None else start_m
    w = wc = integ = theta = 0.0
    dp = plant.static_force_n(x, load[0]) / area
    out_w, out_a, out_th, out_x, out_v, out_dp, out_wc = ([0.0] * n for _ in range(7))
    for k in range(n):
        err = xs[k] - x
        integ += ki * err * dt
        integ = ilim if integ > ilim else (-ilim if integ < -ilim else integ)
        cmd = (ff[k] + kp * err + integ) / r
        cmd = wmax if cmd > wmax else (-wmax if cmd < -wmax else cmd)
        step = cmd - wc
        wc += slew if step > slew else (-slew if step < -slew else step)
        acc = wb * (wc - w)
        m = mass + load[k]
        v = r * w - leak_a * dp  # leakage with the previous step's pressure
        dp = (m * (r * acc + grav) + damping * v + spring * (x - mid)) / area
        out_w[k], out_a[k], out_th[k], out_x[k], out_v[k], out_dp[k], out_wc[k] = (
            w, acc, theta, x, v, dp, wc)
        turned = wc * dt + (w - wc) * held
        x += r * turned - leak_a * dp * dt
        theta += turned
        w = wc + (w - wc) * decay
    dp_a = np.array(out_dp)
    return ClosedLoopRun(np.arange(n) * dt, np.array(out_w), np.array(out_a),
                         np.array(out_th), np.array(out_x), np.array(out_v), dp_a,
                         dp_a * area, np.array(out_wc))
