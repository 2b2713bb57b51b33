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

"""Realistic EHA families of the evaluation bank: closed loop, sensors, true pump, streams."""

from dataclasses import replace
from functools import partial
import math

import numpy as np
from pump_friction_ros.core.estimator import TorqueEstimator
from pump_friction_ros.core.monitor import OK, WARN
from pump_friction_ros.evaluation.bank import (
    base_config,
    build_scenarios,
    feed_signals,
    MonitorReading,
    valve_plate_truth,
)
from pump_friction_ros.evaluation.closed_loop import (
    make_setpoints,
    Plant,
    Setpoints,
    simulate_closed_loop,
)
from pump_friction_ros.evaluation.eha_scenarios import (
    draw_eha,
    eha_estimator_config,
    fault_episodes,
    fault_factor,
)
from pump_friction_ros.evaluation.eha_settings import SensorSettings
from pump_friction_ros.evaluation.scenarios import Scenario, simulate_scenario, SimulatedScenario
from pump_friction_ros.evaluation.sensors import encoder_speed, message_indices
from pump_friction_ros.evaluation.settings import (
    FAMILIES,
    FAULTS,
    FULL,
    HELD_OUT_FAMILIES,
    QUICK,
)
from pump_friction_ros.evaluation.true_pump import PumpVariant, true_table
from pump_friction_ros.evaluation.truths import (
    commissioned_factor,
    commissioned_since,
    memory_weighted_factor,
    memory_weighted_since,
)
from pump_friction_ros.physics.friction import valve_plate_viscous_torque_nm
from pump_friction_ros.physics.model import COMPONENTS
from pump_friction_ros.physics.oil import WaltherViscosity
from pump_friction_ros.physics.pump_parameters import load_pump
from pump_friction_ros.table.table_files import cached_table
import pytest

FAMILY = {f.name: f for f in FAMILIES}
FAULT = {f.name: f for f in FAULTS}
CONFIG = base_config()
V_G = 4.898e-6  # the paper pump's displacement [m^3], 5 x pi/4 x 9.5^2 mm^2 x 13.82 mm
QUIET = SensorSettings(pressure_noise_pa=(0.0, 0.0), pressure_offset_pa=(0.0, 0.0),
                       torque_constant_error=(0.02, 0.02), torque_drift_probability=0.0,
                       torque_offset_nm=(0.01, 0.01), torque_noise_nm=(0.0, 0.0),
                       ripple_fraction=(0.0, 0.0), drop_probability=(0.0, 0.0),
                       burst_rate_per_h=(0.0, 0.0), duplicate_probability=(0.0, 0.0))


def plant(**kw):
    base = {'displacement_m3': V_G, 'area_m2': 1.2e-3, 'stroke_m': 0.3,
            'leakage_m3_s_pa': 0.0, 'mass_kg': 400.0, 'payload_kg': 0.0, 'gravity_sine': 0.5,
            'gravity_m_s2': 9.81, 'spring_n_m': 2.0e4, 'damping_n_s_m': 3.0e3,
            'position_gain_1_s': 20.0, 'integral_gain_1_s2': 0.0,
            'integral_limit_rad_s': 50.0, 'velocity_feedforward': False,
            'speed_bandwidth_rad_s': 2 * math.pi * 80.0, 'slew_rad_s2': 2.0e4,
            'max_speed_rad_s': 900.0, 'step_s': 1e-4}
    base.update(kw)
    return Plant(**base)


def hold(p, n, position_m, payload_kg=0.0):
    return Setpoints(np.full(n, position_m), np.zeros(n), np.full(n, payload_kg), 1)


def scenario(family, fault='nominal', duration_s=40.0, onset_s=20.0, sensors=QUIET):
    fam = FAMILY[family]
    if sensors is not None:
        fam = replace(fam, motion=replace(fam.motion, sensors=sensors))
    return Scenario(fam, FAULT[fault], 0, duration_s, onset_s, 10.0, 0, CONFIG)


# -- the closed loop against closed forms -----------------------------------------------------

