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

"""Friction laws: eq. (9) area and Couette film, eq. (10) Palmgren, against closed forms."""

import dataclasses
import math

import numpy as np
from pump_friction_ros.physics.friction import (
    bearing_torque_nm,
    couette_land_integral_m4,
    smooth_sign,
    valve_plate_viscous_torque_nm,
)
from pump_friction_ros.physics.pump_parameters import barrel_effective_area_m2
import pytest


def test_barrel_effective_area_matches_eq9_by_hand(paper_params):
    # Fig. 2(b) radii in mm, typed from the paper: A_b = 70.882 - 67.659 = 3.2228 mm^2
    assert barrel_effective_area_m2(paper_params.geometry, paper_params.valve_plate) == \
        pytest.approx(3.2228e-6, rel=1e-4)


def test_couette_torque_of_the_lands_at_ten_microns(paper_params):
    vp = dataclasses.replace(paper_params.valve_plate, film_clearance_m=10e-6)
    omega = 10000 * math.pi / 30
    # full annulus pi/2 (R_o^4 - R_i^4) minus two kidneys of (pi - beta)/2 (r_o^4 - r_i^4)
    beta = 2 * math.asin(2.1 / 9.5)
    integral = (math.pi / 2 * (13.25e-3**4 - 6.25e-3**4)
                - (math.pi - beta) / 2 * (11.6e-3**4 - 7.4e-3**4))
    assert couette_land_integral_m4(vp) == pytest.approx(integral, rel=1e-12)
    torque = valve_plate_viscous_torque_nm(omega, 70e-6, 870.0, vp)
    assert torque == pytest.approx(870 * 70e-6 * omega / 10e-6 * integral, rel=1e-12)
    assert 0.15 < torque < 0.18  # ~10x below the paper's ~1.5 Nm viscous part


def test_valve_plate_viscous_torque_is_linear_in_speed_and_viscosity(paper_params):
    vp = paper_params.valve_plate
    base = valve_plate_viscous_torque_nm(100.0, 30e-6, 870.0, vp)
    assert valve_plate_viscous_torque_nm(300.0, 30e-6, 870.0, vp) == pytest.approx(3 * base)
    assert valve_plate_viscous_torque_nm(100.0, 60e-6, 870.0, vp) == pytest.approx(2 * base)


def test_palmgren_viscous_term_scales_with_nu_n_to_two_thirds(paper_params):
    b = paper_params.bearing
    rpm = math.pi / 30
    _, t1 = bearing_torque_nm(0.0, 3000 * rpm, 40e-6, b)
    _, t2 = bearing_torque_nm(0.0, 9000 * rpm, 40e-6, b)
    _, t3 = bearing_torque_nm(0.0, 3000 * rpm, 80e-6, b)
    assert t2 / t1 == pytest.approx(3 ** (2 / 3), rel=1e-12)
    assert t3 / t1 == pytest.approx(2 ** (2 / 3), rel=1e-12)
    d_mm = b.mean_diameter_m * 1e3
    assert t1 == pytest.approx(1e-7 * b.f0 * (40 * 3000) ** (2 / 3) * d_mm**3 * 1e-3)


def test_palmgren_below_threshold_is_the_constant_branch(paper_params):
    b = paper_params.bearing
    d_mm = b.mean_diameter_m * 1e3
    speeds = np.array([0.0, 1.0, 2.0]) * math.pi / 30  # nu n < 2000 cSt rpm at 70 cSt
    _, tv = bearing_torque_nm(0.0, speeds, 70e-6, b)
    np.testing.assert_allclose(tv, 160e-7 * b.f0 * d_mm**3 * 1e-3)


def test_palmgren_load_term_is_f1_load_dm(paper_params):
    b = paper_params.bearing
    tm, _ = bearing_torque_nm(np.array([1000.0, 2000.0]), 100.0, 70e-6, b)
    np.testing.assert_allclose(tm, b.f1 * np.array([1000.0, 2000.0]) * b.mean_diameter_m * 1e3
                               * 1e-3)


def test_smooth_sign_is_odd_bounded_and_saturates():
    w = np.linspace(-50, 50, 1001)
    s = smooth_sign(w, 2.0)
    np.testing.assert_allclose(s, -s[::-1])
    assert np.all(np.abs(s) <= 1.0)
    inner = np.abs(w) < 20.0
    assert np.all(np.diff(s[inner]) > 0)
    assert smooth_sign(8.0, 2.0) > 0.999
