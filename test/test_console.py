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
What the command line prints never stops what it writes (app/console.py).

A closed pipe, a full device, a terminal that cannot show a character, a file name that is
not UTF-8: subprocesses of ``pump_friction``, as a shell runs them.
"""

import os
from pathlib import Path
import shutil
import subprocess
import sys

from pump_friction_ros.core.baseline_file import read_baseline
import pytest

REPO = Path(__file__).resolve().parents[1]
BAG = REPO / 'bags' / 'eha_nominal'
PARAMS = REPO / 'bags' / 'eha_params.yaml'


def command(*argv):
    return [sys.executable, '-m', 'pump_friction_ros.app.cli', *map(os.fsencode, argv)]


def test_a_reader_that_closes_the_pipe_does_not_stop_the_baseline_being_written(
        env, tmp_path):
    out = tmp_path / 'b.yaml'
    proc = subprocess.Popen(command('learn-baseline', BAG, '--params', PARAMS, '--out', out),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    proc.stdout.close()  # `| head -0`: gone before the first line
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert b'Traceback' not in err and b'Exception ignored' not in err, err
    assert read_baseline(out)['learnt']['samples'] > 0


def test_a_full_standard_output_still_writes_the_baseline_and_says_what_was_lost(
        env, tmp_path):
    if not os.path.exists('/dev/full'):
        pytest.skip('no /dev/full on this system')
    out = tmp_path / 'b.yaml'
    with open('/dev/full', 'w') as full:
        proc = subprocess.run(command('learn-baseline', BAG, '--params', PARAMS, '--out', out),
                              stdout=full, stderr=subprocess.PIPE, env=env, timeout=120,
                              check=False)
    lines = proc.stderr.decode().strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert lines[0] == ('pump_friction: error: standard output: No space left on device: '
                        'the summary was not printed')
    assert read_baseline(out)['learnt']['samples'] > 0


def test_a_file_name_argument_that_is_not_utf8_is_refused_in_one_line(env, tmp_path):
    bag = os.fsdecode(os.fsencode(tmp_path) + b'/bag\xff')
    shutil.copytree(BAG, bag)
    proc = subprocess.run(command('learn-baseline', bag, '--params', PARAMS, '--out',
                                  tmp_path / 'b.yaml'),
                          capture_output=True, env=env, timeout=120, check=False)
    lines = proc.stderr.decode().strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert lines[0].startswith('pump_friction: error: argument ') and \
        'bag\\xff' in lines[0] and 'not valid UTF-8' in lines[0]
    assert not (tmp_path / 'b.yaml').exists()


def test_a_fleet_bag_named_in_another_encoding_is_learnt_its_name_written_escaped(
        env, tmp_path):
    fleet = tmp_path / 'fleet'
    shutil.copytree(BAG, os.fsdecode(os.fsencode(fleet) + b'/run\xff'))
    out = tmp_path / 'b.yaml'
    proc = subprocess.run(command('learn-baseline', fleet, '--params', PARAMS, '--out', out),
                          capture_output=True, env=env, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr
    assert b'Traceback' not in proc.stderr
    assert read_baseline(out)['about']['origin'].endswith('run\\xff')


def test_an_ascii_terminal_gets_every_line_escaped_not_a_traceback(env, tmp_path):
    out = tmp_path / 'pompe_\u00e9t\u00e9.yaml'  # printed in the summary
    proc = subprocess.run(command('learn-baseline', BAG, '--params', PARAMS, '--out', out),
                          capture_output=True, env={**env, 'PYTHONIOENCODING': 'ascii'},
                          timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr
    assert b'Traceback' not in proc.stderr
    assert b'pompe_\\xe9t\\xe9.yaml' in proc.stdout
    assert read_baseline(out)['learnt']['samples'] > 0
