"""The operator services of srv/ (crazyflie_bridge's surface) have the request and response
fields of Crazyswarm2's crazyflie_interfaces, field for field, so that Crazyswarm2 clients and
`ros2 service call` lines written for it work against the bridge; StartBehaviour has the fields
of std_srvs/srv/Trigger. Each half of a .srv is parsed with the generator's .msg parser (the
ROS-free build makes no service types: the files are the contract, rosidl builds them)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

PKG_DIR = Path(__file__).resolve().parent.parent
spec = importlib.util.spec_from_file_location('generate_msgs', PKG_DIR / 'scripts' / 'generate_msgs.py')
gen = importlib.util.module_from_spec(spec)
sys.modules['generate_msgs'] = gen
spec.loader.exec_module(gen)

# IMRCLab/crazyswarm2, crazyflie_interfaces/srv/<Name>.srv (request fields; every response
# there is empty). std_srvs/srv/Trigger: empty request; bool success, string message.
EXPECTED = {
    'Takeoff': ([('uint8', 'group_mask'), ('float32', 'height'),
                 ('builtin_interfaces/Duration', 'duration')], []),
    'Land': ([('uint8', 'group_mask'), ('float32', 'height'),
              ('builtin_interfaces/Duration', 'duration')], []),
    'GoTo': ([('uint8', 'group_mask'), ('bool', 'relative'), ('geometry_msgs/Point', 'goal'),
              ('float32', 'yaw'), ('builtin_interfaces/Duration', 'duration')], []),
    'Stop': ([('uint8', 'group_mask')], []),
    'NotifySetpointsStop': ([('uint8', 'group_mask'), ('uint32', 'remain_valid_millisecs')], []),
    'Arm': ([('bool', 'arm')], []),
    'StartBehaviour': ([], [('bool', 'success'), ('string', 'message')]),
}


def halves(path: Path, tmp_path: Path):
    text = path.read_text()
    lines = text.splitlines()
    separators = [i for i, line in enumerate(lines) if line.strip() == '---']
    assert len(separators) == 1, f'{path}: expected one "---" line, found {len(separators)}'
    out = []
    for part, body in (('Request', lines[:separators[0]]), ('Response', lines[separators[0] + 1:])):
        msg = tmp_path / 'tactile_msgs' / 'msg' / f'{path.stem}_{part}.msg'
        msg.parent.mkdir(parents=True, exist_ok=True)
        msg.write_text('\n'.join(body) + '\n')
        parsed = gen.parse_msg(msg)
        assert not parsed.constants, f'{path}: {part} has constants'
        out.append([(f.type.full_name if f.type.is_message else f.type.base, f.name)
                    for f in parsed.fields])
    return out


def test_every_service_file_is_checked():
    assert sorted(p.stem for p in (PKG_DIR / 'srv').glob('*.srv')) == sorted(EXPECTED)


@pytest.mark.parametrize('name', sorted(EXPECTED))
def test_service_fields(name, tmp_path):
    request, response = halves(PKG_DIR / 'srv' / f'{name}.srv', tmp_path)
    assert (request, response) == EXPECTED[name]


def test_services_cite_their_source():
    for name in EXPECTED:
        text = (PKG_DIR / 'srv' / f'{name}.srv').read_text()
        source = 'std_srvs/srv/Trigger' if name == 'StartBehaviour' else \
            f'crazyflie_interfaces/srv/{name}.srv (IMRCLab/crazyswarm2)'
        assert source in text, f'{name}.srv does not name {source}'
