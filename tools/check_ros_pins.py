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
Fail when a ``ros-*`` distribution is installed at a version other than Jazzy's.

Run with the virtual environment's Python after installing requirements-ros.txt
(tools/test.sh does): every installed ``ros-*`` must be pinned, at that version, in
constraints/ros-jazzy.txt. A Kilted wheel beside Jazzy's makes rclpy hang, not fail.
"""

import importlib.metadata
from pathlib import Path
import re
import sys

CONSTRAINTS = Path(__file__).resolve().parents[1] / 'constraints' / 'ros-jazzy.txt'


def canonical(name):
    """Return a distribution name as pip compares them (PEP 503)."""
    return re.sub(r'[-_.]+', '-', name).lower()


def main():
    """Compare the installed ros-* distributions with the pins; print and return 0 or 1."""
    pins = {}
    for line in CONSTRAINTS.read_text().splitlines():
        line = line.split('#', 1)[0].strip()
        if line:
            name, _, version = line.partition('==')
            pins[canonical(name)] = version.strip()
    installed = {canonical(d.metadata['Name']): d.version
                 for d in importlib.metadata.distributions()
                 if canonical(d.metadata['Name'] or '').startswith('ros-')}
    wrong = [f'{name} {version} (Jazzy: {pins.get(name, "not pinned")})'
             for name, version in sorted(installed.items()) if pins.get(name) != version]
    if not installed:
        print(f'{Path(__file__).name}: no ros-* distribution is installed', file=sys.stderr)
        return 1
    if wrong:
        print(f"{Path(__file__).name}: not Jazzy's versions (add the pin to "
              f'{CONSTRAINTS.name}): ' + ', '.join(wrong), file=sys.stderr)
        return 1
    print(f"ros-* wheels: {len(installed)}, all at Jazzy's versions "
          f'(rclpy {installed.get("ros-rclpy", "absent")})')
    return 0


if __name__ == '__main__':
    sys.exit(main())
