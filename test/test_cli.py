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

"""The pump_friction command line: exact JSON keys, unit conversion at the edge, bad input."""

import importlib.metadata
import json
import math
from pathlib import Path
import re
import struct

from pump_friction_ros.app.cli import main
import pytest

TORQUE_KEYS = ['theoretical_nm', 'valve_plate_nm', 'bearing_nm', 'spherical_joints_nm',
               'piston_heads_nm', 'friction_nm', 'input_nm', 'efficiency']
KINEMATICS_KEYS = ['stroke_mm', 'displacement_cc', 'head_speed_max_m_s',
                   'piston_omega_max_rad_s', 'joint_force_max_n', 'head_force_max_n']


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_version_is_the_one_of_the_distribution_and_of_package_xml(capsys):
    with pytest.raises(SystemExit) as stop:
        main(['--version'])
    assert stop.value.code == 0
    printed = capsys.readouterr().out.split()
    package_xml = (Path(__file__).parents[1] / 'package.xml').read_text(encoding='utf-8')
    in_xml = re.search(r'<version>([^<]+)</version>', package_xml).group(1)
    assert printed[:2] == ['pump_friction', importlib.metadata.version('pump_friction_ros')]
    assert printed[1] == in_xml


def test_torque_json_has_exactly_the_documented_keys_and_adds_up(capsys):
    code, out, _ = run(capsys, 'torque', '--speed-rpm', '4000', '--pressure-bar', '136', '--json')
    assert code == 0
    data = json.loads(out)
    assert list(data) == TORQUE_KEYS
    v_g = 5 * math.pi / 4 * 9.5e-3**2 * 2 * 10.75e-3 * math.sin(math.radians(40))
    assert data['theoretical_nm'] == pytest.approx(v_g * 136e5 / (2 * math.pi))
    parts = sum(data[k] for k in TORQUE_KEYS[1:5])
    assert data['friction_nm'] == pytest.approx(parts)
    assert data['input_nm'] == pytest.approx(data['theoretical_nm'] + data['friction_nm'])
    assert data['efficiency'] == pytest.approx(data['theoretical_nm'] / data['input_nm'])


def test_torque_reverse_rotation_has_friction_opposing_speed(capsys):
    _, out, _ = run(capsys, 'torque', '--speed-rpm', '-3000', '--pressure-bar', '100', '--json')
    data = json.loads(out)
    assert data['theoretical_nm'] > 0
    assert all(data[k] < 0 for k in TORQUE_KEYS[1:6])


def test_undefined_efficiency_is_json_null(capsys):
    _, out, _ = run(capsys, 'torque', '--speed-rpm', '0', '--pressure-bar', '100', '--json')
    assert json.loads(out)['efficiency'] is None
    assert 'null' in out


def test_kinematics_json_keys_and_closed_form_stroke(capsys):
    code, out, _ = run(capsys, 'kinematics', '--speed-rpm', '10000', '--pressure-bar', '300',
                       '--json')
    assert code == 0
    data = json.loads(out)
    assert list(data) == KINEMATICS_KEYS
    assert data['stroke_mm'] == pytest.approx(2 * 10.75 * math.sin(math.radians(40)))
    assert data['displacement_cc'] == pytest.approx(
        5 * math.pi / 4 * 0.95**2 * data['stroke_mm'] / 10)
    assert data['head_speed_max_m_s'] == pytest.approx(7.0, rel=0.05)
    assert data['piston_omega_max_rad_s'] == pytest.approx(50.0, rel=0.05)
    assert data['joint_force_max_n'] == pytest.approx(2150, rel=0.03)
    assert data['head_force_max_n'] < 160


def test_viscosity_flag_is_converted_from_cst(capsys):
    _, lo, _ = run(capsys, 'torque', '--speed-rpm', '6000', '--pressure-bar', '0', '--json',
                   '--viscosity-cst', '35')
    _, hi, _ = run(capsys, 'torque', '--speed-rpm', '6000', '--pressure-bar', '0', '--json',
                   '--viscosity-cst', '70')
    lo, hi = json.loads(lo), json.loads(hi)
    assert hi['valve_plate_nm'] == pytest.approx(2 * lo['valve_plate_nm'])


def test_paper_check_prints_the_table_and_exits_zero(capsys):
    code, out, _ = run(capsys, 'paper-check')
    assert code == 0
    assert 'valve plate, 300 bar, 10,000 rpm' in out
    assert 'statements hold' in out
    code, out, _ = run(capsys, 'paper-check', '--json')
    assert code == 0
    assert len(json.loads(out)) > 20


