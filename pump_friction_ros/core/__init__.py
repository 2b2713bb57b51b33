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
Core: the ROS-free estimator the node and the replay share.

Node parameters (`node_parameters`, declared once), the input table (`inputs`), the
viscosity range the friction table covers (`oil_range`), the estimate record, the speed
filter, the wear monitor and its attribution, the diagnostics snapshot and
`TorqueEstimator`, whose `on_input` is the one entry point.

May import: table, physics, base.
"""
