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
The table covers the oil: its viscosity axis spans the configured oil as it runs (issue 17).

Viscosities come from the ASTM D341 closed form written out here, not from the package's
law; accuracy is judged against the full model (360 angles).
"""

import math
import re

import numpy as np
from pump_friction_ros.core.estimator_setup import estimator_from_config
from pump_friction_ros.core.inputs import InputKind, TEMPERATURE_RANGE_C
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.core.oil_range import table_spec_for
from pump_friction_ros.physics.model import COMPONENTS, PumpModel
from pump_friction_ros.physics.oil import WaltherViscosity
from pump_friction_ros.table.friction_table import build_table, TableSpec, VISCOSITY_CLAMPED
from pump_friction_ros.table.table_files import cached_table_path
import pytest

OILS = {'VG32': (32e-6, 5.4e-6), 'VG46': (46e-6, 6.8e-6), 'VG68': (68e-6, 8.7e-6)}
COLD_START_CST = 1000.0  # config/torque_estimator.yaml, cold_start_viscosity_m2_s


def astm_d341(nu40_cst, nu100_cst):
    """Return (nu(T) [cSt], T(nu) [degC]): log10 log10(nu + 0.7) = A - B log10(T [K])."""
    z40, z100 = (math.log10(math.log10(v + 0.7)) for v in (nu40_cst, nu100_cst))
    t40, t100 = math.log10(313.15), math.log10(373.15)
    b = (z40 - z100) / (t100 - t40)
    a = z40 + b * t40

    def nu(t_c):
        return 10.0 ** 10.0 ** (a - b * math.log10(t_c + 273.15)) - 0.7

    def temperature(nu_cst):
        return 10.0 ** ((a - math.log10(math.log10(nu_cst + 0.7))) / b) - 273.15

    return nu, temperature


def oil_config(oil, **overrides):
    nu40, nu100 = OILS[oil]
    return EstimatorConfig(viscosity_source='temperature', oil_viscosity_40c_m2_s=nu40,
                           oil_viscosity_100c_m2_s=nu100, **overrides)


@pytest.fixture(scope='module')
def cache(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        path = tmp_path_factory.mktemp('cache')
        mp.setenv('XDG_CACHE_HOME', str(path))
        yield path / 'pump_friction_ros'


@pytest.fixture(scope='module')
def cores(cache):
    """Return the estimators of the default config for VG 32 and VG 68 (each builds its table)."""
    return {oil: estimator_from_config(oil_config(oil)) for oil in ('VG32', 'VG68')}


def run_at(core, temperature_c, n=5, start_ns=0):
    """Feed n estimates at one oil temperature; return the last estimate."""
    est = None
    for i in range(n):
        ns = start_ns + (i + 1) * 1_000_000
        core.on_input(InputKind.OIL_TEMPERATURE, ns, temperature_c)
        core.on_input(InputKind.LOAD_PRESSURE, ns, 120e5)
        est = core.on_input(InputKind.JOINT_STATE, ns, 300.0, 2.0)
    return est


def test_the_temperature_law_solved_for_temperature_is_the_closed_form():
    _, temperature = astm_d341(46.0, 6.8)
    law = WaltherViscosity(46e-6, 6.8e-6)
    for nu_cst in (1.5, 10.0, 46.0, 1000.0, 5000.0):
        expected = temperature(nu_cst)
        assert law.temperature_c(nu_cst * 1e-6) == pytest.approx(expected, abs=1e-9)


def test_vg32_at_15_degc_and_vg68_at_the_cold_start_limit_are_not_clamped(cores):
    nu32, _ = astm_d341(32.0, 5.4)
    core = cores['VG32']
    est = run_at(core, 15.0)
    assert est.viscosity_m2_s * 1e6 == pytest.approx(nu32(15.0), rel=1e-9)
    assert est.viscosity_m2_s > 100e-6  # beyond the old 10-100 cSt axis
    est = run_at(core, TEMPERATURE_RANGE_C[1], start_ns=10**9)  # the hottest accepted oil
    assert est.viscosity_m2_s * 1e6 == pytest.approx(nu32(250.0), rel=1e-9)
    assert core.counts['clamped_to_table'] == 0 and core.counts['estimates'] == 10
    _, t68 = astm_d341(68.0, 8.7)
    core = cores['VG68']
    at_limit_c = math.ceil(t68(COLD_START_CST) * 100.0) / 100.0  # a 0.01 degC sensor
    est = run_at(core, at_limit_c)
    assert est.viscosity_m2_s * 1e6 == pytest.approx(COLD_START_CST, rel=2e-3)
    assert est.table_flags == 0 and core.counts['clamped_to_table'] == 0
    assert core.table_coverage == '' and cores['VG32'].table_coverage == ''


def test_oil_beyond_the_cold_start_limit_is_counted_and_said_in_the_diagnostics(cores):
    core = cores['VG68']
    core.reset()
    nu68, _ = astm_d341(68.0, 8.7)
    est = run_at(core, -20.0, n=7)
    assert est.table_flags == VISCOSITY_CLAMPED
    assert core.counts['clamped_to_table'] == 7
    message = core.diagnostics(est.stamp_ns).message
    found = re.findall(r'oil viscosity ([\d.e+]+) cSt outside the table \(([\d.]+)-([\d.]+) '
                       r'cSt\): torque taken at the edge', message)
    assert len(found) == 1, message  # once in the status, not once per sample
    nu, low, high = (float(x) for x in found[0])
    assert nu == pytest.approx(nu68(-20.0), rel=1e-3)  # 9,354 cSt
    assert low == pytest.approx(nu68(250.0), rel=1e-3) and high == COLD_START_CST
    est = run_at(core, 20.0, start_ns=10**9)  # warmed up: the state, and the words, end
    assert est.table_flags == 0 and core.counts['clamped_to_table'] == 7
    assert 'outside the table' not in core.diagnostics(est.stamp_ns).message


def test_the_cache_key_differs_for_different_oils_and_holds_their_range(cores, cache,
                                                                        paper_params):
    nu = 70e-6
    paths = {oil: cached_table_path(paper_params, table_spec_for(oil_config(oil), nu))
             for oil in OILS}
    assert len(set(paths.values())) == 3
    assert paths['VG46'] == cached_table_path(paper_params,
                                              table_spec_for(oil_config('VG46'), nu))
    assert '-nu0.965-1000cSt-' in paths['VG32'].name  # VG 32 at 250 degC
    assert sorted(cache.glob('*.npz')) == sorted([paths['VG32'], paths['VG68']])
    for oil in ('VG32', 'VG68'):
        axis = cores[oil].table.viscosity_axis_m2_s * 1e6
        nu_of, _ = astm_d341(*(v * 1e6 for v in OILS[oil]))
        assert axis[0] == pytest.approx(nu_of(250.0), rel=1e-12)
        assert axis[-1] == pytest.approx(COLD_START_CST, rel=1e-12)
        assert cores[oil].table.metadata['spec']['viscosity_points'] == axis.size


@pytest.mark.parametrize('fixed_cst', [0.0, 0.5, 70.0, 2000.0])
def test_the_axis_contains_the_fixed_viscosity_parameter(paper_params, fixed_cst):
    for source in ('parameter', 'temperature'):
        config = EstimatorConfig(viscosity_source=source, oil_viscosity_m2_s=fixed_cst * 1e-6)
        axis = table_spec_for(config, paper_params.oil.viscosity_m2_s).axes(paper_params)[2]
        value = (fixed_cst or 70.0) * 1e-6  # 0: the pump file's, 70 cSt
        assert axis[0] <= value <= axis[-1]
        assert np.all(axis[1:] / axis[:-1] <= 10.0 ** (1.0 / 7.0) * (1.0 + 1e-12))


@pytest.mark.parametrize('low, high, nodes', [(10.0, 100.0, 8), (1.0, 1000.0, 22),
                                              (1.0864, 1000.0, 22), (5.0, 6.0, 2)])
def test_the_axis_has_eight_nodes_per_decade(low, high, nodes):
    spec = TableSpec().covering(low * 1e-6, high * 1e-6)
    assert spec.viscosity_points == nodes == max(2, math.ceil(7 * math.log10(high / low)) + 1)


def test_a_table_file_that_does_not_cover_the_oil_is_reported_in_one_line(
        tmp_path, monkeypatch, paper_params):
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path / 'cache'))
    path = build_table(paper_params).save(tmp_path / 'narrow.npz')  # 10-100 cSt
    core = estimator_from_config(oil_config('VG46', table_file=str(path)))
    warning = core.table_coverage
    assert warning and '\n' not in warning and str(path) in warning
    nu46, t46 = astm_d341(46.0, 6.8)
    assert 'viscosity axis, 10-100 cSt, does not cover the oil (1.086-1000 cSt' in warning
    # which temperatures it does hold: where VG 46 is 100 and 10 cSt
    held = re.search(r'only from ([-\d.]+) to ([-\d.]+) degC', warning)
    assert float(held[1]) == pytest.approx(t46(100.0), abs=0.05)  # 24.9 degC
    assert float(held[2]) == pytest.approx(t46(10.0), abs=0.05)  # 83.9 degC
    low, high = (float(x) for x in re.search(r'--viscosity-cst ([\d.]+) ([\d.]+)', warning)
                 .groups())
    assert low <= nu46(250.0) and high >= COLD_START_CST  # the command it gives covers it
    est = run_at(core, 0.0)  # 577 cSt: taken at 100 cSt, counted
    assert est.table_flags == VISCOSITY_CLAMPED and core.counts['clamped_to_table'] == 5


@pytest.fixture(scope='module')
def wide_table(paper_params):
    """Return the paper pump's table for the default parameters with VG 46: 1.09-1000 cSt."""
    config = oil_config('VG46')
    return build_table(paper_params, table_spec_for(config, paper_params.oil.viscosity_m2_s))


