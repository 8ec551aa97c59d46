"""Peer tests of tactile_bag against the independent Python ``rosbags`` package.

(a) Bags written by ``tactile_bag_tool write-sample`` (metadata versions 9, 8, 5) are
    read by ``rosbags.rosbag2.Reader``; types are registered from the bag's own message
    definitions and every message deserializes to the values documented in
    tools/sample.hpp (recomputed here).
(b) Bags written by ``rosbags.rosbag2.Writer`` (versions 8 and 9, CDR, std_msgs,
    geometry_msgs and tactile_msgs types) are read by our reader through
    ``tactile_bag_tool dump``; payload bytes and decoded values match.
"""

import json
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

TOOL = os.environ.get('TACTILE_BAG_TOOL', 'tactile_bag_tool')
MSG_DIR = Path(__file__).resolve().parents[2] / 'tactile_msgs' / 'msg'
SEPARATOR = '=' * 80 + '\n'


def run_tool(*args, check=True):
    return subprocess.run([TOOL, *map(str, args)], capture_output=True, text=True, check=check)


def register_from_msgdef(typestore, msgtype, msgdef):
    """Register a type and its dependencies from a rosbag2 ros2msg definition."""
    parts = msgdef.split(SEPARATOR)
    types = dict(get_types_from_msg(parts[0], msgtype))
    for part in parts[1:]:
        header, _, body = part.partition('\n')
        assert header.startswith('MSG: '), header
        pkg, name = header[len('MSG: '):].strip().split('/')
        types.update(get_types_from_msg(body, f'{pkg}/msg/{name}'))
    typestore.register(types)


# ---------------------------------------------------------------- expected sample
T0 = 1_000_000_000


def expected_sample():
    """(topic, timestamp, check(msg)) of tools/sample.hpp, recomputed independently."""
    out = []
    for i in range(5):
        t = T0 + i * 20_000_000
        out.append(('/whisker/left/pressure', t, dict(
            sec=t // 10**9, nanosec=t % 10**9, frame_id='whisker_left', whisker_id=0,
            pressure=[101325.0 + 10 * i + k for k in range(3)],
            temperature=[25.0 + 0.5 * k for k in range(3)], sequence=i)))
    for i in range(5):
        t = T0 + i * 20_000_000 + 10_000_000
        out.append(('/whisker/right/pressure', t, dict(
            sec=t // 10**9, nanosec=t % 10**9, frame_id='whisker_right', whisker_id=1,
            pressure=[100000.0 - 7 * i - k for k in range(3)],
            temperature=[math.nan] * 3, sequence=100 + i)))
    for i in range(3):
        out.append(('/chatter', T0 + i * 30_000_000 + 5_000_000, dict(data=f'hello {i}')))
    for i in range(2):
        out.append(('/vector', T0 + i * 50_000_000 + 1_000_000,
                    dict(x=i + 0.25, y=-float(i), z=1e-3 * i)))
    # the reader returns timestamp order; ties do not occur in the sample
    return sorted(out, key=lambda x: x[1])


def check_whisker(msg, exp):
    assert msg.header.stamp.sec == exp['sec']
    assert msg.header.stamp.nanosec == exp['nanosec']
    assert msg.header.frame_id == exp['frame_id']
    assert msg.whisker_id == exp['whisker_id']
    np.testing.assert_array_equal(msg.pressure, exp['pressure'])
    np.testing.assert_array_equal(msg.temperature, exp['temperature'])  # NaN == NaN here
    assert msg.sequence == exp['sequence']


@pytest.mark.parametrize('version', [9, 8, 5])
def test_sample_bag_is_read_by_rosbags(tmp_path, version):
    bag = tmp_path / f'sample_v{version}'
    run_tool('write-sample', bag, '--version', version)
    typestore = get_typestore(Stores.EMPTY)
    with Reader(bag) as reader:
        assert reader.message_count == 15
        assert reader.start_time == T0
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert counts == {'/whisker/left/pressure': 5, '/whisker/right/pressure': 5,
                          '/chatter': 3, '/silent': 0, '/vector': 2}
        registered = set()
        for conn in reader.connections:
            qos = conn.ext.offered_qos_profiles
            assert len(qos) == 1
            assert qos[0].reliability == QosReliability.RELIABLE
            assert qos[0].durability == QosDurability.VOLATILE
            assert qos[0].liveliness == QosLiveliness.AUTOMATIC
            assert conn.ext.serialization_format == 'cdr'
            if conn.msgtype not in registered:
                assert conn.msgdef.data, f'{conn.topic}: no message definition in the bag'
                register_from_msgdef(typestore, conn.msgtype, conn.msgdef.data)
                registered.add(conn.msgtype)
        got = [(c.topic, t, typestore.deserialize_cdr(raw, c.msgtype))
               for c, t, raw in reader.messages()]
    expected = expected_sample()
    assert [(t, ts) for t, ts, _ in got] == [(t, ts) for t, ts, _ in expected]
    for (topic, _, msg), (_, _, exp) in zip(got, expected):
        if topic.startswith('/whisker'):
            check_whisker(msg, exp)
        elif topic == '/chatter':
            assert msg.data == exp['data']
        else:
            assert (msg.x, msg.y, msg.z) == (exp['x'], exp['y'], exp['z'])