def test_a_small_step_is_reached_with_the_loops_time_constant():
    # P loop Kp around a first-order speed loop w_b / (s + w_b): x / x_sp has the poles of
    # s^2 + w_b s + Kp w_b = 0, so the step response is 1 - (p2 e^(p1 t) - p1 e^(p2 t)) / (p2 - p1)
    p = plant(slew_rad_s2=1e7)  # a slew this high does not bind: the linear loop
    kp, wb = p.position_gain_1_s, p.speed_bandwidth_rad_s
    root = math.sqrt(wb * wb - 4.0 * kp * wb)
    p1, p2 = (-wb + root) / 2.0, (-wb - root) / 2.0
    t = np.arange(4000) * p.step_s
    closed = 1.0 - (p2 * np.exp(p1 * t) - p1 * np.exp(p2 * t)) / (p2 - p1)
    start, target = 0.15, 0.152
    run = simulate_closed_loop(p, hold(p, t.size, target), start_m=start)
    np.testing.assert_allclose((run.position_m - start) / (target - start), closed, atol=0.01)
    reached = np.argmax(run.position_m - start >= (1.0 - math.exp(-1.0)) * (target - start))
    assert reached * p.step_s == pytest.approx(1.0 / kp, rel=0.1)  # the position loop's 1/Kp
    assert abs(run.position_m[-1] - target) < 1e-6  # no leakage: no steady-state error


def test_static_pressure_is_the_load_over_the_area():
    p = plant(gravity_sine=-0.8, spring_n_m=5.0e4)
    for position, payload in ((0.1, 0.0), (0.27, 150.0)):
        run = simulate_closed_loop(p, hold(p, 2000, position, payload), start_m=position)
        force = (400.0 + payload) * 9.81 * -0.8 + 5.0e4 * (position - 0.15)
        np.testing.assert_allclose(run.pressure_diff_pa, force / 1.2e-3, rtol=1e-12)
        assert np.all(run.speed_rad_s == 0.0)


def test_the_cylinder_moves_by_the_integral_of_the_pump_flow():
    fam = FAMILY['eha_pick_place']
    scen = Scenario(fam, FAULT['nominal'], 3, 60.0, math.inf, 10.0, 0, CONFIG)
    d = draw_eha(scen)
    p = replace(d.plant, leakage_m3_s_pa=1e-13)
    from pump_friction_ros.evaluation.closed_loop import make_setpoints
    sp = make_setpoints(fam.motion.setpoints, p, 60000, np.random.default_rng(1))
    run = simulate_closed_loop(p, sp)
    flow = V_G * run.speed_rad_s / (2 * math.pi) - 1e-13 * run.pressure_diff_pa  # [m^3/s]
    volume = np.concatenate([[0.0], np.cumsum(0.5 * (flow[1:] + flow[:-1]) * 1e-3)])
    gap = run.position_m - run.position_m[0] - volume / p.area_m2
    assert np.abs(gap).max() < 2e-4 * p.stroke_m  # the trapezoid rule's error, not drift
    assert np.ptp(run.position_m) > 0.3 * p.stroke_m  # it did move
    assert run.position_m.min() >= 0.0 and run.position_m.max() <= p.stroke_m
    np.testing.assert_allclose(np.gradient(run.position_m, 1e-3)[1:-1],
                               run.cylinder_speed_m_s[1:-1], atol=0.02)
    # pressure follows the load: dp A = m a + c v + k (x - mid) + m g s
    m = p.mass_kg + sp.payload_kg
    a = p.metres_per_rad * run.accel_rad_s2
    force = m * (a + 9.81 * p.gravity_sine) + p.damping_n_s_m * run.cylinder_speed_m_s + \
        p.spring_n_m * (run.position_m - p.mid_m)
    np.testing.assert_allclose(run.pressure_diff_pa * p.area_m2, force, rtol=1e-9, atol=1e-6)


# -- the true pump --------------------------------------------------------------------------

