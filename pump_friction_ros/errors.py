"""Exceptions raised by pump_friction_ros; every one carries a message fit for a user."""

__all__ = ['ConfigError', 'PumpFrictionError', 'TableError']


class PumpFrictionError(Exception):
    """Base class of every error this package raises on purpose."""


class ConfigError(PumpFrictionError, ValueError):
    """A pump parameter file or a parameter set is missing, malformed or non-physical."""


class TableError(PumpFrictionError, ValueError):
    """A friction-torque table file is malformed or does not match the pump in use."""
