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

"""Calibration: synthetic data with known parameters, the nominal sample bag, bad input."""

import csv
import math
from pathlib import Path

import numpy as np
from pump_friction_ros.app.cli import main
from pump_friction_ros.calibration import (
    calibrate,
    CalibrationError,
    correlation_time,
    fitted_pump,
)
from pump_friction_ros.core.node_parameters import load_estimator_config
from pump_friction_ros.physics.model import PumpModel
from pump_friction_ros.physics.pump_parameters import load_pump
from pump_friction_ros.table.table_files import cached_table
import pytest

REPO = Path(__file__).resolve().parents[1]
BASE = REPO / 'config' / 'pumps' / 'hong_doh_2004.yaml'
# the shipped defaults, then what the sample bags' simulated pump brings with them
SAMPLE_PARAMS = REPO / 'bags' / 'eha_params.yaml'
CONFIG = load_estimator_config([REPO / 'config' / 'torque_estimator.yaml', SAMPLE_PARAMS])
NOISE_NM = 0.02


def write_bench(path, pump, rpms, bars, seed=0, noise=NOISE_NM):
    r, b = np.meshgrid(np.asarray(rpms, float), np.asarray(bars, float))
    cst = np.where(np.arange(r.size) % 2 == 0, 46.0, 32.0)
    res = PumpModel(pump).evaluate(r.ravel() * math.pi / 30, b.ravel() * 1e5, cst / 1e6)
    torque = res.input_nm + np.random.default_rng(seed).normal(0.0, noise, r.size)
    with open(path, 'w', newline='') as handle:
        out = csv.writer(handle)
        out.writerow(['speed_rpm', 'pressure_bar', 'torque_nm', 'viscosity_cst'])
        out.writerows(zip(r.ravel(), b.ravel(), torque, cst, strict=True))
    return path


TRUTH = np.array([1.3, 1.25, 1.5, 0.7, 1.0, 1.0, 0.0, 0.0])  # coulomb, viscous, f1, f0, ...


def test_fit_recovers_known_parameters_within_their_intervals(tmp_path):
    base = load_pump(BASE)
    truth = fitted_pump(base, TRUTH, 'truth')
    data = write_bench(tmp_path / 'bench.csv', truth,
                       [100, 130, 160, 200, 300, 500, 1000, 2000, 3500, 5000, 7000, 9000],
                       np.linspace(20, 300, 8))
    result = calibrate([data], BASE, tmp_path / 'mine.yaml',
                       fix=['piston_friction.joint', 'piston_friction.head'])
    by_name = {p.name: p for p in result.parameters}
    for k, name in enumerate(('valve_plate.coulomb', 'valve_plate.viscous', 'bearing.f1',
                              'bearing.f0')):
        p = by_name[name]
        assert p.status == 'fitted'
        assert abs(p.fitted - TRUTH[k]) <= p.ci95, (name, p.fitted, p.ci95)
    assert by_name['piston_friction.joint'].status == 'fixed'
    assert result.cv_rmse_nm == pytest.approx(NOISE_NM, rel=0.3)  # held-out ~ noise
    assert result.rmse_after_nm < 0.25 * result.rmse_before_nm


def test_fit_survives_a_solver_that_writes_into_its_jacobian(tmp_path, monkeypatch):
    # SciPy < 1.16 (Jazzy: 1.11) scales the array a `jac` callable returns in place when the
    # loss is robust; simulate that on any SciPy: the fit must not depend on it
    import scipy.optimize
    real = scipy.optimize.least_squares

    def least_squares_before_1_16(fun, x0, jac='2-point', **kwargs):
        if callable(jac):
            user_jac = jac

            def jac(theta):
                returned = user_jac(theta)
                solver_copy = np.array(returned, dtype=float)
                returned *= 0.5  # what the old solver did to the caller's array
                return solver_copy
        return real(fun, x0, jac=jac, **kwargs)

    monkeypatch.setattr(scipy.optimize, 'least_squares', least_squares_before_1_16)
    truth = fitted_pump(load_pump(BASE), TRUTH, 'truth')
    data = write_bench(tmp_path / 'bench.csv', truth, [100, 130, 160, 200, 500, 2000, 9000],
                       np.linspace(20, 300, 6))
    result = calibrate([data], BASE, None, fix=['piston_friction.joint', 'piston_friction.head'])
    for k, p in enumerate(result.parameters[:4]):
        assert p.status == 'fitted' and abs(p.fitted - TRUTH[k]) <= p.ci95, p