# ---------------------------------------------------------------- rosbags -> us
def latest_with_whisker():
    typestore = get_typestore(Stores.LATEST)
    text = (MSG_DIR / 'WhiskerPressure.msg').read_text()
    typestore.register(get_types_from_msg(text, 'tactile_msgs/msg/WhiskerPressure'))
    return typestore


def dump(bag, *topics):
    res = run_tool('dump', bag, *topics)
    return [json.loads(line) for line in res.stdout.splitlines()]


@pytest.mark.parametrize('version', [9, 8])
def test_rosbags_bag_is_read_by_tactile_bag(tmp_path, version):
    ts = latest_with_whisker()
    String = ts.types['std_msgs/msg/String']
    Vector3 = ts.types['geometry_msgs/msg/Vector3']
    WrenchStamped = ts.types['geometry_msgs/msg/WrenchStamped']
    Header = ts.types['std_msgs/msg/Header']
    Time = ts.types['builtin_interfaces/msg/Time']
    WhiskerPressure = ts.types['tactile_msgs/msg/WhiskerPressure']
    best_effort = Qos(QosHistory.KEEP_LAST, 5, QosReliability.BEST_EFFORT, QosDurability.VOLATILE,
                      QosTime(0, 0), QosTime(0, 0), QosLiveliness.AUTOMATIC, QosTime(0, 0), False)

    bag = tmp_path / f'rosbags_v{version}'
    written = []  # (topic, timestamp, msgtype, bytes)
    with Writer(bag, version=version) as w:
        conns = {
            '/chatter': w.add_connection('/chatter', 'std_msgs/msg/String', typestore=ts),
            '/vec': w.add_connection('/vec', 'geometry_msgs/msg/Vector3', typestore=ts,
                                     offered_qos_profiles=[best_effort]),
            '/wrench': w.add_connection('/wrench', 'geometry_msgs/msg/WrenchStamped', typestore=ts),
            '/whisker/right/pressure': w.add_connection(
                '/whisker/right/pressure', 'tactile_msgs/msg/WhiskerPressure', typestore=ts),
        }
        msgs = [
            ('/chatter', 300, String(data='späť ünïcode')),
            ('/vec', 100, Vector3(x=1.5, y=-2.0, z=1e300)),
            ('/whisker/right/pressure', 200, WhiskerPressure(
                header=Header(stamp=Time(sec=7, nanosec=123), frame_id='whisker_right'),
                whisker_id=1, pressure=np.array([1.0, 2.0, 3.0]),
                temperature=np.array([np.nan, 20.0, -5.5]), sequence=4_000_000_000)),
            ('/wrench', 50, WrenchStamped(
                header=Header(stamp=Time(sec=-1, nanosec=0), frame_id=''),
                wrench=ts.types['geometry_msgs/msg/Wrench'](
                    force=Vector3(x=0.0, y=1.0, z=2.0), torque=Vector3(x=3.0, y=4.0, z=5.0)))),
            ('/chatter', 250, String(data='')),
        ]
        for topic, t, msg in msgs:
            raw = ts.serialize_cdr(msg, conns[topic].msgtype)
            w.write(conns[topic], t, raw)
            written.append((topic, t, conns[topic].msgtype, bytes(raw)))

    lines = dump(bag)
    expected = sorted(written, key=lambda x: x[1])
    assert [(d['topic'], d['timestamp'], d['type']) for d in lines] == \
        [(t, s, ty) for t, s, ty, _ in expected]
    for d, (_, _, msgtype, raw) in zip(lines, expected):
        payload = bytes.fromhex(d['data'])
        assert payload == raw
        # values, decoded from our bytes
        back = ts.deserialize_cdr(payload, msgtype)
        orig = ts.deserialize_cdr(raw, msgtype)
        if msgtype == 'tactile_msgs/msg/WhiskerPressure':
            assert back.sequence == 4_000_000_000
            np.testing.assert_array_equal(back.temperature, orig.temperature)
        elif msgtype == 'std_msgs/msg/String':
            assert back.data == orig.data

    # topic filter and info
    only = dump(bag, '/chatter')
    assert [d['timestamp'] for d in only] == [250, 300]
    info = run_tool('info', bag).stdout
    assert f'version {version}' in info
    assert 'messages:     5' in info
    assert '/chatter | std_msgs/msg/String | cdr | 2 msgs' in info
    assert '/whisker/right/pressure | tactile_msgs/msg/WhiskerPressure | cdr | 1 msgs' in info


def test_tool_errors_name_the_path(tmp_path):
    res = run_tool('info', tmp_path / 'missing', check=False)
    assert res.returncode == 1
    assert 'missing' in res.stderr and 'does not exist' in res.stderr
    res = run_tool('frobnicate', tmp_path, check=False)
    assert res.returncode == 2
