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
Friction-torque model of a bent-axis hydraulic piston pump (Hong & Doh 2004) for ROS 2.

Layers, lowest first, each a folder whose ``__init__`` says what it may import: the base
modules here (errors, paths, yaml_files, progress, staging, plotting, blas_threads: they
import only each other), physics, table, core, messages, sim, bags, calibration, evaluation,
node, app.
docs/architecture.md draws them and says where a change goes.

May import: base.
"""

__version__ = '0.1.0'

#: Version of the physical model. Bump it whenever a change alters computed torques,
#: so that tables built by an older model are refused (see ``table``).
MODEL_VERSION = '1'
