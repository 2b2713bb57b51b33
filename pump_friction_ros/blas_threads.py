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
One BLAS thread for the node and the command line, unless the user chose otherwise.

The package's matrices are 6 x 6 (the wear monitor's baseline and isolation).
OpenBLAS, which numpy's wheels bundle and Ubuntu's numpy links, starts a thread per core
at the first call and keeps the others busy-waiting after every call: measured here, any
call on a 5 x 5 matrix cost twice its time in CPU, the second core spinning. Next to an
EHA controller that is a core taken from the controller; in a replay it is the reader
process's core (the replay of the wear bag went from 1.55x to 1.87x the rosbags loop with
one thread). The entry layers (``node``, ``app``) call `limit_blas_threads` before
anything imports numpy; the library layers do not, so a program that imports them keeps
its own setting. An environment variable the user set wins.
"""

from __future__ import annotations

import os

__all__ = ['BLAS_THREAD_VARIABLES', 'limit_blas_threads']

BLAS_THREAD_VARIABLES = ('OPENBLAS_NUM_THREADS', 'MKL_NUM_THREADS', 'OMP_NUM_THREADS')
"""What OpenBLAS (pthreads or OpenMP build) and MKL read at load time."""


def limit_blas_threads() -> None:
    """
    Ask the BLAS numpy will load for one thread, where the environment does not say.

    Works only before numpy is first imported in the process (BLAS reads the variables
    when it loads); a later call changes nothing for this process but is inherited by the
    processes it starts.

    """
    for name in BLAS_THREAD_VARIABLES:
        os.environ.setdefault(name, '1')
