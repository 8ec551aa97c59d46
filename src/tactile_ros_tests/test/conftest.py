"""Shared set-up of the ROS 2 tests: the workspace root, an isolated DDS domain per run."""

from __future__ import annotations

import os
import random
from pathlib import Path

import pytest

WORKSPACE = Path(os.environ.get('TACTILE_WORKSPACE', Path(__file__).resolve().parents[3])).resolve()

# One DDS domain per test session, so concurrent runs (and other ROS users of the machine) do
# not see each other's topics; discovery stays on this host (scripts/ros2_test.sh sets
# ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST; set here too for a direct pytest run).
os.environ.setdefault('ROS_DOMAIN_ID', str(random.SystemRandom().randint(1, 100)))
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')


@pytest.fixture(scope='session')
def workspace() -> Path:
    return WORKSPACE


def pytest_configure(config):
    config.addinivalue_line(
        'markers', 'e2e: SITL flights over DDS compared with tactile sim (run by default; '
        'skipped with scripts/ros2_test.sh --no-e2e or TACTILE_ROS_E2E=0)')


def pytest_collection_modifyitems(config, items):
    """The end-to-end flights (several minutes) run unless TACTILE_ROS_E2E=0, e.g. for a
    quick run of the launch tests (scripts/ros2_test.sh --no-e2e); deselected, not skipped,
    so the summary counts only the tests that ran."""
    if os.environ.get('TACTILE_ROS_E2E', '1') != '0':
        return
    selected = [i for i in items if 'e2e' not in i.keywords]
    deselected = [i for i in items if 'e2e' in i.keywords]
    if deselected:
        config.hook.pytest_deselected(items=deselected)
        items[:] = selected
