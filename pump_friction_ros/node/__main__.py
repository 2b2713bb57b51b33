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
Entry point of ``torque_estimator`` (console script, ``python -m pump_friction_ros.node``).

Light on purpose: the stop-signal handler is installed before rclpy and the message packages
are imported (a second or so on a small computer), so a Ctrl-C at any moment of the start-up
stops the node with exit code 0 and one line, never a ``KeyboardInterrupt`` traceback.
"""

from __future__ import annotations

import sys

from .stop_signals import StopSignals

__all__ = ['main']


def main(args: list[str] | None = None) -> int:
    """
    Run the node (console script ``torque_estimator``).

    Parameters
    ----------
    args : list of str, optional
        Command-line arguments for rclpy.

    Returns
    -------
    int
        0 on a normal shutdown (SIGINT, SIGTERM, or the context shut down elsewhere), 1 when
        the parameters, pump file or table are invalid, or rclpy cannot be imported.

    """
    with StopSignals() as stop:
        try:
            from .torque_estimator import run  # rclpy, the messages: after the handler
        except ImportError as exc:  # a shell without ROS 2 sourced
            print(f'torque_estimator: cannot start: {exc} (the node needs ROS 2 Jazzy: '
                  'source /opt/ros/jazzy/setup.bash)', file=sys.stderr)
            return 1
        return run(args, stop)


if __name__ == '__main__':
    sys.exit(main())
