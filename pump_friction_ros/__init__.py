"""Friction-torque model of a bent-axis hydraulic piston pump (Hong & Doh 2004) for ROS 2."""

__version__ = '0.1.0'

#: Version of the physical model. Bump it whenever a change alters computed torques,
#: so that tables built by an older model are refused (see ``table``).
MODEL_VERSION = '1'
