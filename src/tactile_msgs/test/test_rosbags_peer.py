"""Peer test of the generated C++ CDR code against the Python rosbags package.

- Our definition texts are registered with rosbags (get_types_from_msg), i.e. they parse
  the way rosbag2 readers parse them.
- Bytes serialized by C++ decode in rosbags to the values of an independent Python
  implementation of the deterministic filler, and equal rosbags' own serialization.
- rosbags-serialized messages decode in C++ to the same values.
- The ROS-free standard messages match rosbags' ROS 2 Humble store field for field.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

PKG_DIR = Path(__file__).resolve().parent.parent
SEPARATOR = '=' * 80

BASE, NAME, ARRAY, SEQUENCE = 1, 2, 3, 4
INT_BITS = {'int8': (8, True), 'uint8': (8, False), 'byte': (8, False), 'char': (8, False),
            'int16': (16, True), 'uint16': (16, False), 'int32': (32, True),
            'uint32': (32, False), 'int64': (64, True), 'uint64': (64, False)}
NP_DTYPE = {'bool': np.bool_, 'int8': np.int8, 'uint8': np.uint8, 'byte': np.uint8,
            'char': np.uint8, 'int16': np.int16, 'uint16': np.uint16, 'int32': np.int32,
            'uint32': np.uint32, 'int64': np.int64, 'uint64': np.uint64,
            'float32': np.float32, 'float64': np.float64}


def peer() -> str:
    path = os.environ.get('TACTILE_MSGS_PEER')
    if not path:
        pytest.skip('TACTILE_MSGS_PEER not set (run through ctest)')
    return path


@pytest.fixture(scope='module')
def dump() -> dict[str, dict]:
    out = subprocess.run([peer(), 'dump'], check=True, capture_output=True, text=True).stdout
    entries = [json.loads(line) for line in out.splitlines() if line.strip()]
    return {e['type']: e for e in entries}


@pytest.fixture(scope='module')
def store(dump):
    """An empty rosbags type store with every type registered from OUR definition texts."""
    ts = get_typestore(Stores.EMPTY)
    for name, entry in dump.items():
        ts.register(get_types_from_msg(entry['definition'], name))
    return ts


# --- independent Python implementation of the filler (see generate_msgs.emit_testing) ---


class Filler:
    def __init__(self) -> None:
        self.k = 1

    def take(self) -> int:
        k = self.k
        self.k += 1
        return k

    def prim(self, base: str):
        k = self.take()
        if base == 'bool':
            return k % 2 == 1
        if base in ('float32', 'float64'):
            return (-1.0 if k % 2 == 1 else 1.0) * (k + 0.25)
        bits, signed = INT_BITS[base]
        u = (k * 2654435761) % (1 << bits)
        if signed and u >= 1 << (bits - 1):
            u -= 1 << bits
        return u

    def string(self, bound: int) -> str:
        s = f's{self.take()}'
        return s[:bound] if bound else s

    def count(self, bound: int) -> int:
        n = self.take() % 3 + 1
        return min(n, bound) if bound else n


def fill_value(ts, desc, f: Filler):
    kind, args = desc
    if kind == BASE:
        base, bound = args
        return f.string(bound) if base == 'string' else f.prim(base)
    if kind == NAME:
        return fill_message(ts, args, f)
    (sub, size) = args
    n = size if kind == ARRAY else f.count(size)
    items = [fill_value(ts, sub, f) for _ in range(n)]
    if sub[0] == BASE and sub[1][0] != 'string':
        return np.array(items, dtype=NP_DTYPE[sub[1][0]])
    return items


def fill_message(ts, typename: str, f: Filler | None = None):
    f = f or Filler()
    _, fields = ts.fielddefs[typename]
    kwargs = {name: fill_value(ts, desc, f) for name, desc in fields}
    return ts.types[typename](**kwargs)


def assert_same(a, b, path: str = 'msg') -> None:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        assert a.shape == b.shape, path
        assert np.array_equal(a, b), f'{path}: {a} != {b}'
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f'{path}[{i}]')
    elif hasattr(a, '__dataclass_fields__'):
        assert type(a).__name__ == type(b).__name__, path
        for name in a.__dataclass_fields__:
            assert_same(getattr(a, name), getattr(b, name), f'{path}.{name}')
    else:
        assert a == b, f'{path}: {a!r} != {b!r}'


# --- tests ---


def test_every_type_is_dumped(dump):
    assert len(dump) >= 40
    for pkg in ('tactile_msgs', 'std_msgs', 'geometry_msgs', 'sensor_msgs', 'nav_msgs',
                'builtin_interfaces'):
        assert any(t.startswith(pkg + '/msg/') for t in dump), pkg


def test_definitions_have_rosbag2_layout(dump):
    for name, entry in dump.items():
        pkg, _, typ = name.split('/')
        text = entry['definition']
        own = text.split(SEPARATOR + '\n')[0]
        if pkg == 'tactile_msgs':
            assert own == (PKG_DIR / 'msg' / f'{typ}.msg').read_text()
        elif os.environ.get('TACTILE_MSGS_ROS_FREE') == '1':
            # In ROS builds the standard texts come from the installed ROS packages.
            assert own == (PKG_DIR / 'ros_free_std' / pkg / 'msg' / f'{typ}.msg').read_text()
        for block in text.split(SEPARATOR + '\n')[1:]:
            header = block.split('\n', 1)[0]
            assert header.startswith('MSG: ') and '/msg/' not in header, header
        deps = [b.split('\n', 1)[0][5:] for b in text.split(SEPARATOR + '\n')[1:]]
        assert len(deps) == len(set(deps)), f'{name}: duplicate dependency'


def test_dependencies_are_complete(dump):
    # Each definition alone (as a bag reader sees it) must define every type it uses.
    for name, entry in dump.items():
        types = get_types_from_msg(entry['definition'], name)
        for _, fields in types.values():
            for _, (kind, args) in fields:
                if kind == NAME:
                    assert args in types, f'{name}: {args} missing'
                elif kind in (ARRAY, SEQUENCE) and args[0][0] == NAME:
                    assert args[0][1] in types, f'{name}: {args[0][1]} missing'


def test_cpp_bytes_decode_in_rosbags(dump, store):
    for name, entry in dump.items():
        ours = bytes.fromhex(entry['hex'])
        expected = fill_message(store, name)
        decoded = store.deserialize_cdr(ours, name)
        assert_same(decoded, expected, name)
        theirs = bytes(store.serialize_cdr(expected, name))
        assert ours == theirs, f'{name}: C++ bytes differ from rosbags bytes'


def test_rosbags_bytes_decode_in_cpp(dump, store):
    names = sorted(dump)
    request = ''.join(
        f'{n} {bytes(store.serialize_cdr(fill_message(store, n), n)).hex()}\n' for n in names)
    out = subprocess.run([peer(), 'check'], input=request, check=True, capture_output=True,
                         text=True).stdout
    replies = [json.loads(line) for line in out.splitlines()]
    assert [r['type'] for r in replies] == names
    for n, reply in zip(names, replies):
        assert reply['ok'], f'{n}: {reply["error"]}'
        assert reply['equal'], f'{n}: decoded value differs from the expected message'
        assert reply['hex'] == bytes(store.serialize_cdr(fill_message(store, n), n)).hex()


def test_cpp_rejects_truncated_rosbags_bytes(store):
    n = 'tactile_msgs/msg/WhiskerSignal'
    data = bytes(store.serialize_cdr(fill_message(store, n), n))
    request = ''.join(f'{n} {data[:cut].hex()}\n' for cut in range(0, len(data), 7))
    out = subprocess.run([peer(), 'check'], input=request, check=True, capture_output=True,
                         text=True).stdout
    replies = [json.loads(line) for line in out.splitlines()]
    assert replies and all(not r['ok'] and n in r['error'] for r in replies)


STD_TYPES = [
    'builtin_interfaces/msg/Time', 'builtin_interfaces/msg/Duration',
    'std_msgs/msg/Header', 'std_msgs/msg/Float64', 'std_msgs/msg/Bool', 'std_msgs/msg/String',
    'geometry_msgs/msg/Point', 'geometry_msgs/msg/Point32', 'geometry_msgs/msg/Vector3',
    'geometry_msgs/msg/Quaternion', 'geometry_msgs/msg/Pose', 'geometry_msgs/msg/PoseStamped',
    'geometry_msgs/msg/PoseArray', 'geometry_msgs/msg/Twist', 'geometry_msgs/msg/TwistStamped',
    'geometry_msgs/msg/Wrench', 'geometry_msgs/msg/WrenchStamped', 'geometry_msgs/msg/Accel',
    'geometry_msgs/msg/PoseWithCovariance', 'geometry_msgs/msg/TwistWithCovariance',
    'geometry_msgs/msg/Transform', 'geometry_msgs/msg/TransformStamped',
    'sensor_msgs/msg/Imu', 'sensor_msgs/msg/Range', 'sensor_msgs/msg/PointCloud2',
    'sensor_msgs/msg/PointField', 'sensor_msgs/msg/Temperature', 'sensor_msgs/msg/FluidPressure',
    'nav_msgs/msg/Odometry', 'nav_msgs/msg/Path',
    'sensor_msgs/msg/CompressedImage', 'std_msgs/msg/ColorRGBA',
    'nav_msgs/msg/OccupancyGrid', 'nav_msgs/msg/MapMetaData',
    'visualization_msgs/msg/UVCoordinate', 'visualization_msgs/msg/MeshFile',
    'visualization_msgs/msg/Marker', 'visualization_msgs/msg/MarkerArray',
]


def ros_free_fields(typename):
    pkg, _, typ = typename.split('/')
    text = (PKG_DIR / 'ros_free_std' / pkg / 'msg' / f'{typ}.msg').read_text()
    ours = get_types_from_msg(text, typename)[typename]
    return [(n, t, v) for n, t, v in ours[0]], [(n, d) for n, d in ours[1]]


@pytest.mark.parametrize('store_name', ['ROS2_KILTED', 'ROS2_JAZZY'])
@pytest.mark.parametrize('typename', STD_TYPES)
def test_std_types_match_ros2_kilted_and_jazzy(typename, store_name):
    """ros_free_std/*.msg field for field against rosbags' Kilted and Jazzy stores.

    The ROS-free standard types follow Kilted (the distro whose toolchain the ROS build is
    tested with); Jazzy has the same layouts for every type of the list.
    """
    store = get_typestore(getattr(Stores, store_name))
    consts, fields = store.fielddefs[typename]
    assert ros_free_fields(typename) == ([(n, t, v) for n, t, v in consts],
                                         [(n, d) for n, d in fields])


@pytest.mark.parametrize('typename', STD_TYPES)
def test_std_types_vs_ros2_humble(typename):
    """Humble differs in two places: sensor_msgs/Range has no trailing variance, and
    visualization_msgs/Marker has no constant ARROW_STRIP (its fields are the same)."""
    consts, fields = get_typestore(Stores.ROS2_HUMBLE).fielddefs[typename]
    ours_consts, ours_fields = ros_free_fields(typename)
    if typename == 'visualization_msgs/msg/Marker':
        assert ('ARROW_STRIP', 'int32', 12) in ours_consts
        ours_consts = [c for c in ours_consts if c[0] != 'ARROW_STRIP']
    assert ours_consts == [(n, t, v) for n, t, v in consts]
    if typename == 'sensor_msgs/msg/Range':
        assert ours_fields[-1][0] == 'variance'
        ours_fields = ours_fields[:-1]
    assert ours_fields == [(n, d) for n, d in fields]


def test_std_types_cover_list(dump):
    for t in STD_TYPES:
        if (t.startswith('visualization_msgs/') and os.environ.get('TACTILE_MSGS_ROS_FREE') != '1'
                and t not in dump):
            continue  # a ROS toolchain without visualization_msgs (see CMakeLists.txt)
        assert t in dump, t
