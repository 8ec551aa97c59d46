"""Interop of tactile_bag's mcap and compressed bags with independent Python tools.

(a) Our sample bags in every storage (sqlite3, mcap with no / zstd / lz4 chunks) and distro
    are read by the Python ``mcap`` package (CRCs validated, messages decoded with
    ``mcap_ros2``) and by ``rosbags`` in the distro's type store; every message decodes and
    the payloads equal those of our sqlite3 bag. The RIHS01 hashes we store equal rosbags'
    ``hash_rihs01`` and, where the ROS 2 toolchain is present, rosidl's.
(b) Bags written by the Python ``mcap`` writer (zstd, lz4, uncompressed chunks, no chunks)
    and by ``rosbags`` (mcap with zstd chunks; sqlite3 compressed per file and per message)
    are read by our ``tactile_bag_tool dump``: same order and payload bytes.
(c) Reader faults name file, byte offset and reason (bad magic, CRC, truncation, unknown
    compression).
"""

import json
import os
import shutil
import struct
import subprocess
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.stream_reader import StreamReader
from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter
from mcap_ros2.decoder import DecoderFactory
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

TOOL = os.environ.get('TACTILE_BAG_TOOL', 'tactile_bag_tool')
SEPARATOR = '=' * 80 + '\n'
STORE = {'humble': Stores.ROS2_HUMBLE, 'iron': Stores.ROS2_IRON, 'jazzy': Stores.ROS2_JAZZY,
         'kilted': Stores.ROS2_KILTED}


def run_tool(*args, check=True):
    return subprocess.run([TOOL, *map(str, args)], capture_output=True, text=True, check=check)


def dump(bag):
    return [json.loads(line) for line in run_tool('dump', bag).stdout.splitlines()]


def register(typestore, msgtype, msgdef):
    parts = msgdef.split(SEPARATOR)
    types = dict(get_types_from_msg(parts[0], msgtype))
    for part in parts[1:]:
        header, _, body = part.partition('\n')
        pkg, name = header[len('MSG: '):].strip().split('/')
        types.update(get_types_from_msg(body, f'{pkg}/msg/{name}'))
    typestore.register(types)


def ros2_share():
    """share/ of a ROS 2 (Kilted) install with rosidl's type description JSON files, if any:
    TACTILE_ROS2_SHARE, else the prefixes of a sourced ROS 2 environment."""
    cands = [os.environ.get('TACTILE_ROS2_SHARE', '')]
    for var in ('AMENT_PREFIX_PATH', 'CMAKE_PREFIX_PATH'):
        cands += [str(Path(p) / 'share') for p in os.environ.get(var, '').split(os.pathsep) if p]
    for cand in cands:
        if cand and (Path(cand) / 'std_msgs' / 'msg' / 'String.json').exists():
            return Path(cand)
    return None


@pytest.fixture(scope='module')
def reference(tmp_path_factory):
    bag = tmp_path_factory.mktemp('ref') / 'sqlite'
    run_tool('write-sample', bag)
    return dump(bag)


VARIANTS = [('sqlite3', '', 'jazzy'), ('sqlite3', '', 'humble'), ('mcap', '', 'kilted'),
            ('mcap', 'zstd', 'jazzy'), ('mcap', 'lz4', 'kilted'), ('mcap', 'zstd', 'humble')]


@pytest.mark.parametrize('storage,compression,distro', VARIANTS)
def test_our_bags_read_by_mcap_and_rosbags(tmp_path, reference, storage, compression, distro):
    bag = tmp_path / 'bag'
    args = ['write-sample', bag, '--storage', storage, '--distro', distro]
    if compression:
        args += ['--compression', compression]
    run_tool(*args)
    meta = (bag / 'metadata.yaml').read_text()
    assert f'storage_identifier: {storage}' in meta
    assert f'version: {5 if distro == "humble" else 9}' in meta
    ours = dump(bag)
    assert ours == reference
    if storage == 'mcap':
        path = next(bag.glob('*.mcap'))
        with path.open('rb') as f:
            records = list(StreamReader(f, validate_crcs=True).records)
        assert type(records[-1]).__name__ == 'Footer'
        with path.open('rb') as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            summary = reader.get_summary()
            assert reader.get_header().profile == 'ros2'
            assert summary.statistics.message_count == len(reference)
            assert all(ci.compression == compression for ci in summary.chunk_indexes)
            decoded = [(ch.topic, msg.log_time, bytes(msg.data))
                       for _, ch, msg, _ in reader.iter_decoded_messages(log_time_order=True)]
        assert [(t, ts) for t, ts, _ in decoded] == [(d['topic'], d['timestamp']) for d in reference]
        assert [d.hex() for _, _, d in decoded] == [d['data'] for d in reference]
    store = get_typestore(STORE[distro])
    with Reader(bag) as reader:
        for c in reader.connections:
            register(store, c.msgtype, c.msgdef.data)
        n = 0
        for c, t, raw in reader.messages():
            store.deserialize_cdr(raw, c.msgtype)
            n += 1
        assert n == len(reference)
        share = ros2_share()
        for c in reader.connections:
            if distro == 'humble':
                assert not c.digest  # Humble has no type hashes
                continue
            assert c.digest == store.hash_rihs01(c.msgtype), c.msgtype
            pkg, _, name = c.msgtype.split('/')
            if share is not None and (share / pkg / 'msg' / f'{name}.json').exists():
                want = json.loads((share / pkg / 'msg' / f'{name}.json').read_text())
                assert c.digest == want['type_hashes'][0]['hash_string'], c.msgtype


