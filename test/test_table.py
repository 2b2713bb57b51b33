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

"""Friction table: accuracy against the full model, both lookup paths, provenance, bad input."""

import json
import math
import os

import numpy as np
from pump_friction_ros.errors import TableError
from pump_friction_ros.physics.model import COMPONENTS, PumpModel
from pump_friction_ros.table import friction_table as tb
from pump_friction_ros.table.friction_table import (
    build_table,
    NOT_FINITE,
    PRESSURE_CLAMPED,
    SPEED_CLAMPED,
    TableSpec,
    VISCOSITY_CLAMPED,
)
from pump_friction_ros.table.table_files import cached_table, cached_table_path, load_table
import pytest
from scipy.interpolate import RegularGridInterpolator


@pytest.fixture(scope='module')
def paper_table(paper_params):
    return build_table(paper_params)


@pytest.fixture(scope='module')
def consistent_table(consistent_params):
    return build_table(consistent_params)


def _random_points(spec, n, seed):
    rng = np.random.default_rng(seed)
    speed = rng.uniform(0.0, spec.max_speed_rad_s, n)
    speed[: n // 3] = rng.uniform(0.0, 60.0, n // 3)  # breakaway and Palmgren threshold
    pressure = rng.uniform(0.0, spec.max_pressure_pa, n)
    pressure[n // 3: n // 2] = rng.uniform(0.0, 30e5, n // 2 - n // 3)
    viscosity = np.exp(rng.uniform(math.log(spec.min_viscosity_m2_s),
                                   math.log(spec.max_viscosity_m2_s), n))
    sign = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    return speed * sign, pressure * np.where(rng.random(n) < 0.5, 1.0, -1.0), viscosity


@pytest.mark.parametrize('which', ['paper', 'consistent'])
def test_table_matches_full_model_within_half_a_percent_at_random_points(
        which, paper_table, consistent_table, paper_params, consistent_params):
    table, params = {'paper': (paper_table, paper_params),
                     'consistent': (consistent_table, consistent_params)}[which]
    speed, dp, visc = _random_points(TableSpec(), 1500, seed=11)
    ref = PumpModel(params, n_angles=360).evaluate(speed, dp, visc)
    got = table.lookup_array(speed, dp, visc)
    friction = ref.friction_magnitude_nm
    tolerance = np.maximum(0.005 * friction, 1e-3)
    assert np.all(np.abs(got['friction_nm'] - ref.friction_nm) <= tolerance)
    for c in COMPONENTS:
        assert np.all(np.abs(got[f'{c}_nm'] - ref.component_nm(c)) <= tolerance), c
    assert np.all(got['flags'] == 0)


def test_table_equals_model_on_its_own_nodes(paper_table, paper_params):
    s = paper_table.speed_axis_rad_s[[0, 5, 40, -1]]
    p = paper_table.pressure_axis_pa[[0, 3, -1]]
    v = paper_table.viscosity_axis_m2_s[[0, -1]]
    grid = np.stack(np.meshgrid(s, p, v, indexing='ij'), -1).reshape(-1, 3)
    model = PumpModel(paper_params, n_angles=TableSpec().n_angles)
    ref = model.evaluate(-grid[:, 0], grid[:, 1], grid[:, 2])  # motoring
    mags, flags = paper_table.magnitudes_array(grid[:, 0], grid[:, 1], grid[:, 2], True)
    for c, name in enumerate(COMPONENTS):
        np.testing.assert_allclose(mags[:, c], ref.magnitudes_nm[name], rtol=1e-12, atol=1e-15)
    assert not flags.any()


def test_scalar_and_vector_paths_give_the_same_numbers(paper_table):
    speed, dp, visc = _random_points(TableSpec(), 400, seed=3)
    vec = paper_table.lookup_array(speed, dp, visc)
    for i in range(speed.size):
        one = paper_table.lookup(float(speed[i]), float(dp[i]), float(visc[i]))
        for c, name in enumerate(COMPONENTS):
            assert one.components_nm[c] == pytest.approx(vec[f'{name}_nm'][i], rel=1e-13,
                                                         abs=1e-15)
        assert one.input_nm == pytest.approx(vec['input_nm'][i], rel=1e-13)
        assert (math.isnan(one.efficiency) and math.isnan(vec['efficiency'][i])) or \
            one.efficiency == pytest.approx(vec['efficiency'][i], rel=1e-13)


def test_lookup_agrees_with_scipy_regular_grid_interpolator(paper_table):
    """Trilinear interpolation on the same grid, computed by an independent implementation."""
    rgi = RegularGridInterpolator((paper_table.speed_axis_rad_s, paper_table.pressure_axis_pa,
                                   paper_table.viscosity_axis_m2_s), paper_table.torque_nm[1])
    rng = np.random.default_rng(5)
    pts = np.column_stack([rng.uniform(0, paper_table.speed_axis_rad_s[-1], 2000),
                           rng.uniform(0, paper_table.pressure_axis_pa[-1], 2000),
                           rng.uniform(*paper_table.viscosity_axis_m2_s[[0, -1]], 2000)])
    mags, _ = paper_table.magnitudes_array(pts[:, 0], pts[:, 1], pts[:, 2], True)
    np.testing.assert_allclose(mags, rgi(pts), rtol=1e-12, atol=1e-15)


def test_friction_opposes_speed_smoothly_through_zero_like_the_model(paper_table, paper_model):
    speeds = np.linspace(-10.0, 10.0, 81)
    got = paper_table.lookup_array(speeds, 100e5)
    ref = paper_model.evaluate(speeds, 100e5)
    np.testing.assert_allclose(got['friction_nm'], ref.friction_nm, atol=1e-3)
    assert got['friction_nm'][40] == 0.0
    np.testing.assert_array_equal(np.sign(got['friction_nm']), np.sign(speeds))
    assert np.abs(np.diff(got['input_nm'])).max() < 0.05


def test_out_of_envelope_is_clamped_and_flagged(paper_table):
    assert paper_table.viscosity_axis_m2_s[-1] == 100e-6  # 100 cSt exactly, no round-off
    edge = paper_table.lookup(paper_table.speed_axis_rad_s[-1], 350e5, 100e-6)
    beyond = paper_table.lookup(2 * paper_table.speed_axis_rad_s[-1], 350e5, 100e-6)
    assert beyond.flags == SPEED_CLAMPED
    assert beyond.components_nm == pytest.approx(edge.components_nm)
    assert paper_table.lookup(100.0, 500e5, 50e-6).flags == PRESSURE_CLAMPED
    assert paper_table.lookup(100.0, -500e5, 50e-6).flags == PRESSURE_CLAMPED
    assert paper_table.lookup(100.0, 1e5, 1e-6).flags == VISCOSITY_CLAMPED
    assert paper_table.lookup(-1e4, 1e5, 1e-3).flags == SPEED_CLAMPED | VISCOSITY_CLAMPED
    vec = paper_table.lookup_array([2e4, 100.0, 100.0], [1e5, 9e7, 1e5], [5e-5, 5e-5, 1e-6])
    np.testing.assert_array_equal(vec['flags'], [SPEED_CLAMPED, PRESSURE_CLAMPED,
                                                 VISCOSITY_CLAMPED])


@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_non_finite_input_gives_nan_and_a_flag(paper_table, bad):
    for args in ((bad, 1e5, 5e-5), (100.0, bad, 5e-5), (100.0, 1e5, bad)):
        res = paper_table.lookup(*args)
        assert res.flags & NOT_FINITE
        assert math.isnan(res.input_nm) and math.isnan(res.friction_nm)
    vec = paper_table.lookup_array([bad, 100.0], [1e5, 1e5], [5e-5, 5e-5])
    assert vec['flags'][0] & NOT_FINITE and not vec['flags'][1]
    assert np.isnan(vec['input_nm'][0]) and np.isfinite(vec['input_nm'][1])


def test_saved_table_round_trips_with_provenance(tmp_path, paper_table, paper_params):
    path = paper_table.save(tmp_path / 'table.npz')
    loaded = load_table(path, paper_params)
    np.testing.assert_array_equal(loaded.torque_nm, paper_table.torque_nm)
    meta = loaded.metadata
    assert meta['pump_sha256'] == paper_params.sha256
    assert meta['pump_name'] == 'hong_doh_2004'
    assert meta['components'] == list(COMPONENTS)
    assert meta['units']['torque_nm'] == 'N*m'
    assert meta['model_version'] and meta['created_utc'].endswith('Z')
    assert not list(tmp_path.glob('*.tmp'))


def test_table_for_another_pump_is_refused_with_how_to_rebuild(tmp_path, paper_table,
                                                               consistent_params):
    path = paper_table.save(tmp_path / 'table.npz')
    with pytest.raises(TableError, match='pump_friction build-table --pump'):
        load_table(path, consistent_params)


def test_table_from_another_model_version_is_refused(tmp_path, paper_table, paper_params,
                                                     monkeypatch):
    path = paper_table.save(tmp_path / 'table.npz')
    monkeypatch.setattr(tb, 'MODEL_VERSION', 'future')
    with pytest.raises(TableError, match='model version'):
        load_table(path, paper_params)


def _rewrite(path, **changes):
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    arrays.update(changes)
    arrays = {k: v for k, v in arrays.items() if v is not None}
    np.savez(path, **arrays)


@pytest.mark.parametrize(('change', 'message'), [
    ({'torque_nm': None}, 'missing torque_nm'),
    ({'torque_nm': np.zeros((2, 3, 4, 5, 4))}, 'shape'),
    ({'torque_nm': 'text'}, 'dtype'),
    ({'speed_axis_rad_s': np.array([0.0, 2.0, 1.0])}, 'strictly increasing'),
    ({'metadata': np.array('{not json')}, 'not valid JSON'),
    ({'metadata': np.array(json.dumps({'format': 99}))}, 'unsupported'),
    ({'metadata': np.array([1.0, 2.0])}, 'JSON string'),
])
def test_malformed_table_files_are_refused(tmp_path, paper_table, change, message):
    path = paper_table.save(tmp_path / 'table.npz')
    _rewrite(path, **change)
    with pytest.raises(TableError, match=message):
        load_table(path)


@pytest.mark.parametrize(('key', 'value'), [
    ('zero_speed_threshold_rad_s', math.nan),  # the replay published NaN torques on it
    ('displacement_m3', -1.0),  # and -1.9e6 N m on this
    ('displacement_m3', 0.0),
    ('displacement_m3', 'abc'),
    ('default_viscosity_m2_s', None),
    ('efficiency_min_pressure_pa', [1.0]),
    ('efficiency_min_speed_rad_s', True),
    ('efficiency_min_speed_rad_s', -0.5),
])
def test_table_metadata_numbers_out_of_their_range_are_refused_naming_them(
        tmp_path, paper_table, key, value):
    path = paper_table.save(tmp_path / 'table.npz')
    metadata = {k: v for k, v in paper_table.metadata.items() if k != 'source'}
    _rewrite(path, metadata=np.array(json.dumps({**metadata, key: value})))
    with pytest.raises(TableError, match=f'metadata {key}: expected a finite number'):
        load_table(path)


def test_object_arrays_are_never_unpickled(tmp_path, paper_table):
    path = paper_table.save(tmp_path / 'table.npz')
    _rewrite(path, metadata=np.array([{'evil': 1}], dtype=object))
    with pytest.raises(TableError, match='cannot read'):
        load_table(path)


def test_garbage_and_missing_files_are_refused(tmp_path):
    junk = tmp_path / 'junk.npz'
    junk.write_bytes(b'not a zip file at all')
    with pytest.raises(TableError, match='cannot read'):
        load_table(junk)
    with pytest.raises(TableError, match='not found'):
        load_table(tmp_path / 'nothing.npz')


def test_default_table_is_built_once_then_cached_under_its_hash(tmp_path, monkeypatch,
                                                                paper_params):
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path))
    calls = []
    first = cached_table(paper_params, progress=calls.append)
    files = list((tmp_path / 'pump_friction_ros').glob('*.npz'))
    assert len(files) == 1 and paper_params.sha256[:16] in files[0].name
    assert calls and calls[-1] == pytest.approx(1.0)
    calls.clear()
    second = cached_table(paper_params, progress=calls.append)
    assert not calls  # loaded, not rebuilt
    np.testing.assert_array_equal(first.torque_nm, second.torque_nm)
    files[0].write_bytes(b'corrupt')  # a damaged cache entry is rebuilt, not trusted
    third = cached_table(paper_params)
    np.testing.assert_array_equal(third.torque_nm, first.torque_nm)


