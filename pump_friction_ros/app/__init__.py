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
App: the ``pump_friction`` command line, its data commands, figures, benchmarks.

The top layer: it wires the others to the command line.

May import: node, evaluation, calibration, bags, sim, messages, core, table, physics, base.
"""

from ..blas_threads import limit_blas_threads

limit_blas_threads()  # before numpy loads BLAS: see blas_threads
