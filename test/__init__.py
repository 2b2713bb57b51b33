"""Tests of pump_friction_ros."""
