"""Peer test: the official Python client (cflib, UDP driver) against our
simulated Crazyflie (crazyflie_sim_server, the SITL whiskered drone behind
the firmware side of CRTP). cflib connects (platform, log TOC, memories,
param TOC, all params), receives the whisker barometers in a 50 Hz log block,
reads and writes parameters, and its hover setpoints fly the simulated drone.
CRAZYFLIE_SIM_SERVER and TACTILE_CONFIG_DIR are set by CMake."""
import os
import signal
import socket
import subprocess
import threading
import time

import pytest

cflib = pytest.importorskip('cflib')
import cflib.crtp  # noqa: E402
from cflib.crazyflie import Crazyflie  # noqa: E402
from cflib.crazyflie.log import LogConfig  # noqa: E402
from cflib.crazyflie.syncCrazyflie import SyncCrazyflie  # noqa: E402

SCENARIO = os.path.join(os.environ.get('TACTILE_CONFIG_DIR', 'config'), 'scenarios', 'whisker_hover.yaml')


def free_udp_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(('127.0.0.1', 0))
    port = s.getsockname()[1]
    s.close()
    return port


def start_server(*extra):
    port = free_udp_port()
    p = subprocess.Popen([os.environ['CRAZYFLIE_SIM_SERVER'], SCENARIO, '--port', str(port), '--duration', '60', *extra],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return port, p


@pytest.fixture
def sim():
    port, p = start_server()
    line = p.stdout.readline()
    assert line.startswith('listening udp://127.0.0.1:%d' % port), line + p.stderr.read()
    yield 'udp://127.0.0.1:%d' % port
    p.terminate()
    out, err = p.communicate(timeout=10)
    assert p.returncode == 0, err


def collect(scf, name, variables, period_ms, seconds):
    lc = LogConfig(name=name, period_in_ms=period_ms)
    for v in variables:
        lc.add_variable(v, 'float')
    samples = []
    lock = threading.Lock()

    def cb(ts, data, conf):
        with lock:
            samples.append((ts, dict(data)))
    lc.data_received_cb.add_callback(cb)
    scf.cf.log.add_config(lc)
    lc.start()
    time.sleep(seconds)
    lc.stop()
    time.sleep(0.1)
    with lock:
        return list(samples)


def test_cflib_connects_logs_params_and_flies(sim, tmp_path):
    cflib.crtp.init_drivers()
    cf = Crazyflie(rw_cache=str(tmp_path))
    with SyncCrazyflie(sim, cf=cf) as scf:
        assert scf.cf.platform.get_protocol_version() == 10
        toc = scf.cf.log.toc.toc
        for i in (1, 2, 3):
            assert 'Barometer1_%d' % i in toc['Whisker']
            assert 'Barometer2_%d' % i in toc['Whisker1']
        for n in ('x', 'y', 'z', 'yaw'):
            assert n in toc['stateEstimate']

        # Whisker barometers at 50 Hz (000: 3 barometers per whisker, 50 Hz).
        names = ['Whisker.Barometer1_%d' % i for i in (1, 2, 3)] + ['Whisker1.Barometer2_%d' % i for i in (1, 2, 3)]
        samples = collect(scf, 'whisker', names, 20, 2.0)
        assert 80 <= len(samples) <= 110, len(samples)
        stamps = [ts for ts, _ in samples]
        periods = {b - a for a, b in zip(stamps, stamps[1:])}
        assert periods == {20}, periods  # firmware timestamps exactly 20 ms apart
        for _, d in samples:
            for n in names:
                assert 9.0e4 < d[n] < 1.1e5, (n, d[n])  # absolute pressure [Pa]
        # The barometers are not a constant: noise/drift makes values change.
        assert len({d[names[0]] for _, d in samples}) > 5

        # Parameters: read a read-only one, write and read back a writable one.
        scf.wait_for_params()
        assert scf.cf.param.get_value('deck.bcWhisker') == '1'
        assert scf.cf.param.get_value('commander.enHighLevel') == '0'
        scf.cf.param.set_value('commander.enHighLevel', 1)
        time.sleep(0.3)
        assert scf.cf.param.get_value('commander.enHighLevel') == '1'

        # Hover setpoints move the simulated drone: take off to 0.4 m, then fly
        # forward at 0.2 m/s for 2 s.
        lc = LogConfig(name='state', period_in_ms=20)
        for v in ('sitl.truthX', 'sitl.truthZ', 'stateEstimate.z'):
            lc.add_variable(v, 'float')
        state = []
        lc.data_received_cb.add_callback(lambda ts, data, conf: state.append(dict(data)))
        scf.cf.log.add_config(lc)
        lc.start()
        time.sleep(0.2)
        x0 = state[-1]['sitl.truthX']
        z0 = state[-1]['sitl.truthZ']
        for _ in range(100):  # 2 s at 50 Hz
            scf.cf.commander.send_hover_setpoint(0.0, 0.0, 0.0, 0.4)
            time.sleep(0.02)
        z_hover = state[-1]['sitl.truthZ']
        x_hover = state[-1]['sitl.truthX']
        for _ in range(100):
            scf.cf.commander.send_hover_setpoint(0.2, 0.0, 0.0, 0.4)
            time.sleep(0.02)
        x_end = state[-1]['sitl.truthX']
        scf.cf.commander.send_stop_setpoint()
        scf.cf.commander.send_notify_setpoint_stop()
        lc.stop()
        assert z0 < 0.05
        assert 0.3 < z_hover < 0.5, z_hover
        assert abs(x_hover - x0) < 0.1
        # 0.2 m/s for 2 s = 0.4 m; the velocity loop needs a few tenths of a second to reach it.
        assert 0.2 < x_end - x_hover < 0.5, (x_hover, x_end)
        assert abs(state[-1]['stateEstimate.z'] - state[-1]['sitl.truthZ']) < 0.1


@pytest.mark.parametrize('protocol', [8, 10])
def test_cflib_yaw_rate_turns_ccw_on_both_firmware_generations(protocol, tmp_path):
    """cflib's own Commander picks the hover packet by protocol version
    (<= 8: legacy type 5 with -yawrate); the simulated firmware of that
    generation turns the drone CCW for a positive yaw rate either way. The
    firmware's compressed attitude (stateEstimateZ.quat) decodes with cflib's
    decompress_quaternion to the logged yaw."""
    import math
    import warnings
    from cflib.utils.encoding import decompress_quaternion
    port = free_udp_port()
    p = subprocess.Popen([os.environ['CRAZYFLIE_SIM_SERVER'], SCENARIO, '--port', str(port), '--duration', '30',
                          '--protocol-version', str(protocol)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().startswith('listening udp://127.0.0.1:%d' % port)
        cflib.crtp.init_drivers()
        cf = Crazyflie(rw_cache=str(tmp_path))
        with SyncCrazyflie('udp://127.0.0.1:%d' % port, cf=cf) as scf:
            assert scf.cf.platform.get_protocol_version() == protocol
            lc = LogConfig(name='att', period_in_ms=20)
            lc.add_variable('stateEstimate.yaw', 'float')
            lc.add_variable('stateEstimateZ.quat', 'uint32_t')
            lc.add_variable('sitl.truthZ', 'float')
            state = []
            lc.data_received_cb.add_callback(lambda ts, data, conf: state.append(dict(data)))
            scf.cf.log.add_config(lc)
            lc.start()
            with warnings.catch_warnings():
                warnings.simplefilter('ignore', DeprecationWarning)  # cflib warns on the legacy packet
                for _ in range(75):  # take off to 0.4 m, 1.5 s
                    scf.cf.commander.send_hover_setpoint(0.0, 0.0, 0.0, 0.4)
                    time.sleep(0.02)
                yaw0 = state[-1]['stateEstimate.yaw']
                for _ in range(75):  # +40 deg/s (CCW) for 1.5 s
                    scf.cf.commander.send_hover_setpoint(0.0, 0.0, 40.0, 0.4)
                    time.sleep(0.02)
            yaw1 = state[-1]['stateEstimate.yaw']
            last = state[-1]
            scf.cf.commander.send_stop_setpoint()
            lc.stop()
        assert last['sitl.truthZ'] > 0.3
        turned = (yaw1 - yaw0 + 180.0) % 360.0 - 180.0
        assert turned > 25.0, (protocol, yaw0, yaw1)  # ~60 deg commanded, CCW
        x, y, z, w = decompress_quaternion(int(last['stateEstimateZ.quat']))
        yaw_q = math.degrees(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
        assert abs((yaw_q - last['stateEstimate.yaw'] + 180.0) % 360.0 - 180.0) < 0.5
    finally:
        p.terminate()
        p.communicate(timeout=10)


@pytest.fixture
def sim_requires_arming():
    port, p = start_server('--require-arming')
    line = p.stdout.readline()
    assert line.startswith('listening udp://127.0.0.1:%d' % port), line + p.stderr.read()
    yield 'udp://127.0.0.1:%d' % port
    p.terminate()
    out, err = p.communicate(timeout=10)
    assert p.returncode == 0, err


def test_cflib_arming_request_and_supervisor_info(sim_requires_arming, tmp_path):
    """A simulated Crazyflie that requires arming (crazyflie_sim_server
    --require-arming): cflib's hover setpoints do not start the motors until
    cflib's own arming request (Supervisor.send_arming_request: the legacy
    platform packet at protocol 10), and cflib decodes our supervisor.info as
    the firmware's bit field."""
    cflib.crtp.init_drivers()
    cf = Crazyflie(rw_cache=str(tmp_path))
    with SyncCrazyflie(sim_requires_arming, cf=cf) as scf:
        lc = LogConfig(name='status', period_in_ms=20)
        lc.add_variable('supervisor.info', 'uint16_t')
        lc.add_variable('pm.vbat', 'float')
        lc.add_variable('sitl.truthZ', 'float')
        state = []
        lc.data_received_cb.add_callback(lambda ts, data, conf: state.append(dict(data)))
        scf.cf.log.add_config(lc)
        lc.start()
        time.sleep(0.3)
        decode = scf.cf.supervisor.decode_bitfield
        names = decode(state[-1]['supervisor.info'])
        assert 'Can be armed' in names and 'Is armed' not in names and 'Is auto armed' not in names, names
        assert 3.9 < state[-1]['pm.vbat'] < 4.2
        for _ in range(50):  # 1 s of hover setpoints while not armed: motors stay off
            scf.cf.commander.send_hover_setpoint(0.0, 0.0, 0.0, 0.4)
            time.sleep(0.02)
        assert state[-1]['sitl.truthZ'] < 0.01, state[-1]
        with pytest.warns(UserWarning):  # cflib: protocol < 12 uses the legacy platform request
            scf.cf.supervisor.send_arming_request(True)
        time.sleep(0.2)
        names = decode(state[-1]['supervisor.info'])
        assert 'Is armed' in names and 'Can fly' in names, names
        for _ in range(100):  # 2 s of hover setpoints, armed: it flies
            scf.cf.commander.send_hover_setpoint(0.0, 0.0, 0.0, 0.4)
            time.sleep(0.02)
        assert state[-1]['sitl.truthZ'] > 0.3, state[-1]
        assert 'Is flying' in decode(state[-1]['supervisor.info'])
        scf.cf.commander.send_stop_setpoint()
        lc.stop()


def test_cflib_scan_finds_simulated_crazyflie():
    """cflib's UDP scan (null packet to 19850..19859) finds our server."""
    p = None
    for port in range(19859, 19849, -1):
        p = subprocess.Popen([os.environ['CRAZYFLIE_SIM_SERVER'], SCENARIO, '--port', str(port), '--duration', '10'],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = p.stdout.readline()
        if line.startswith('listening'):
            break
        p.communicate(timeout=10)
        p = None
    if p is None:
        pytest.skip('UDP ports 19850-19859 all busy')
    try:
        cflib.crtp.init_drivers()
        found = [uri for uri, _ in cflib.crtp.scan_interfaces()]
        assert 'udp://127.0.0.1:%d' % port in found, found
    finally:
        p.terminate()
        p.communicate(timeout=10)


@pytest.mark.parametrize('args, expected', [
    (['--port', '70000'], '--port: must be in [0, 65535], got 70000'),  # listened on 4464 before
    (['--port', '5x'], "--port: expected a whole number"),              # std::stoi read 5
    (['--loss', 'nan'], '--loss: expected a finite number'),
    (['--protocol-version', '-1'], '--protocol-version: expected a whole number'),
    (['--linger', 'nan'], '--linger: expected a finite number in [0.000000, 600.000000]'),
    (['--linger', '601'], '--linger: expected a finite number'),
])
def test_sim_server_refuses_bad_option_values(args, expected):
    p = subprocess.run([os.environ['CRAZYFLIE_SIM_SERVER'], SCENARIO, *args], capture_output=True, text=True,
                       timeout=30)
    assert p.returncode == 1
    assert expected in p.stderr, p.stderr


@pytest.mark.parametrize('linger', [False, True])
def test_sim_server_lingers_after_a_signal_until_the_motors_stop(linger, tmp_path):
    """A launch file's Ctrl-C reaches the simulator and the bridge together. With --linger
    the simulator keeps flying after SIGINT while the motors run, so the bridge's shutdown
    landing has a vehicle to land, and ends 0.5 s after they stop; without, it ends at
    once (the previous behaviour: the landing heard no vehicle)."""
    port, p = start_server(*(['--linger', '10'] if linger else []))
    try:
        assert p.stdout.readline().startswith('listening udp://127.0.0.1:%d' % port)
        cflib.crtp.init_drivers()
        cf = Crazyflie(rw_cache=str(tmp_path))
        with SyncCrazyflie('udp://127.0.0.1:%d' % port, cf=cf) as scf:
            for _ in range(50):  # motors on: take off towards 0.4 m
                scf.cf.commander.send_hover_setpoint(0.0, 0.0, 0.0, 0.4)
                time.sleep(0.02)
            p.send_signal(signal.SIGINT)
            for _ in range(50):  # 1 s more of flight after the signal
                scf.cf.commander.send_hover_setpoint(0.0, 0.0, 0.0, 0.4)
                time.sleep(0.02)
            alive_after_1s = p.poll() is None
            t_stop = time.monotonic()
            scf.cf.commander.send_stop_setpoint()
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                pass
            ended_after = time.monotonic() - t_stop
        out, err = p.communicate(timeout=10)
        assert p.returncode == 0, err
        assert alive_after_1s == linger, out
        if linger:
            assert 'lingering until the motors stop' in out, out
            assert 0.4 < ended_after < 3.0, ended_after  # 0.5 s after the stop setpoint
    finally:
        if p.poll() is None:
            p.kill()
            p.communicate(timeout=10)


def test_sim_server_second_signal_ends_the_linger_at_once(tmp_path):
    port, p = start_server('--linger', '20')
    try:
        assert p.stdout.readline().startswith('listening udp://127.0.0.1:%d' % port)
        cflib.crtp.init_drivers()
        cf = Crazyflie(rw_cache=str(tmp_path))
        with SyncCrazyflie('udp://127.0.0.1:%d' % port, cf=cf) as scf:
            for _ in range(50):
                scf.cf.commander.send_hover_setpoint(0.0, 0.0, 0.0, 0.4)
                time.sleep(0.02)
            p.send_signal(signal.SIGINT)
            time.sleep(0.1)
            p.send_signal(signal.SIGINT)  # the same Ctrl-C, forwarded by ros2 launch: still lingering
            time.sleep(1.2)
            assert p.poll() is None
            p.send_signal(signal.SIGTERM)  # a second signal 1 s after the first
            p.wait(timeout=2)
        assert p.returncode == 0
    finally:
        if p.poll() is None:
            p.kill()
            p.communicate(timeout=10)