@pytest.mark.parametrize('argv', [
    ['torque', '--speed-rpm', 'nan', '--pressure-bar', '100'],
    ['torque', '--speed-rpm', 'inf', '--pressure-bar', '100'],
    ['torque', '--speed-rpm', 'fast', '--pressure-bar', '100'],
    ['torque', '--pressure-bar', '100'],
    ['torque', '--speed-rpm', '1e9', '--pressure-bar', '100'],
    ['torque', '--speed-rpm', '100', '--pressure-bar', '100', '--viscosity-cst', '-3'],
    ['kinematics', '--speed-rpm', '100', '--pump', '/no/such/pump.yaml'],
    ['frobnicate'],
    [],
    ['torque', '--speed', '100', '--pressure-bar', '100'],  # abbreviations are typos
    ['replay', 'bags/eha_nominal', '--plot', 'figs'],
    ['build-table', '--max-speed', '3000'],
])
def test_bad_arguments_exit_2_with_one_line_and_no_traceback(capsys, argv):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert out == ''
    assert len(err.strip().splitlines()) == 1
    assert err.startswith('pump_friction: error: ')
    assert 'Traceback' not in err


@pytest.mark.parametrize('argv, named', [
    (['replay', 'bags/eha_valve_plate_wear', '--baseline', ''], '--baseline'),  # not "none"
    (['replay', ''], 'BAG'),  # not "every bag under here"
    (['learn-baseline', 'bags/eha_nominal', '--baseline', '', '--out', 'x.yaml'], '--baseline'),
    (['torque', '--speed-rpm', '1000', '--pressure-bar', '100', '--table', ''], '--table'),
    (['make-sample-bags', '--out', ''], '--out'),  # not "here"
    (['replay', 'bags/eha_nominal', '--dask', ''], '--dask'),  # not "locally"
])
def test_an_empty_path_or_address_is_refused_not_taken_as_none_or_here(capsys, tmp_path,
                                                                       monkeypatch, argv,
                                                                       named):
    monkeypatch.chdir(tmp_path)  # nothing may be written here
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ''
    assert err.strip() == (f'pump_friction: error: argument {named}: expected a value, got an '
                           f'empty string (see pump_friction {argv[0]} --help)')
    assert not any(tmp_path.iterdir())


def test_every_parser_refuses_abbreviations():
    from pump_friction_ros.app.cli import build_parser
    parser = build_parser()
    subs = next(a for a in parser._actions if a.dest == 'command').choices
    assert parser.allow_abbrev is False
    assert subs and all(p.allow_abbrev is False for p in subs.values())


