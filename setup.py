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

from glob import glob

from setuptools import find_packages, setup

package_name = 'pump_friction_ros'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
        ('share/' + package_name + '/config/pumps', glob('config/pumps/*.yaml')),
    ],
    python_requires='>=3.10',
    install_requires=[
        'setuptools',
        'numpy>=1.24',
        'scipy>=1.10',
        'PyYAML>=6.0',
        'matplotlib>=3.6',
        'rosbags>=0.10',
        'ruamel.yaml>=0.17.21',
    ],
    extras_require={
        # pytest is bounded below 9: with a ROS 2 Jazzy install sourced, the
        # launch_testing / launch_ros pytest plugins make pytest 9 fail to start.
        # mypy: test_types.py; 1.12 is the oldest release the package checks clean with.
        'test': ['pytest>=7,<9', 'ruff>=0.5', 'dask[distributed]>=2024.1', 'hypothesis>=6',
                 'mypy>=1.12', 'types-PyYAML>=6.0'],
        'fleet': ['dask[distributed]>=2024.1'],
    },
    zip_safe=True,
    maintainer='pump_friction_ros developers',
    maintainer_email='dev@pump-friction-ros.invalid',
    description='Bent-axis pump friction model, torque table, estimator node and bag replay.',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'pump_friction = pump_friction_ros.app.entry:main',
            'torque_estimator = pump_friction_ros.node.__main__:main',
            'measure_node_cpu = pump_friction_ros.node.measure_cpu:main',
        ],
    },
)
