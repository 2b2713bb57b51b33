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
The README's and docs pages' numbers and tables, checked against what the code prints.

Each check parses the page that shows the figure (issue 11; the README was split into
``docs/*.md`` in issue 16), so a figure that drifts from the code fails here instead of
misleading a reader: the parameters table in README.md (made from `config.PARAMETERS`),
the ``pump_friction torque`` example in any page, and the calibration worked example in
docs/calibration.md. Every relative link and image of the pages must resolve.
"""

from pathlib import Path
import re
import shlex

from pump_friction_ros.app.cli import main
from pump_friction_ros.core.node_parameters import PARAMETERS
import pytest

REPO = Path(__file__).resolve().parents[1]
README = (REPO / 'README.md').read_text()
PAGES = {path: path.read_text() for path in [REPO / 'README.md',
                                             *sorted((REPO / 'docs').glob('*.md'))]}
CALIBRATION = (REPO / 'docs' / 'calibration.md').read_text()


def _text(value):
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, str):
        return repr(value)
    text = f'{value:g}'
    if isinstance(value, float) and text.lstrip('-').isdigit():
        return f'{text}.0'  # a double as a params file or -p must give it: 1.0, not 1
    return text


def parameter_rows():
    """Return the README's parameters table rows, made from the declaration in config.py."""
    rows = []
    for p in PARAMETERS:
        if p.choices:
            span = ' / '.join(p.choices)
        elif p.low is None:
            span = ''
        else:
            span = f'[{_text(p.low)}, {_text(p.high)}]'
        description = p.description.replace('|', '\\|')
        rows.append(f'| `{p.name}` | {_text(p.default)} | {span} | {description} |')
    return rows


def test_parameters_table_is_the_declared_spec():
    table = [line for line in README.splitlines() if re.match(r'\| `[a-z0-9_]+` \|', line)
             and any(line.startswith(f'| `{p.name}` |') for p in PARAMETERS)]
    assert table == parameter_rows()


def console_blocks():
    """(command, printed lines) of each ``$ pump_friction ...`` in a console block of any page."""
    blocks = [block for text in PAGES.values()
              for block in re.findall(r'```console\n(.*?)```', text, flags=re.S)]
    for block in blocks:
        lines = block.splitlines()
        assert lines[0].startswith('$ pump_friction ')
        yield shlex.split(lines[0][2:])[1:], lines[1:]


def test_torque_example_prints_what_the_readme_shows(capsys):
    examples = [(argv, lines) for argv, lines in console_blocks() if argv[0] == 'torque']
    assert examples
    for argv, lines in examples:
        assert main(argv) == 0
        assert capsys.readouterr().out.splitlines() == lines


def _figures(pattern, text):
    match = re.search(pattern, text, flags=re.S)
    assert match, pattern
    return [float(x) for x in match.groups()]


@pytest.fixture(scope='module')
def worked_example(tmp_path_factory):
    """Run docs/calibration.md's worked example in a scratch folder: calibrate, table, replay."""
    import os

    tmp = tmp_path_factory.mktemp('worked')
    env = pytest.MonkeyPatch()
    env.setenv('XDG_CACHE_HOME', str(tmp / 'cache'))
    env.chdir(tmp)
    try:
        from pump_friction_ros.calibration import calibrate
        result = calibrate([REPO / 'config/examples/bench_example.csv'], 'hong_doh_2004',
                           'out/my_pump.yaml', report_dir='out/calibration',
                           fix=['piston_friction.joint', 'piston_friction.head'])
        assert main(['build-table', '--pump', 'out/my_pump.yaml', '--out',
                     'out/my_pump_table.npz', '--quiet']) == 0
        yield result, tmp, os.getcwd()
    finally:
        env.undo()


def test_calibration_example_figures(worked_example):
    result = worked_example[0]
    fitted = {p.name: p for p in result.parameters}
    documented = _figures(
        r'valve_plate\.coulomb ([\d.]+) \+-([\d.]+), valve_plate\.viscous ([\d.]+) \+-([\d.]+),'
        r' bearing\.f1 ([\d.]+)\s+#?\s*\+-([\d.]+), bearing\.f0 ([\d.]+) \+-([\d.]+); RMSE '
        r'([\d.]+) -> ([\d.]+) N m; 5-fold CV ([\d.]+) N m\s+#?\s*\(noise ([\d.]+) N m\)',
        CALIBRATION)
    got = []
    for name in ('valve_plate.coulomb', 'valve_plate.viscous', 'bearing.f1', 'bearing.f0'):
        got += [fitted[name].fitted, fitted[name].ci95]
    got += [result.rmse_before_nm, result.rmse_after_nm, result.cv_rmse_nm,
            result.noise_std_nm]
    for doc, value in zip(documented, got, strict=True):
        assert value == pytest.approx(doc, abs=0.5 * 10 ** -_decimals(doc)), (doc, value)


def _decimals(number):
    text = repr(number)
    return len(text.split('.')[1]) if '.' in text else 0


def test_worked_example_replay_figures(worked_example):
    import numpy as np
    from pump_friction_ros.bags.replay import replay_bag
    from pump_friction_ros.core.estimator_setup import estimator_from_config
    from pump_friction_ros.core.node_parameters import load_estimator_config

    _, tmp, _ = worked_example
    params = tmp / 'out' / 'my_params.yaml'  # as the page's printf writes it, from $PWD
    params.write_text('/**/torque_estimator:\n  ros__parameters:\n'
                      f'    pump_file: {tmp}/out/my_pump.yaml\n'
                      f'    table_file: {tmp}/out/my_pump_table.npz\n')
    config = load_estimator_config([REPO / 'bags' / 'eha_params.yaml', params])
    core = estimator_from_config(config)
    summary = replay_bag(REPO / 'bags' / 'eha_nominal', config, core=core,
                         keep_estimates=True)
    est = summary.estimates_list
    speed = np.array([e.speed_rad_s for e in est])
    accel = np.array([e.accel_rad_s2 for e in est])
    residual = np.array([e.residual_nm for e in est])
    learnt = (np.abs(speed) >= config.monitor_min_speed_rad_s) & \
        (np.abs(accel) <= config.monitor_max_accel_rad_s2)
    mean, rest, vp = _figures(r'residual the monitor learns from averages\s+(-[\d.]+) N m.*?'
                              r'other components\s+at ([\d.]+) of the model and the valve '
                              r'plate at ([\d.]+)', CALIBRATION)
    assert np.mean(residual[learnt] * np.sign(speed[learnt])) == pytest.approx(mean, abs=5e-4)
    baseline = core.monitor.baseline
    assert baseline is not None  # learnt from the nominal bag
    assert 1.0 + baseline.coefficients[1] == pytest.approx(rest, abs=5e-3)
    assert 1.0 + baseline.coefficients[0] == pytest.approx(vp, abs=5e-3)
    assert not summary.warn_intervals and not summary.error_intervals  # "no alarm"


def _anchor(heading):
    """Return GitHub's anchor of a markdown heading: lower case, punctuation dropped."""
    text = re.sub(r'[^\w\- ]', '', heading.strip().lower())
    return text.replace(' ', '-')


def _prose(text):
    return re.sub(r'```.*?```', '', text, flags=re.S)


def test_relative_links_resolve():
    links = 0
    for page, text in PAGES.items():
        for target in re.findall(r'\]\(([^)\s]+)\)', _prose(text)):
            if re.match(r'[a-z]+:', target):
                continue
            path, _, anchor = target.partition('#')
            linked = (page.parent / path).resolve() if path else page
            assert linked.exists(), (page.name, target)
            if anchor:
                headings = re.findall(r'^#+ (.*)$', _prose(PAGES[linked]), flags=re.M)
                assert anchor in [_anchor(h) for h in headings], (page.name, target)
            links += 1
    assert links