def test_one_speed_cannot_separate_coulomb_from_viscous_and_says_so(tmp_path):
    base = load_pump(BASE)
    truth = fitted_pump(base, TRUTH, 'truth')
    data = write_bench(tmp_path / 'one_speed.csv', truth, [3000], np.linspace(20, 300, 16))
    out = tmp_path / 'mine.yaml'
    result = calibrate([data], BASE, out)
    flagged = {p.name for p in result.parameters if p.status == 'unidentifiable'}
    assert {'valve_plate.viscous', 'bearing.f0'} & flagged  # both constant at one speed
    assert any('cannot be identified' in w for w in result.warnings)
    written = load_pump(out)
    if 'valve_plate.viscous' in flagged:  # left at the base value in the file
        assert written.valve_plate.film_clearance_m == base.valve_plate.film_clearance_m
    if 'bearing.f0' in flagged:
        assert written.bearing.f0 == base.bearing.f0


def test_nominal_sample_bag_is_consistent_with_the_papers_pump(tmp_path, monkeypatch):
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path / 'cache'))
    result = calibrate([REPO / 'bags' / 'eha_nominal'], BASE, tmp_path / 'fit.yaml',
                       config=CONFIG)
    assert 'near-steady' in result.selection and 'whole record' in result.selection
    fitted = [p for p in result.parameters if p.status == 'fitted']
    assert len(fitted) >= 4
    truth = {'rotor_inertia_kg_m2': 2e-4, 'drive_loss_torque_nm': 0.05}  # the simulation's
    for p in fitted:
        expected = truth.get(p.name, 1.0)
        assert abs(p.fitted - expected) <= p.ci95, (p.name, p.fitted, p.ci95)


def test_written_pump_file_has_provenance_rebuilds_its_table_and_replays(tmp_path,
                                                                         monkeypatch):
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path / 'cache'))
    base = load_pump(BASE)
    data = write_bench(tmp_path / 'b.csv', fitted_pump(base, TRUTH, 't'),
                       [300, 1000, 3000, 6000, 9000], [50, 150, 250])
    out = tmp_path / 'my_pump.yaml'
    calibrate([data], BASE, out, report_dir=tmp_path / 'report')
    text = out.read_text()
    assert '# Table 1' in text  # the base file's comments are kept
    import yaml
    prov = yaml.safe_load(text)['provenance']
    assert prov['inputs'][0]['sha256'] and prov['base_pump']['sha256'] == base.sha256
    assert set(prov['fit']) >= {'rmse_before_nm', 'rmse_after_nm', 'cv_rmse_nm'}
    pump = load_pump(out)
    assert pump.name == 'my_pump' and pump.sha256 != base.sha256
    table = cached_table(pump)
    assert table.pump_sha256 == pump.sha256
    assert sorted(p.name for p in (tmp_path / 'report').glob('*.png')) == [
        'residual.png', 'torque_vs_pressure.png', 'torque_vs_speed.png']
    from pump_friction_ros.bags.replay import replay_bag
    from pump_friction_ros.core.node_parameters import EstimatorConfig
    summary = replay_bag(REPO / 'bags' / 'eha_nominal',
                         EstimatorConfig(pump_file=str(out), oil_viscosity_m2_s=46e-6))
    assert summary.estimates == 75000


@pytest.mark.parametrize(('content', 'message'), [
    ('speed_rpm,pressure_bar,torque_nm\n1000,100,nan\n', 'not finite'),
    ('speed_rpm,pressure_bar,torque_nm\n1000,fast,8\n', 'not a number'),
    ('speed_rpm,torque_nm\n1000,8\n', 'missing column'),
    ('speed_rpm,pressure_bar,torque_nm\n1000,1.0e7,8\n2000,2.0e7,16\n', 'looks like Pa'),
    ('speed_rpm,pressure_bar,torque_nm,viscosity_cst\n1000,100,8,4.6e-5\n', 'm\\^2/s'),
    ('speed_rpm,pressure_bar,torque_nm\n5,100,8\n6,150,12\n', 'no usable samples'),
    ('speed_rpm,pressure_bar,torque_nm\n1000,100,8\n2000,150,12\n', 'too few'),
    ('speed_rpm,pressure_bar,torque_nm\n', 'no data rows'),
    ('speed_rpm,pressure_bar,torque_nm,viscosity_cst\n1000,100,8,1e9\n',
     'viscosity_cst up to 1e\\+09: above 10000 cSt'),
    # ISO VG 46 (the node's default oil law) at -40 degC: ~1e5 cSt, beyond the node's range
    ('speed_rpm,pressure_bar,torque_nm,temperature_c\n1000,100,8,-40\n',
     'temperature_c down to -40 degC: the oil is [0-9]+ cSt there, above the 10000 cSt'),
    # a logger stuck on one reading: 50 samples, 1 point; it "fitted" every scale +-1e-16
    ('speed_rpm,pressure_bar,torque_nm\n' + '1000,100,8.5\n' * 50,
     '1 distinct usable samples \\(49 repeat others exactly\\) are too few'),
])
def test_bad_input_is_refused_and_writes_nothing(tmp_path, content, message):
    data = tmp_path / 'bad.csv'
    data.write_text(content)
    out = tmp_path / 'out.yaml'
    with pytest.raises(CalibrationError, match=message):
        calibrate([data], BASE, out)
    assert not out.exists() and not list(tmp_path.glob('out.yaml*'))