def test_a_thinner_film_adds_couette_shear_and_coulomb_factors_scale_breakaway():
    params = load_pump(None)
    node = cached_table(params)
    thin = true_table(PumpVariant(film_clearance=0.8))
    sticky = true_table(PumpVariant(valve_plate_coulomb=1.2, bearing_f0=1.2))
    speed, dp, nu = 500.0, 150e5, 46e-6
    vp = COMPONENTS.index('valve_plate')
    base = node.lookup_array(speed, dp, nu)['valve_plate_nm'][0]
    viscous = valve_plate_viscous_torque_nm(speed, nu, params.oil.density_kg_m3,
                                            params.valve_plate)
    # 1/h: at 0.8 h the shear is 1.25 x; the coulomb part does not depend on h
    assert thin.lookup_array(speed, dp, nu)['valve_plate_nm'][0] - base == pytest.approx(
        0.25 * viscous, rel=0.01)
    # at rest there is no shear: the valve plate's torque is its coulomb part, x 1.2
    rest_node = node.magnitudes(0.0, dp, nu, False)[0][vp]
    assert sticky.magnitudes(0.0, dp, nu, False)[0][vp] == pytest.approx(1.2 * rest_node,
                                                                         rel=1e-9)
    assert thin.viscosity_axis_m2_s[-1] == pytest.approx(450e-6)  # cold oil is in the table
    assert node.viscosity_axis_m2_s[-1] == pytest.approx(100e-6)


# -- sensors and message streams ------------------------------------------------------------

def closed_form_torque_nm(scen, sim):
    """
    Return the torque QUIET sensors measure [N m].

    1.02 x the delivered torque + 0.01 N m, with the fault's friction factors, drive loss
    and offset from the onset at 20 s.
    """
    fault, d = scen.fault, draw_eha(scen)
    truth = true_table(d.variant).lookup_array(sim.true_speed_rad_s, sim.true_pressure_diff_pa,
                                               sim.true_viscosity_m2_s)
    after = sim.t_s >= 20.0
    friction = sum(truth[f'{c}_nm'] * np.where(after, fault.factors[c], 1.0)
                   for c in COMPONENTS)
    v_g = load_pump(None).geometry.displacement_m3
    delivered = v_g * sim.true_pressure_diff_pa / (2 * math.pi) + friction + \
        d.rotor_inertia_kg_m2 * sim.true_accel_rad_s2 + \
        (d.drive_loss_nm + fault.drive_loss_nm * after) * np.tanh(sim.true_speed_rad_s / 2.0)
    return 1.02 * delivered + 0.01 + fault.torque_offset_nm * after


def test_measured_torque_is_gain_times_the_delivered_torque_plus_offset():
    scen = scenario('eha_pick_place', 'valve_plate_x1.8')
    sim = simulate_scenario(scen, cached_table(load_pump(None)))
    d = draw_eha(scen)
    np.testing.assert_allclose(sim.torque_nm, closed_form_torque_nm(scen, sim), rtol=1e-9,
                               atol=1e-9)
    assert sim.t_s.size == 40000 and np.all(np.diff(sim.t_s) > 0)  # no drops, no duplicates
    # the node is told the installation's J to +-10 % and its drive loss
    config = scen.estimator_config()
    assert abs(config.rotor_inertia_kg_m2 / d.rotor_inertia_kg_m2 - 1.0) <= 0.1
    assert 5e-4 <= d.rotor_inertia_kg_m2 <= 1e-3
    assert config.drive_loss_torque_nm == d.drive_loss_nm


@pytest.mark.parametrize('name', [f.name for f in FAULTS if f.scope == 'held_out'])
def test_a_held_out_fault_changes_the_measured_signals_by_its_closed_form(name):
    fault = FAULT[name]
    scen = scenario('eha_pick_place', name)
    sim = simulate_scenario(scen, cached_table(load_pump(None)))
    np.testing.assert_allclose(sim.torque_nm, closed_form_torque_nm(scen, sim), rtol=1e-9,
                               atol=1e-9)
    # the pressure sensor (no offset, no noise here) reads the gain times the true one
    gain = np.where(sim.pressure_t_s >= 20.0, fault.pressure_gain, 1.0)
    np.testing.assert_allclose(sim.pressure_diff_pa, gain * np.interp(
        sim.pressure_t_s, sim.t_s, sim.true_pressure_diff_pa), rtol=1e-9, atol=1e-6)
    assert sim.fault_running_nm > 0.0 and sim.vp_truth == 1.0


