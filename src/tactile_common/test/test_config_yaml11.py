"""Every parameter file in config/ reads the same to the launch system as to the standalone host.

`ros2 launch` reads parameter files with PyYAML (YAML 1.1): there `52.0e9` is a string (a
float needs a sign in its exponent), while yaml-cpp, which the standalone host uses, reads
it as a number. A node then gets a string where it needs a double. This test reads every
config/*.yaml as the launch system does and rejects values that only yaml-cpp would take
for numbers.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

CONFIG = Path(__file__).resolve().parents[3] / 'config'
# A YAML 1.2 / yaml-cpp number that YAML 1.1 leaves a string.
NUMBER_ONLY_IN_12 = re.compile(r'^[-+]?(\d+\.?\d*|\.\d+)[eE]\d+$')


def leaves(node, path=''):
    if isinstance(node, dict):
        for k, v in node.items():
            yield from leaves(v, f'{path}.{k}' if path else str(k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from leaves(v, f'{path}[{i}]')
    else:
        yield path, node


FILES = sorted(CONFIG.glob('*.yaml'))


def test_config_files_found():
    assert len(FILES) >= 10, CONFIG


@pytest.mark.parametrize('path', FILES, ids=lambda p: p.name)
def test_numbers_are_numbers_to_yaml11(path):
    data = yaml.safe_load(path.read_text())
    bad = [(k, v) for k, v in leaves(data) if isinstance(v, str) and NUMBER_ONLY_IN_12.match(v.strip())]
    assert not bad, f'{path.name}: YAML 1.1 (ros2 launch) reads these as strings: {bad}'


def test_the_rule_catches_the_case_it_is_for():
    assert isinstance(yaml.safe_load('x: 52.0e9')['x'], str)
    assert NUMBER_ONLY_IN_12.match('52.0e9')
    assert isinstance(yaml.safe_load('x: 52.0e+9')['x'], float)