def test_cli_exits_2_with_one_line_on_bad_arguments(tmp_path, capsys):
    data = write_bench(tmp_path / 'b.csv', load_pump(BASE), [1000, 3000], [100, 200])
    for argv in (['calibrate', str(data), '--pump', str(BASE), '--out', str(tmp_path / 'o.yaml'),
                  '--fix', 'bearing.f9'],
                 ['calibrate', str(tmp_path / 'missing.csv'), '--pump', str(BASE), '--out',
                  str(tmp_path / 'o.yaml')]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith('pump_friction: error: ') and err.count('\n') == 1
    assert not (tmp_path / 'o.yaml').exists()


def test_cli_says_in_one_line_that_ruamel_yaml_is_needed(tmp_path, capsys, monkeypatch):
    import sys
    data = write_bench(tmp_path / 'b.csv', load_pump(BASE), [300, 1000, 3000, 9000], [50, 250])
    monkeypatch.setitem(sys.modules, 'ruamel', None)  # as if not installed
    monkeypatch.setitem(sys.modules, 'ruamel.yaml', None)
    out = tmp_path / 'o.yaml'
    assert main(['calibrate', str(data), '--pump', str(BASE), '--out', str(out)]) == 2
    assert capsys.readouterr().err == ('pump_friction: error: writing a calibrated pump file '
                                       'needs ruamel.yaml: pip install ruamel.yaml\n')
    assert not out.exists() and not list(tmp_path.glob('o.yaml*'))


def test_correlation_time_is_one_for_white_noise_and_grows_with_smoothing():
    rng = np.random.default_rng(0)
    white = rng.normal(size=20000)
    assert correlation_time(white) == pytest.approx(1.0, abs=0.1)
    smooth = np.convolve(white, np.ones(10) / 10, mode='same')  # 10-sample moving average
    assert correlation_time(smooth) == pytest.approx(10.0, rel=0.2)


def test_a_parameter_whose_column_the_others_make_is_unidentifiable_however_small_the_noise():
    """Two free parameters, one column twice the other: no data can split them."""
    from pump_friction_ros.calibration.fit import NAMES
    from pump_friction_ros.calibration.identifiability import fit_identifiable
    rng = np.random.default_rng(7)
    n, k = 40, len(NAMES)
    x = np.zeros((n, k))
    x[:, 0] = rng.uniform(0.5, 2.0, n)
    x[:, 1] = 2.0 * x[:, 0]  # collinear: any theta_0 + 2 theta_1 fits
    y = x[:, 0] * 1.3 + 1e-9 * rng.standard_normal(n)  # all but noise-free
    free = np.zeros(k, dtype=bool)
    free[:2] = True
    fit = fit_identifiable(x, y, np.ones(k), free, np.full(k, 10.0))
    assert list(fit.unidentifiable) in ([NAMES[0]], [NAMES[1]])
    assert 'combination of the others' in next(iter(fit.unidentifiable.values()))
    kept = 0 if NAMES[1] in fit.unidentifiable else 1  # the other, fitted given it
    assert fit.free.sum() == 1 and fit.free[kept]
    expected = 1.3 - 2.0 if kept == 0 else (1.3 - 1.0) / 2.0
    assert fit.theta[kept] == pytest.approx(max(expected, 0.0), abs=1e-6)


def test_a_fit_beyond_a_pump_files_range_names_the_fitted_pump_not_a_staging_path(
        tmp_path, monkeypatch):
    from pump_friction_ros.calibration import report
    from pump_friction_ros.errors import ConfigError

    def beyond(path):  # the written file only: the base pump loads as it is
        if Path(path) == Path(BASE):
            return load_pump(path)
        raise ConfigError(f'{path}: valve_plate.film_clearance_m: must be <= 0.001, got 1072.7')

    data = write_bench(tmp_path / 'b.csv', load_pump(BASE), [1000, 2000, 3000, 4000],
                       [50, 100, 150, 200, 250])
    monkeypatch.setattr(report, 'load_pump', beyond)
    out = tmp_path / 'out.yaml'
    with pytest.raises(CalibrationError) as info:
        calibrate([data], BASE, out)
    assert str(info.value).startswith('the fitted pump: valve_plate.film_clearance_m')
    assert 'partial' not in str(info.value) and not list(tmp_path.glob('*out.yaml*'))