def test_encoder_speed_is_quantised_and_keeps_the_angle():
    t = np.arange(5000) * 1e-3
    angle = 37.0 * t + 0.2 * np.sin(3.0 * t)
    speed = encoder_speed(angle, 4096, 1e-3, 0.3)
    q = 2 * math.pi / (4096 * 1e-3)
    np.testing.assert_allclose(speed / q, np.round(speed / q), atol=1e-9)
    counted = np.sum(speed[1:]) * 1e-3  # the counted angle, within one count of the truth
    assert abs(counted - (angle[-1] - angle[0])) <= 2 * math.pi / 4096 + 1e-12


def test_dropouts_bursts_and_duplicates_as_counted_streams():
    rng = np.random.default_rng(4)
    t = np.arange(200000) * 1e-3
    windows = np.array([[10.0, 10.25], [100.0, 100.1]])
    idx = message_indices(t, 0.02, 0.01, windows, rng)
    unique = np.unique(idx)
    lost = 200000 - unique.size
    expected = 250 + 100 + 0.02 * (200000 - 350)
    assert abs(lost - expected) < 4 * math.sqrt(0.02 * 200000)
    assert not np.any((t[unique] >= 10.0) & (t[unique] < 10.25))
    dups = idx.size - unique.size
    assert abs(dups - 0.01 * unique.size) < 4 * math.sqrt(0.01 * unique.size)
    assert np.all(np.diff(idx) >= 0)  # in order; a duplicate right after its original


def test_the_node_sees_the_duplicates_as_such():
    noisy = SensorSettings(duplicate_probability=(0.01, 0.01), drop_probability=(0.005, 0.005))
    scen = scenario('eha_steps_no_temp', sensors=noisy, duration_s=20.0)
    table = cached_table(load_pump(None))
    sim = simulate_scenario(scen, table)
    core = TorqueEstimator(scen.estimator_config(), table, 70e-6, 'x')
    feed_signals(core, sim, math.inf)
    joint = int(np.sum(np.diff(sim.t_s) == 0))
    pressure = int(np.sum(np.diff(sim.pressure_t_s) == 0))
    # a JointState duplicate repeats both its speed and its torque sample
    assert joint > 100 and core.counts['rejected_duplicate'] == 2 * joint + pressure
    assert np.unique(sim.t_s).size < 20000  # some were lost


# -- oils, temperatures, faults --------------------------------------------------------------

def test_cold_start_and_the_nodes_viscosity_with_and_without_the_topic():
    table = cached_table(load_pump(None))
    for family, topic in (('eha_cold_start', True), ('eha_cold_no_temp', False)):
        scen = scenario(family, duration_s=30.0)
        d = draw_eha(scen)
        assert 12.0 <= d.temperature_start_c <= 18.0 and 50.0 <= d.temperature_end_c <= 60.0
        sim = simulate_scenario(scen, table)
        law = WaltherViscosity(d.oil.viscosity_40c_m2_s, d.oil.viscosity_100c_m2_s)
        assert sim.true_viscosity_m2_s[0] == pytest.approx(law(d.temperature_start_c), rel=1e-6)
        assert sim.true_viscosity_m2_s[0] > 100e-6  # beyond the node's table: cold oil
        config = eha_estimator_config(scen)
        assert config.oil_viscosity_40c_m2_s == d.oil.viscosity_40c_m2_s
        if topic:
            assert config.viscosity_source == 'temperature' and sim.temperature_t_s.size == 300
        else:
            assert config.viscosity_source == 'parameter' and sim.temperature_t_s.size == 0
            assert config.oil_viscosity_m2_s == pytest.approx(law(50.0), rel=1e-12)


def test_fault_factors_steps_ramps_and_episodes():
    t = np.arange(0.0, 1000.0, 0.5)
    rng = np.random.default_rng(0)
    step = FAULT['torque_constant_-5%']
    assert fault_episodes(step, 100.0, t[-1], rng).size == 0  # not intermittent: no draw
    ramp = fault_factor(step, 0.95, t, 100.0, 600.0, np.zeros(0))
    assert np.all(ramp[t <= 100.0] == 1.0) and ramp[t == 400.0][0] == pytest.approx(0.975)
    assert np.all(ramp[t >= 700.0] == pytest.approx(0.95))
    fault = FAULT['valve_plate_intermittent_1.8']
    assert fault_episodes(fault, math.inf, t[-1], rng).size == 0  # never starts
    f = fault_factor(fault, 1.8, t, 100.0, 600.0, fault_episodes(fault, 100.0, t[-1], rng))
    assert np.all(f[t < 100.0] == 1.0) and f[t == 100.0][0] == 1.8
    edges = t[1:][np.diff(f) != 0]  # the onset, then each end of an episode
    lengths = np.diff(edges)
    assert np.all(lengths[0::2] >= 20.0 - 0.5) and np.all(lengths[0::2] <= 90.0 + 0.5)
    assert np.all(lengths[1::2] >= 20.0 - 0.5) and np.all(lengths[1::2] <= 180.0 + 0.5)
    assert set(np.unique(f)) == {1.0, 1.8}


