"""Launch the torque_estimator node with its parameters file (remap its inputs as needed)."""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    """Return the launch description: arguments params_file, use_sim_time, namespace."""
    default_params = os.path.join(get_package_share_directory('pump_friction_ros'), 'config',
                                  'torque_estimator.yaml')
    return LaunchDescription([
        DeclareLaunchArgument('params_file', default_value=default_params,
                              description='ROS 2 parameters file of the torque_estimator'),
        DeclareLaunchArgument('use_sim_time', default_value='false',
                              description='follow /clock (bag replay with --clock)'),
        DeclareLaunchArgument('namespace', default_value='',
                              description='namespace of the node and its relative topics'),
        Node(
            package='pump_friction_ros',
            executable='torque_estimator',
            name='torque_estimator',
            namespace=LaunchConfiguration('namespace'),
            parameters=[LaunchConfiguration('params_file'),
                        {'use_sim_time': LaunchConfiguration('use_sim_time')}],
            output='screen',
        ),
    ])
