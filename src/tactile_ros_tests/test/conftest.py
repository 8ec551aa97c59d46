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