def test_an_intermittent_fault_moves_all_its_factors_in_the_same_episodes():
    fault = replace(FAULT['valve_plate_intermittent_1.8'], drive_loss_nm=0.1,
                    pressure_gain=0.95)
    t = np.arange(0.0, 3000.0, 0.01)  # the joint-state grid
    tp = np.arange(0.003, 3000.0, 1.0 / 120.0)  # a pressure sensor's own, slower grid
    episodes = fault_episodes(fault, 500.0, t[-1], np.random.default_rng(4))
    assert episodes.size >= 10 and episodes[0] == 500.0 and episodes[-1] >= t[-1]
    friction = np.asarray(fault_factor(fault, 1.8, t, 500.0, 0.0, episodes))
    share = np.asarray(fault_factor(fault, 2.0, t, 500.0, 0.0, episodes)) - 1.0
    gain = np.asarray(fault_factor(fault, fault.pressure_gain, tp, 500.0, 0.0, episodes))
    starts, ends = episodes[0::2], episodes[1::2]  # each 'on' episode [start, end)

    def inside(times):
        return ((times[:, None] >= starts[None, :len(ends)])
                & (times[:, None] < ends[None, :])).any(axis=1)

    np.testing.assert_array_equal(friction, np.where(inside(t), 1.8, 1.0))
    np.testing.assert_array_equal(share, inside(t).astype(float))  # comes and goes with it
    np.testing.assert_array_equal(gain, np.where(inside(tp), 0.95, 1.0))  # on its own grid


# -- bank sizes -------------------------------------------------------------------------------

def test_bank_sizes_of_the_realistic_families():
    realistic = [f.name for f in FAMILIES if f.realistic]
    eha_faults = [f.name for f in FAULTS if f.scope == 'eha']
    full = [s for s in build_scenarios(FULL) if s.family.realistic]
    nominal_h = sum(s.duration_s for s in full if s.fault.name == 'nominal') / 3600.0
    assert nominal_h >= 10.0
    for family in realistic:
        for fault in eha_faults:
            runs = [s for s in full if s.family.name == family and s.fault.name == fault]
            assert len(runs) >= 3 and all(1800.0 <= s.onset_s <= 1860.0 for s in runs)
    assert all(s.fault.scope in ('eha', 'all') for s in full)
    quick = [s for s in build_scenarios(QUICK) if s.family.realistic]
    assert len(quick) <= 8 and all(s.duration_s <= 180.0 for s in quick)
    classic = [s for s in build_scenarios(FULL) if not s.family.realistic]
    assert all(s.fault.scope in ('classic', 'all') for s in classic)


def test_the_held_out_bank_runs_what_the_bank_holds_out_at_its_size():
    held = [f.name for f in HELD_OUT_FAMILIES]
    realistic = [f.name for f in FAMILIES if f.realistic]
    held_faults = [f.name for f in FAULTS if f.scope == 'held_out']
    assert all(f.realistic for f in HELD_OUT_FAMILIES)
    assert not set(held) & {f.name for f in FAMILIES} and len(held_faults) == 5
    bank = build_scenarios(FULL)
    assert not any(s.family.name in held or s.fault.name in held_faults for s in bank)
    runs = build_scenarios(replace(FULL, held_out=True))

    def size(scenarios, family, faults):  # per fault: run lengths, onsets in range
        return {fault: sorted((s.duration_s, 1800.0 <= s.onset_s <= 1860.0 or
                               s.onset_s == math.inf) for s in scenarios
                              if s.family.name == family and s.fault.name == fault)
                for fault in faults}

    bank_faults = [f.name for f in FAULTS if f.scope in ('eha', 'all')]
    for family in held:  # every realistic fault, as the bank runs pick and place
        assert size(runs, family, bank_faults) == size(bank, 'eha_pick_place', bank_faults)
    for family in held + realistic:  # the held-out faults on every realistic family
        assert size(runs, family, held_faults) == {
            fault: [(FULL.eha.fault_duration_s, True)] * 3 for fault in held_faults}
    assert len(runs) == len(held) * (len(bank_faults) + len(held_faults)) * 3 + \
        len(realistic) * len(held_faults) * 3  # nothing the bank runs