@pytest.mark.parametrize('name', ['/abs/x', '../..', 'a/b', 'x' * 300, '..', 'p\udcff e'])
def test_a_pump_name_never_leads_the_cached_table_out_of_the_cache_folder(
        tmp_path, monkeypatch, paper_params, name):
    from dataclasses import replace
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path))
    path = cached_table_path(replace(paper_params, name=name))
    assert path.parent == tmp_path / 'pump_friction_ros'
    assert not path.name.startswith('.') and len(path.name) < 200
    path.name.encode('ascii')  # a plain name on every file system
    assert path != cached_table_path(replace(paper_params, name='other'))


def test_a_saved_table_gets_the_permissions_open_would_give_a_new_file(
        tmp_path, paper_table):
    old = os.umask(0o027)
    try:
        path = paper_table.save(tmp_path / 't.npz')
    finally:
        os.umask(old)
    assert path.stat().st_mode & 0o777 == 0o640  # not mkstemp's 0o600


def test_bad_table_spec_is_refused():
    with pytest.raises(TableError, match='max_pressure_pa'):
        TableSpec(max_pressure_pa=-1.0)
    with pytest.raises(TableError, match='min_viscosity'):
        TableSpec(min_viscosity_m2_s=2e-4, max_viscosity_m2_s=1e-4)