def sample_messages():
    store = get_typestore(Stores.ROS2_KILTED)
    s = store.types['std_msgs/msg/String']
    v = store.types['geometry_msgs/msg/Vector3']
    out = []
    for i in range(40):
        if i % 3 == 0:
            out.append(('/vec', 'geometry_msgs/msg/Vector3', 1000 + 7 * i,
                        bytes(store.serialize_cdr(v(x=i, y=-i, z=0.5), 'geometry_msgs/msg/Vector3'))))
        else:
            out.append(('/chatter', 'std_msgs/msg/String', 1000 + 7 * i,
                        bytes(store.serialize_cdr(s(data=f'm{i}'), 'std_msgs/msg/String'))))
    return out


@pytest.mark.parametrize('compression,chunked', [(CompressionType.ZSTD, True), (CompressionType.LZ4, True),
                                                 (CompressionType.NONE, True), (CompressionType.NONE, False)])
def test_we_read_python_mcap_bags(tmp_path, compression, chunked):
    bag = tmp_path / 'pm'
    bag.mkdir()
    msgs = sample_messages()
    with (bag / 'pm_0.mcap').open('wb') as f:
        w = McapWriter(f, compression=compression, use_chunking=chunked, chunk_size=200)
        w.start(profile='ros2', library='python-mcap')
        defs = {'std_msgs/msg/String': 'string data\n',
                'geometry_msgs/msg/Vector3': 'float64 x\nfloat64 y\nfloat64 z\n'}
        schemas = {t: w.register_schema(t, 'ros2msg', d.encode()) for t, d in defs.items()}
        chans = {}
        for topic, typ, _, _ in msgs:
            if topic not in chans:
                chans[topic] = w.register_channel(topic, 'cdr', schemas[typ])
        # out of order on purpose: the reader must return log-time order
        for topic, _, t, data in sorted(msgs, key=lambda m: (m[2] % 3, m[2])):
            w.add_message(chans[topic], log_time=t, data=data, publish_time=t)
        w.finish()
    got = dump(bag)  # no metadata.yaml: found by the .mcap extension
    want = sorted(msgs, key=lambda m: m[2])
    assert [(d['topic'], d['timestamp'], d['data']) for d in got] == \
        [(m[0], m[2], m[3].hex()) for m in want]


@pytest.mark.parametrize('storage,mode', [(StoragePlugin.MCAP, CompressionMode.STORAGE),
                                          (StoragePlugin.MCAP, CompressionMode.NONE),
                                          (StoragePlugin.SQLITE3, CompressionMode.FILE),
                                          (StoragePlugin.SQLITE3, CompressionMode.MESSAGE)])
def test_we_read_rosbags_mcap_and_compressed_bags(tmp_path, storage, mode):
    bag = tmp_path / 'rb'
    msgs = sample_messages()
    w = Writer(bag, version=9, storage_plugin=storage)
    w.set_compression(mode, CompressionFormat.ZSTD)
    store = get_typestore(Stores.ROS2_KILTED)
    with w:
        conns = {}
        for topic, typ, t, data in msgs:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=store)
            w.write(conns[topic], t, data)
    info = run_tool('info', bag).stdout
    assert 'messages:     40' in info
    got = dump(bag)
    assert [(d['topic'], d['timestamp'], d['data']) for d in got] == \
        [(m[0], m[2], m[3].hex()) for m in msgs]