def test_the_held_out_duty_cycles_are_what_their_names_say():
    held = {f.name: f for f in HELD_OUT_FAMILIES}
    p = plant()
    max_step_m = p.metres_per_rad * p.max_speed_rad_s * p.step_s  # a ramp at the loop's top

    def setpoints(family):  # 200 s of setpoints
        return make_setpoints(family.motion.setpoints, p, 2_000_000, np.random.default_rng(3))

    def moves(family):  # fraction of the moves that are steps (jumps); sizes [stroke]
        sp = setpoints(family)
        steps = np.count_nonzero(np.abs(np.diff(sp.position_m)) > max_step_m)
        still = np.diff(np.concatenate([[0], np.diff(sp.position_m) == 0.0, [0]]).astype(int))
        start, stop = np.flatnonzero(still == 1), np.flatnonzero(still == -1)
        targets = sp.position_m[stop[stop - start >= 2500]]  # dwells of 0.25 s or more
        return steps / sp.moves, np.abs(np.diff(targets)) / p.stroke_m

    # ramps only: no setpoint jump; the bank's steps jump by up to 15 % of the stroke
    assert np.abs(np.diff(setpoints(held['eha_ramps_temp']).position_m)).max() <= max_step_m
    assert np.abs(np.diff(setpoints(FAMILY['eha_steps_no_temp']).position_m)).max() > \
        100.0 * max_step_m
    # jerky: 70 % of the moves steps and half of all moves small corrections (<= 5 % of the
    # stroke; a move anywhere falls there about a tenth of the time), against 40 % and a
    # fifth on the bank's steps
    jerky_steps, jerky_sizes = moves(held['eha_jerky_temp'])
    bank_steps, bank_sizes = moves(FAMILY['eha_steps_no_temp'])
    assert jerky_steps > 0.55 > 0.5 > bank_steps
    assert np.mean(jerky_sizes <= 0.05) > 0.45 > 0.4 > np.mean(bank_sizes <= 0.05)
    # long dwells: fewer moves than pick and place with its dwells of 0.3-3 s
    assert setpoints(held['eha_long_dwell']).moves < 0.5 * setpoints(
        FAMILY['eha_pick_place']).moves
    # a thermostat oil without topic: no swing, the node told one viscosity
    for rep in range(5):
        scen = Scenario(held['eha_pnp_nt_thermo'], FAULT['nominal'], rep, 30.0, math.inf,
                        10.0, 0, CONFIG)
        assert draw_eha(scen).temperature_swing_c == 0.0
        assert eha_estimator_config(scen).viscosity_source == 'parameter'


