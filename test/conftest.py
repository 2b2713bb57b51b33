"""Shared fixtures: the two shipped pump parameter sets and their models."""

from pathlib import Path

from pump_friction_ros.model import PumpModel
from pump_friction_ros.params import load_pump
import pytest

REPO = Path(__file__).resolve().parents[1]
PAPER_PUMP = REPO / 'config' / 'pumps' / 'hong_doh_2004.yaml'
CONSISTENT_PUMP = REPO / 'config' / 'pumps' / 'hong_doh_2004_consistent.yaml'


@pytest.fixture(scope='session')
def paper_params():
    return load_pump(PAPER_PUMP)


@pytest.fixture(scope='session')
def consistent_params():
    return load_pump(CONSISTENT_PUMP)


@pytest.fixture(scope='session')
def paper_model(paper_params):
    return PumpModel(paper_params)


@pytest.fixture(scope='session')
def consistent_model(consistent_params):
    return PumpModel(consistent_params)


def pytest_configure(config):
    # markers the ament linters and launch_testing register themselves when ROS is sourced
    for marker in ('flake8', 'pep257', 'copyright', 'linter', 'launch_test', 'rostest'):
        config.addinivalue_line('markers', f'{marker}: ament / launch_testing marker')