def test_reader_faults_name_file_offset_and_reason(tmp_path):
    src = tmp_path / 'good'
    run_tool('write-sample', src, '--storage', 'mcap', '--compression', 'zstd')
    path = next(src.glob('*.mcap'))
    data = path.read_bytes()

    def broken(name, content):
        bag = tmp_path / name
        shutil.copytree(src, bag)
        (bag / path.name).write_bytes(content)
        res = run_tool('dump', bag, check=False)
        assert res.returncode == 1
        return res.stderr

    err = broken('magic', b'XXXX' + data[4:])
    assert path.name in err and 'byte 0' in err and 'bad magic' in err
    # find the chunk record and flip a byte of its compressed records
    pos = 8
    while data[pos] != 0x06:
        pos += 9 + struct.unpack_from('<Q', data, pos + 1)[0]
    body = pos + 9 + 8 + 8 + 8 + 4
    clen = struct.unpack_from('<I', data, body)[0]
    records = body + 4 + clen + 8
    bad = bytearray(data)
    bad[records + 20] ^= 0xFF
    err = broken('crc', bytes(bad))
    assert path.name in err and f'byte {pos}' in err and ('zstd' in err or 'CRC' in err)
    bad = bytearray(data)
    bad[body + 4:body + 8] = b'xxxx'  # compression "zstd" -> "xxxx"
    err = broken('compression', bytes(bad))
    assert f'byte {pos}' in err and "unknown compression 'xxxx'" in err
    # truncated inside its only chunk: nothing is recovered, which is an error (not an
    # empty bag) naming the file, the offset and what was lost
    bag = tmp_path / 'cut'
    shutil.copytree(src, bag)
    (bag / path.name).write_bytes(data[:records + 10])
    res = run_tool('info', bag, check=False)
    assert res.returncode == 1
    assert 'nothing recovered' in res.stderr and 'no mcap footer' in res.stderr and f'byte {pos}' in res.stderr


ROSIDL_SCRIPT = r'''
import glob, json, sys
from pathlib import Path
from rosidl_adapter.msg import convert_msg_to_idl
from rosidl_generator_type_description import generate_type_hash
msg_dir, share, work = Path(sys.argv[1]), sys.argv[2], Path(sys.argv[3])
msgs = sorted(msg_dir.glob('*.msg'))
for m in msgs:
    convert_msg_to_idl(msg_dir.parent, 'tactile_msgs', Path('msg') / m.name, work / 'idl' / 'msg')
args = {'package_name': 'tactile_msgs', 'output_dir': str(work / 'out'),
        'idl_tuples': [f"{work / 'idl'}:msg/{m.stem}.idl" for m in msgs],
        'include_paths': [f'{p}:{share}/{p}' for p in
                          ['std_msgs', 'geometry_msgs', 'builtin_interfaces', 'sensor_msgs', 'nav_msgs']]}
(work / 'args.json').write_text(json.dumps(args))
for f in generate_type_hash(str(work / 'args.json')):
    h = json.loads(Path(f).read_text())['type_hashes'][0]
    print(h['type_name'], h['hash_string'])
'''


def test_hashes_equal_rosidl_where_the_toolchain_is_present(tmp_path):
    """Our RIHS01 of every tactile_msgs and standard type against rosidl's own output.

    rosidl runs in the Python of a ROS 2 Kilted install (its share/ and the interpreter next to
    it, or python3 of the sourced environment); without one the rosidl comparison is skipped (rosbags' independent hash_rihs01 is
    compared in every environment).
    """
    ours = dict(line.split() for line in run_tool('hashes').stdout.splitlines())
    store = get_typestore(Stores.ROS2_KILTED)
    for name, h in ours.items():
        if name.startswith('tactile_msgs/'):
            continue
        assert h == store.hash_rihs01(name), name
    share = ros2_share()
    if share is None:
        pytest.skip('no ROS 2 Kilted install found (TACTILE_ROS2_SHARE): rosidl comparison not run')
    std = {n: h for n, h in ours.items() if not n.startswith('tactile_msgs/')}
    # A package may come from another prefix of the environment than std_msgs (the Kilted
    # toolchain's visualization_msgs wheel is in its extras overlay); visualization_msgs is
    # optional (tactile_msgs/README.md): compared where installed.
    shares = [share] + [Path(p) / 'share' for var in ('AMENT_PREFIX_PATH', 'CMAKE_PREFIX_PATH')
                        for p in os.environ.get(var, '').split(os.pathsep) if p]
    for name, h in std.items():
        pkg, _, typ = name.split('/')
        found = [d / pkg / 'msg' / f'{typ}.json' for d in shares if (d / pkg / 'msg' / f'{typ}.json').exists()]
        if not found and pkg == 'visualization_msgs':
            continue
        assert found, f'{name}: no {pkg}/msg/{typ}.json in {[str(d) for d in shares]}'
        want = json.loads(found[0].read_text())['type_hashes'][0]
        assert h == want['hash_string'], name
    python = share.parent / 'bin' / 'python'
    if not python.exists():
        python = Path(shutil.which('python3'))
    msg_dir = Path(__file__).resolve().parents[2] / 'tactile_msgs' / 'msg'
    res = subprocess.run([str(python), '-c', ROSIDL_SCRIPT, str(msg_dir), str(share), str(tmp_path)],
                         capture_output=True, text=True, check=True)
    rosidl = dict(line.split() for line in res.stdout.splitlines() if line.startswith('tactile_msgs/'))
    assert len(rosidl) == len(list(msg_dir.glob('*.msg')))
    assert {n: ours[n] for n in rosidl} == rosidl