def test_the_intermittent_truth_is_the_factor_the_isolation_memory_holds():
    n, dt = 20000, 1e-3
    on = np.where((np.arange(n) // 2000) % 2 == 0, 1.8, 1.0)  # 2 s on, 2 s off
    sig = np.full(n, 0.2)
    taken = np.ones(n, dtype=bool)
    # a memory far longer than the run: the plain mean, half on and half off
    assert memory_weighted_factor(on, sig, taken, dt, 1e9) == pytest.approx(1.4, abs=1e-6)
    # a memory of a few samples: the factor at the end (an off episode)
    assert memory_weighted_factor(on, sig, taken, dt, 1e-4) == pytest.approx(1.0, abs=1e-6)
    # the samples the monitor does not take do not count, and a larger signature weighs more
    assert memory_weighted_factor(on, sig, on > 1.0, dt, 1e9) == pytest.approx(1.8)
    big = np.where(on > 1.0, 0.4, 0.2)  # on-samples weigh 4x: (4 x 1.8 + 1) / 5
    assert memory_weighted_factor(on, big, taken, dt, 1e9) == pytest.approx(1.64, abs=1e-6)
    # exponential memory: closed form for a step at the middle, memory tau
    step = np.where(np.arange(n) >= n // 2, 1.8, 1.0)
    tau = 3.0
    w_on = 1.0 - math.exp(-10.0 / tau)  # the last 10 s, relative weight
    expected = 1.0 + 0.8 * w_on / (1.0 - math.exp(-20.0 / tau))
    assert memory_weighted_factor(step, sig, taken, dt, tau) == pytest.approx(expected, abs=1e-3)


def test_the_intermittent_truth_counts_from_where_the_change_under_way_began():
    n, dt = 18000, 1e-3
    t = np.arange(n) * dt
    on = np.where((np.arange(n) // 2000) % 2 == 0, 1.8, 1.0)  # 2 s on, 2 s off; on 16-18 s
    sig = np.full(n, 0.2)
    taken = (np.arange(n) % 3) != 0  # the monitor takes some samples only
    for memory in (1e9, 3.0, 0.5):
        # from the onset: the factor over every sample taken
        assert memory_weighted_since(t[taken], on[taken], sig[taken], dt, memory,
                                     -math.inf) == memory_weighted_factor(on, sig, taken, dt,
                                                                          memory)
        # a change that cleared in the off episode and began again at 16 s: that episode's
        assert memory_weighted_since(t[taken], on[taken], sig[taken], dt, memory,
                                     16.0) == pytest.approx(1.8)
    # from the middle of the last off episode (14-16 s): 1 s off, 2 s on, by running
    assert memory_weighted_since(t[taken], on[taken], sig[taken], dt, 1e9,
                                 15.0) == pytest.approx((1.0 + 2 * 1.8) / 3, abs=1e-3)
    # with a memory of 0.5 s: the integral of exp(-age / m) over each part, age in running
    # taken (2 of 3 samples: 2 s of time is 4/3 s of running), closed form
    m, on_s, off_s = 0.5, 2.0 * 2 / 3, 1.0 * 2 / 3
    w_on, w_off = 1.0 - math.exp(-on_s / m), math.exp(-on_s / m) - math.exp(-(on_s + off_s) / m)
    assert memory_weighted_since(t[taken], on[taken], sig[taken], dt, m, 15.0) == \
        pytest.approx((1.8 * w_on + 1.0 * w_off) / (w_on + w_off), abs=2e-3)


def test_a_reading_in_alarm_is_held_to_the_truth_of_the_change_it_reads():
    n, dt = 18000, 1e-3
    t = np.arange(n) * dt
    on = np.where((np.arange(n) // 2000) % 2 == 0, 1.8, 1.0)  # on 16-18 s
    since = partial(memory_weighted_since, t, on, np.full(n, 0.2), dt, 1e9)
    arrays = dict.fromkeys((
        't_s', 'speed_rad_s', 'torque_nm', 'pressure_t_s', 'pressure_diff_pa',
        'temperature_t_s', 'temperature_c', 'true_speed_rad_s', 'true_accel_rad_s2',
        'true_pressure_diff_pa', 'true_viscosity_m2_s', 'true_temperature_c'), np.zeros(0))
    sim = SimulatedScenario(**arrays, motion={}, vp_truth=since(-math.inf), other_truth=1.0,
                            other_truth_exact=True, above_min_speed_fraction=1.0,
                            vp_truth_since=since)
    assert sim.vp_truth == pytest.approx((5 * 1.8 + 4 * 1.0) / 9, abs=1e-3)
    began = MonitorReading(WARN, 'valve_plate', 1.8, 0.05, 1.0, 0.1, 16.0)
    assert valve_plate_truth(sim, began) == pytest.approx(1.8)  # that episode's
    # no alarm: a scale of 1 spanning the unseen change over the memory since the onset
    assert valve_plate_truth(sim, began._replace(level=OK)) == sim.vp_truth
    assert valve_plate_truth(sim, began._replace(change_start_s=math.nan)) == sim.vp_truth
    # a fault that stays: its factor at the end, whatever the monitor holds
    assert valve_plate_truth(replace(sim, vp_truth_since=None), began) == sim.vp_truth


def test_a_baseline_learnt_after_the_onset_holds_the_factor_of_its_last_learnt_running():
    dt, learn = 1e-3, 2.0
    t = np.arange(20000) * dt  # 20 s, a step x1.8 at 5 s and a ramp 1 -> 1.6 over 10-16 s
    step = np.where(t >= 5.0, 1.8, 1.0)
    ramp = 1.0 + 0.6 * np.clip((t - 10.0) / 6.0, 0.0, 1.0)
    sig = np.full(t.size, 0.2)
    running = (np.arange(t.size) % 2) == 0  # half the samples: 2 s of running is 4 s of time
    step_at = commissioned_since(step, t, sig, running, learn)
    assert step_at(4.0) == 1.0  # learnt before the onset: the healthy pump, exactly
    assert step_at(9.5) == pytest.approx(1.8)  # its last 4 s after the onset: all of it
    assert step_at(6.0) == pytest.approx(1.0 + 0.8 * 1.0 / 4.0, abs=1e-3)  # 1 of its 4 s
    # a ramp: the mean over its last 4 s of time (linear: the factor at their middle)
    assert commissioned_since(ramp, t, sig, running, learn)(14.0) == \
        pytest.approx(1.0 + 0.6 * 2.0 / 6.0, abs=1e-3)
    # exactly the last learn_s / dt samples up to and including the one at learnt_s
    ones = np.arange(10.0)  # 1 s apart, the factor 1 + t / 10
    assert commissioned_factor(ones, 1.0 + ones / 10.0, np.ones(10), 1.0, 4.0, 6.0) == \
        pytest.approx(1.0 + (3 + 4 + 5 + 6) / 40.0, rel=1e-12)
    assert commissioned_factor(ones, 1.0 + ones / 10.0, np.ones(10), 1.0, 4.0, 5.5) == \
        pytest.approx(1.0 + (2 + 3 + 4 + 5) / 40.0, rel=1e-12)
    assert commissioned_factor(ones, 1.0 + ones / 10.0, np.ones(10), 1.0, 4.0, 1.0) == \
        pytest.approx(1.0 + (0 + 1) / 20.0, rel=1e-12)  # fewer than learn_s: those there
    # least squares weighs each sample by its signature squared
    heavy = np.where(t < 8.0, 0.1, 0.3)
    mixed = commissioned_factor(t, np.where(t >= 7.5, 1.8, 1.0), heavy, dt, 2.0, 8.9995)
    assert mixed == pytest.approx((0.005 * 1.0 + 0.005 * 1.8 + 0.09 * 1.8) / 0.1, abs=1e-3)
    assert commissioned_since(1.0, t, sig, running, learn) is None  # no valve-plate fault
    assert commissioned_factor(t, step, sig, dt, learn, -1.0) == 1.0  # nothing before


def test_a_scale_from_a_baseline_learnt_after_the_onset_is_held_to_the_change_since():
    dt = 1e-3
    t = np.arange(20000) * dt
    step = np.where(t >= 5.0, 1.8, 1.0)
    arrays = dict.fromkeys((
        't_s', 'speed_rad_s', 'torque_nm', 'pressure_t_s', 'pressure_diff_pa',
        'temperature_t_s', 'temperature_c', 'true_speed_rad_s', 'true_accel_rad_s2',
        'true_pressure_diff_pa', 'true_viscosity_m2_s', 'true_temperature_c'), np.zeros(0))
    sim = SimulatedScenario(**arrays, motion={}, vp_truth=1.8, other_truth=1.0,
                            other_truth_exact=True, above_min_speed_fraction=1.0,
                            vp_commissioned=commissioned_since(step, t, np.full(t.size, 0.2),
                                                               np.ones(t.size, bool), 2.0))
    quiet = MonitorReading(OK, 'none', 1.0, 0.05, 1.0, 0.1, math.nan)
    assert valve_plate_truth(sim, quiet) == 1.8  # (no learnt time given: the healthy pump)
    assert valve_plate_truth(sim, quiet, 3.0) == 1.8  # learnt before the onset
    assert valve_plate_truth(sim, quiet, 12.0) == pytest.approx(1.0)  # commissioned worn
    assert valve_plate_truth(sim, quiet, math.inf) == 1.8  # never learnt: the factor
