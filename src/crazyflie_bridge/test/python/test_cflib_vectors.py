"""Byte-exact comparison of our CRTP encoders with packets built by cflib's own
classes (Commander, Param, LogConfig, TocFetcher, PlatformService, Memory),
captured through a fake Crazyflie object. CRTP_VECTORS is the path of the
crtp_vectors helper (set by CMake)."""
import os
import struct
import subprocess
import warnings

import pytest

cflib = pytest.importorskip('cflib')
from cflib.crazyflie.commander import Commander  # noqa: E402
from cflib.crazyflie.log import LogConfig, LogTocElement  # noqa: E402
from cflib.crazyflie.toc import Toc  # noqa: E402
from cflib.crtp.crtpstack import CRTPPacket  # noqa: E402


class _Platform:
    def __init__(self, version=10):
        self.version = version

    def get_protocol_version(self):
        return self.version


class FakeCf:
    """Collects every packet cflib would send."""

    def __init__(self, protocol_version=10):
        self.sent = []
        self.platform = _Platform(protocol_version)
        self.link = object()
        from cflib.utils.callbacks import Caller
        self.disconnected = Caller()
        self.connected = Caller()
        self.connection_requested = Caller()

    def send_packet(self, pk, expected_reply=(), resend=False, timeout=0.2):
        self.sent.append(bytes([pk.header]) + bytes(pk.data))

    def add_port_callback(self, *a):
        pass

    def add_header_callback(self, *a, **k):
        pass


def ours():
    out = subprocess.run([os.environ['CRTP_VECTORS']], check=True, capture_output=True, text=True).stdout
    return {line.split()[0]: bytes(int(b, 16) for b in line.split()[1:]) for line in out.splitlines()}


def test_commander_packets():
    v = ours()
    cf = FakeCf()
    c = Commander(cf)
    c.send_hover_setpoint(0.5, -0.25, 30.0, 0.4)
    c.send_hover_setpoint(-0.1, 0.2, -12.5, 1.25)
    c.send_velocity_world_setpoint(0.1, -0.2, 0.3, 45.0)
    c.send_position_setpoint(1.0, 2.0, 0.5, 90.0)
    c.send_stop_setpoint()
    c.send_notify_setpoint_stop(250)
    names = ['hover', 'hover2', 'velocity_world', 'position', 'stop', 'notify_stop']
    for name, pk in zip(names, cf.sent):
        assert v[name] == pk, name


def test_commander_packets_per_protocol_version():
    """cflib picks the hover / velocity-world packet by protocol version
    (commander.py: get_protocol_version() <= 8 -> legacy type, -yawrate)."""
    v = ours()
    for version, name in ((8, 'hover_legacy'), (9, 'hover_v9')):
        cf = FakeCf(version)
        with warnings.catch_warnings():
            warnings.simplefilter('ignore', DeprecationWarning)
            Commander(cf).send_hover_setpoint(0.5, -0.25, 30.0, 0.4)
        assert v[name] == cf.sent[0], name
    cf = FakeCf(8)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', DeprecationWarning)
        Commander(cf).send_velocity_world_setpoint(0.1, -0.2, 0.3, 45.0)
    assert v['velocity_world_legacy'] == cf.sent[0]


def test_quaternion_compression_matches_cflib():
    """Our quatcompress equals cflib's compress_quaternion (firmware quatcompress.h)."""
    from cflib.utils.encoding import compress_quaternion, decompress_quaternion
    v = ours()
    quats = [(0, 0, 0, 1), (0, 0, 0.7071067811865476, 0.7071067811865476),
             (0, 0, -0.7071067811865476, 0.7071067811865476), (0.5, 0, 0, 0.8660254037844386),
             (0.1, -0.2, 0.3, 0.9273618495495703), (-0.6, 0.5, 0.4, -0.4795831523312719)]
    for i, q in enumerate(quats):
        comp = struct.unpack('<I', v['quat%d' % i])[0]
        assert comp == compress_quaternion(q), (i, hex(comp), hex(compress_quaternion(q)))
        d = decompress_quaternion(comp)
        assert abs(abs(sum(a * b for a, b in zip(d, q))) - 1.0) < 1e-5, i


def test_log_block_create_and_start():
    v = ours()
    cf = FakeCf()
    toc = Toc()
    for ident, (group, name, t) in enumerate([('a', 'v0', 7), ('a', 'v1', 7), ('a', 'v2', 7), ('Whisker', 'Barometer1_1', 7),
                                              ('pm', 'state', 4)]):
        data = bytes([t]) + group.encode() + b'\0' + name.encode() + b'\0'
        toc.add_element(LogTocElement(ident, data))
    el = LogTocElement(258, bytes([2]) + b'motor\0m1\0')
    toc.add_element(el)

    class Log:
        pass
    cf.log = Log()
    cf.log.toc = toc
    cf.log.log_blocks = []
    lc = LogConfig('w', 20)
    lc.add_variable('Whisker.Barometer1_1', 'float')
    lc.add_variable('motor.m1', 'uint16_t')
    lc.add_variable('pm.state', 'int8_t')
    lc.cf = cf
    lc.id = 1
    lc.useV2 = True
    lc.create()
    assert cf.sent[-1] == v['log_create']
    # cflib's start after the create ACK: (CMD_START_LOGGING, id, period_in_ms / 10)
    pk = CRTPPacket()
    pk.set_header(5, 1)
    pk.data = (3, 1, lc.period)
    assert bytes([pk.header]) + bytes(pk.data) == v['log_start_v1']


def test_param_packets():
    v = ours()
    # _ParamUpdater.request_param_update (v2) and Param.set_value packing
    pk = CRTPPacket()
    pk.set_header(2, 1)
    pk.data = struct.pack('<H', 261)
    assert bytes([pk.header]) + bytes(pk.data) == v['param_read']
    for name, ident, fmt, value in [('param_write_u8', 2, '<B', 1), ('param_write_float', 7, '<f', 0.75),
                                    ('param_write_i32', 300, '<i', -123456)]:
        pk = CRTPPacket()
        pk.set_header(2, 2)
        pk.data = struct.pack('<H', ident)
        pk.data += struct.pack(fmt, value)
        assert bytes([pk.header]) + bytes(pk.data) == v[name], name


def test_toc_platform_mem_requests():
    v = ours()
    from cflib.crazyflie.toc import TocFetcher
    cf = FakeCf()
    TocFetcher(cf, LogTocElement, 5, Toc(), None, None).start()
    assert cf.sent[-1] == v['toc_info_log']
    f = TocFetcher(cf, LogTocElement, 2, Toc(), None, None)
    f._useV2 = True
    f._request_toc_element(513)
    assert cf.sent[-1] == v['toc_item_param']
    from cflib.crazyflie.platformservice import PlatformService
    p = PlatformService(cf)
    p.fetch_platform_informations(lambda: None)
    assert cf.sent[-1] == v['link_source']
    reply = CRTPPacket(0xF1, b'Bitcraze Crazyflie')
    p._crt_service_callback(reply)
    assert cf.sent[-1] == v['protocol_version']
    from cflib.crazyflie.mem import Memory
    m = Memory(cf)
    m.refresh(lambda: None)
    assert cf.sent[-1] == v['mem_count']
    # Log reset, as sent by Log.refresh_toc
    from cflib.crazyflie.log import Log
    lg = Log(cf)
    lg.refresh_toc(lambda: None, None)
    assert cf.sent[-1] == v['log_reset']