def test_invalid_pump_yaml_exits_2(capsys, tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('name: [unterminated\n')
    code, _, err = run(capsys, 'torque', '--speed-rpm', '1', '--pressure-bar', '1',
                       '--pump', str(bad))
    assert code == 2
    assert 'invalid YAML' in err


def test_plot_writes_labelled_png_figures(capsys, tmp_path):
    code, _, _ = run(capsys, 'plot', '--out', str(tmp_path / 'figs'))
    assert code == 0
    files = sorted((tmp_path / 'figs').glob('*.png'))
    assert [f.name[:5] for f in files] == ['fig03', 'fig10', 'fig11', 'fig12', 'fig13',
                                           'fig14', 'fig15', 'fig16', 'fig17', 'fig19']
    for f in files:
        head = f.read_bytes()[:24]
        assert head[:8] == b'\x89PNG\r\n\x1a\n'
        width, height = struct.unpack('>II', head[16:24])
        assert width > 400 and height > 300


@pytest.mark.parametrize('out', ['.', '..', '/'])
def test_an_output_named_by_the_current_folder_or_one_above_is_refused_and_leaves_nothing(
        capsys, tmp_path, monkeypatch, out):
    # '.' has no name: the staging folder was the output itself, left behind and named
    here = tmp_path / 'here'
    here.mkdir()
    (here / 'fig03_mine.png').write_bytes(b'mine')
    monkeypatch.chdir(here)
    code, _, err = run(capsys, 'plot', '--out', out, '--force')
    assert code == 2 and err.count('\n') == 1 and 'the current folder or one above' in err
    assert sorted(p.name for p in here.iterdir()) == ['fig03_mine.png']
    assert sorted(p.name for p in tmp_path.iterdir()) == ['here']


def test_a_dangling_link_at_the_output_is_an_output_that_exists(capsys, tmp_path):
    link = tmp_path / 'figs'
    link.symlink_to(tmp_path / 'nowhere')
    code, _, err = run(capsys, 'plot', '--out', str(link))
    assert code == 2 and 'output exists' in err and link.is_symlink()


def test_plot_replaces_an_earlier_folder_only_with_force_and_refuses_a_file(capsys, tmp_path):
    figs = tmp_path / 'figs'
    figs.mkdir()
    (figs / 'fig03_old.png').write_bytes(b'old')
    code, _, err = run(capsys, 'plot', '--out', str(figs))
    assert code == 2 and 'output exists' in err and (figs / 'fig03_old.png').exists()
    assert run(capsys, 'plot', '--out', str(figs), '--force')[0] == 0
    assert not (figs / 'fig03_old.png').exists() and len(list(figs.glob('*.png'))) == 10
    a_file = tmp_path / 'a_file'
    a_file.write_text('mine\n')
    for args in (['--out', str(a_file), '--force'], ['--out', str(a_file / 'figs')]):
        code, out, err = run(capsys, 'plot', *args)
        assert code == 2 and out == '' and err.count('\n') == 1 and str(a_file) in err
    assert a_file.read_text() == 'mine\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['a_file', 'figs']  # no staging


def test_build_table_then_torque_from_table_matches_the_model(capsys, tmp_path):
    out = tmp_path / 'tab.npz'
    code, text, _ = run(capsys, 'build-table', '--out', str(out), '--quiet')
    assert code == 0 and out.exists() and str(out) in text
    _, model_json, _ = run(capsys, 'torque', '--speed-rpm', '-7000', '--pressure-bar', '-210',
                           '--json')
    code, table_json, err = run(capsys, 'torque', '--speed-rpm', '-7000', '--pressure-bar',
                                '-210', '--json', '--table', str(out))
    assert code == 0 and err == ''
    model, table = json.loads(model_json), json.loads(table_json)
    assert list(table) == TORQUE_KEYS
    assert table['theoretical_nm'] == model['theoretical_nm']
    tolerance = max(0.005 * abs(model['friction_nm']), 1e-3)
    for key in TORQUE_KEYS[1:7]:
        assert table[key] == pytest.approx(model[key], abs=tolerance)


def test_torque_from_table_outside_its_envelope_warns_on_stderr(capsys, tmp_path):
    out = tmp_path / 'tab.npz'
    run(capsys, 'build-table', '--out', str(out), '--quiet', '--max-speed-rpm', '3000',
        '--max-pressure-bar', '100')
    code, _, err = run(capsys, 'torque', '--speed-rpm', '5000', '--pressure-bar', '50',
                       '--table', str(out))
    assert code == 0
    assert 'warning: speed above the table' in err


def test_a_reversed_viscosity_range_is_said_in_the_cst_given(capsys, tmp_path):
    code, _, err = run(capsys, 'build-table', '--viscosity-cst', '80', '20',
                       '--out', str(tmp_path / 't.npz'))
    assert code == 2 and 'LOW must be below HIGH, got 80 20' in err and 'm^2/s' not in err
    assert not (tmp_path / 't.npz').exists()


def test_table_for_another_pump_exits_2_saying_how_to_rebuild(capsys, tmp_path):
    out = tmp_path / 'tab.npz'
    run(capsys, 'build-table', '--out', str(out), '--quiet', '--max-speed-rpm', '2000')
    consistent = str(Path(__file__).parents[1] / 'config/pumps/hong_doh_2004_consistent.yaml')
    code, _, err = run(capsys, 'torque', '--speed-rpm', '1000', '--pressure-bar', '50',
                       '--table', str(out), '--pump', consistent)
    assert code == 2
    assert 'build-table --pump' in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize('argv', [
    ['build-table', '--max-speed-rpm', '-5'],
    ['build-table', '--viscosity-cst', '50'],
    ['build-table', '--viscosity-cst', '80', '20'],
    ['torque', '--speed-rpm', '1', '--pressure-bar', '1', '--table', '/no/such/table.npz'],
])
def test_bad_table_arguments_exit_2(capsys, argv):
    code, _, err = run(capsys, *argv)
    assert code == 2
    assert err.startswith('pump_friction: error: ') and len(err.strip().splitlines()) == 1