def test_interpolation_over_the_whole_oil_range_is_within_half_a_percent_of_the_model(
        wide_table, paper_params):
    axis = wide_table.viscosity_axis_m2_s
    assert axis.size == 22
    rng = np.random.default_rng(17)
    n = 2000
    speed = rng.uniform(0.0, 12000.0 * math.pi / 30.0, n)
    speed[: n // 3] = rng.uniform(0.0, 60.0, n // 3)  # breakaway and Palmgren threshold
    pressure = rng.uniform(0.0, 350e5, n)
    pressure[n // 3: n // 2] = rng.uniform(0.0, 30e5, n // 2 - n // 3)
    viscosity = np.exp(rng.uniform(math.log(axis[0]), math.log(axis[-1]), n))
    viscosity[n // 2:] = np.sqrt(axis[1:] * axis[:-1])[rng.integers(0, axis.size - 1,
                                                                    n - n // 2)]  # mid-cells
    speed *= np.where(rng.random(n) < 0.5, 1.0, -1.0)
    pressure *= np.where(rng.random(n) < 0.5, 1.0, -1.0)
    ref = PumpModel(paper_params, n_angles=360).evaluate(speed, pressure, viscosity)
    got = wide_table.lookup_array(speed, pressure, viscosity)
    tolerance = np.maximum(0.005 * ref.friction_magnitude_nm, 1e-3)
    assert np.all(got['flags'] == 0)
    assert np.all(np.abs(got['friction_nm'] - ref.friction_nm) <= tolerance)
    for c in COMPONENTS:
        assert np.all(np.abs(got[f'{c}_nm'] - ref.component_nm(c)) <= tolerance), c
