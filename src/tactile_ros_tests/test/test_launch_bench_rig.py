"""launch/bench_rig.launch.py: the whisker deck on two serial ports (pseudo terminals here)
-> whisker_driver x2 -> TDORC x2 in one container.

Whisker 1 (left) gets the text protocol ("P1:<Pa>" ... "T3:<degC>", one value per line),
whisker 2 (right) the CSV protocol ("p1,p2,p3"), at 50 frames per second, as the deck
sends them (whisker_driver README "Protocols"); every frame carries values of its own, so
each published message is matched to the frame it came from.
"""

from __future__ import annotations

import math
import os
import threading
import time
import tty

import pytest
import yaml

from launch_check import CONFIG_DIR, Graph, Launch, assert_rate

NODES = ['/bench_rig_container', '/whisker/left/whisker_driver', '/whisker/left/tdorc_filter',
         '/whisker/right/whisker_driver', '/whisker/right/tdorc_filter']
TOPICS = {
    '/whisker/left/pressure': 'tactile_msgs/msg/WhiskerPressure',
    '/whisker/right/pressure': 'tactile_msgs/msg/WhiskerPressure',
    '/whisker/left/signal': 'tactile_msgs/msg/WhiskerSignal',
    '/whisker/right/signal': 'tactile_msgs/msg/WhiskerSignal',
}
RATE_HZ = 50.0  # the deck's frame rate (000 Methods) and the driver's rate_hz


def left_frame(k: int):
    """Frame k of whisker 1: pressures [Pa] and temperatures [degC]."""
    return [100000.0 + 0.25 * k + 7.0 * i for i in range(3)], [21.5 + 0.5 * i for i in range(3)]


def right_frame(k: int):
    return [101000.0 + 0.25 * k + 9.0 * i for i in range(3)]


class Deck:
    """Two pseudo terminals fed at 50 frames per second by a thread."""

    def __init__(self):
        self.left_master, self.left_slave = os.openpty()
        self.right_master, self.right_slave = os.openpty()
        for fd in (self.left_slave, self.right_slave):
            tty.setraw(fd)  # no echo back into the master before the driver sets raw 8N1
        for fd in (self.left_master, self.right_master):
            # A deck whose reader is not reading (a lifecycle driver not active) drops the frame
            # once the tty's buffer is full, as a UART would, instead of blocking the thread.
            os.set_blocking(fd, False)
        self.left_device = os.ttyname(self.left_slave)
        self.right_device = os.ttyname(self.right_slave)
        self.frames = 0
        self.left_paused = threading.Event()    # whisker 1 sends nothing (a stalled deck)
        self.right_garbage = threading.Event()  # whisker 2 sends a malformed line per frame
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        next_t = time.monotonic()
        k = 0
        while not self._stop.is_set():
            p, t = left_frame(k)
            text = ''.join(f'P{i + 1}:{p[i]:.2f}\n' for i in range(3)) + \
                ''.join(f'T{i + 1}:{t[i]:.2f}\r\n' for i in range(3))
            csv = ','.join(f'{v:.2f}' for v in right_frame(k)) + '\n'
            if self.right_garbage.is_set():
                csv = 'x7,?,\n' + csv
            try:
                if not self.left_paused.is_set():
                    self._write(self.left_master, text.encode())
                self._write(self.right_master, csv.encode())
            except OSError:
                return
            k += 1
            self.frames = k
            next_t += 1.0 / RATE_HZ
            time.sleep(max(0.0, next_t - time.monotonic()))

    @staticmethod
    def _write(fd, data: bytes):
        try:
            os.write(fd, data)
        except BlockingIOError:
            pass  # the buffer is full: nobody reads (the frame is dropped)

    def close(self):
        self._stop.set()
        self._thread.join()
        for fd in (self.left_master, self.left_slave, self.right_master, self.right_slave):
            os.close(fd)


@pytest.fixture
def deck():
    d = Deck()
    yield d
    d.close()


def frame_index(pressure0: float, base: float) -> int:
    k = (pressure0 - base) / 0.25
    assert abs(k - round(k)) < 1e-6, f'pressure {pressure0} is no written frame'
    return int(round(k))


def test_bench_rig_streams_the_deck_frames(deck, tmp_path):
    with Launch('bench_rig.launch.py', [f'left_device:={deck.left_device}',
                                        f'right_device:={deck.right_device}'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        g.wait_for_nodes(NODES, launch)
        samples = g.sample(TOPICS, window_s=3.0)
        params = {side: g.get_parameters(f'/whisker/{side}/whisker_driver',
                                         ['device', 'protocol', 'whisker_id', 'frame_id', 'rate_hz'])
                  for side in ('left', 'right')}
        tdorc = g.get_parameters('/whisker/left/tdorc_filter', ['mode', 'window', 'contact_threshold'])

    for topic, s in samples.items():
        assert len(s.messages) >= 0.5 * RATE_HZ * 3.0, f'{topic}: {len(s.messages)} messages in 3 s'
        assert_rate(s, RATE_HZ)

    # Pressure: exactly the values written, in order, with the deck's temperatures (text) or
    # NaN (CSV), the whisker id and frame of config/whisker_driver.yaml's sections.
    # (A best-effort sample lost on the way to this subscriber is allowed; each received
    # one is a written frame, in order, its sequence counting the deck's frames.)
    left = samples['/whisker/left/pressure'].messages
    ks = [frame_index(m.pressure[0], 100000.0) for m in left]
    assert all(b > a for a, b in zip(ks, ks[1:])), 'left frames reordered or repeated'
    assert len(ks) >= 0.95 * (ks[-1] - ks[0] + 1), f'{ks[-1] - ks[0] + 1 - len(ks)} frames lost'
    for m, k in zip(left, ks):
        p, t = left_frame(k)
        assert list(m.pressure) == pytest.approx(p, abs=1e-9)
        assert list(m.temperature) == pytest.approx(t, abs=1e-9)
        assert (m.whisker_id, m.header.frame_id) == (0, 'whisker_left')
        assert m.sequence - left[0].sequence == k - ks[0]
    right = samples['/whisker/right/pressure'].messages
    for m in right:
        k = frame_index(m.pressure[0], 101000.0)
        assert list(m.pressure) == pytest.approx(right_frame(k), abs=1e-9)
        assert all(math.isnan(v) for v in m.temperature)
        assert (m.whisker_id, m.header.frame_id) == (1, 'whisker_right')

    # Signal: TDORC of those samples (raw = S_r), in the configured mode, window n = 100.
    for side, base in (('left', 100000.0), ('right', 101000.0)):
        sig = samples[f'/whisker/{side}/signal'].messages
        for m in sig:
            k = frame_index(m.raw[0], base)
            want = left_frame(k)[0] if side == 'left' else right_frame(k)
            assert list(m.raw) == pytest.approx(want, abs=1e-9)
            assert m.mode == 0  # MODE_TDORC, config/tdorc_filter.yaml mode: "tdorc"
            assert m.whisker_id == (0 if side == 'left' else 1)
            assert m.window_fill <= 100
        assert max(m.window_fill for m in sig) > 0

    # Launch arguments and the per-whisker sections of the YAML reached the nodes.
    assert params['left'] == {'device': deck.left_device, 'protocol': 'text', 'whisker_id': 0,
                              'frame_id': 'whisker_left', 'rate_hz': 50.0}
    assert params['right'] == {'device': deck.right_device, 'protocol': 'csv', 'whisker_id': 1,
                               'frame_id': 'whisker_right', 'rate_hz': 50.0}
    cfg = yaml.safe_load((CONFIG_DIR / 'tdorc_filter.yaml').read_text())['/**/tdorc_filter']['ros__parameters']
    assert tdorc == {'mode': cfg['mode'], 'window': cfg['window'],
                     'contact_threshold': cfg['contact_threshold']}


def tdorc_file(tmp_path, **overrides):
    cfg = yaml.safe_load((CONFIG_DIR / 'tdorc_filter.yaml').read_text())
    cfg['/**/tdorc_filter']['ros__parameters'].update(overrides)
    path = tmp_path / 'tdorc_filter.yaml'
    path.write_text(yaml.safe_dump(cfg))
    return path


def test_bench_rig_tdorc_params_override_changes_the_signal(deck, tmp_path):
    params = tdorc_file(tmp_path, mode='bandpass', window=20)
    with Launch('bench_rig.launch.py', [f'left_device:={deck.left_device}',
                                        f'right_device:={deck.right_device}',
                                        f'tdorc_params:={params}'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        g.wait_for_nodes(NODES, launch)
        samples = g.sample({'/whisker/left/signal': TOPICS['/whisker/left/signal']}, window_s=1.0)
        window = g.get_parameters('/whisker/right/tdorc_filter', ['window'])['window']
    sig = samples['/whisker/left/signal'].messages
    assert sig and all(m.mode == 2 for m in sig)  # MODE_BANDPASS
    assert window == 20


def test_bench_rig_bad_parameter_stops_the_launch_naming_file_key_and_reason(deck, tmp_path):
    params = tdorc_file(tmp_path, window=1)
    with Launch('bench_rig.launch.py', [f'left_device:={deck.left_device}',
                                        f'right_device:={deck.right_device}',
                                        f'tdorc_params:={params}'],
                tmp_path / 'launch.log') as launch:
        code = launch.wait_exit(60)
        out = launch.output()
    assert code is not None, f'the launch kept running with a bad parameter:\n{out[-3000:]}'
    assert code != 0
    assert 'a node failed to start' in out
    assert 'tdorc_filter' in out and 'window' in out and 'got 1' in out, out[-3000:]
    # The file the value came from (ros2 launch reads it and hands the node plain values;
    # the launch file tells the node which file that was).
    assert f'/whisker/left/tdorc_filter from {params}: tdorc_filter.ros__parameters.window: ' \
        in out, out[-3000:]


def test_bench_rig_bad_launch_argument_stops_the_launch_naming_the_argument(deck, tmp_path):
    # config/whisker_driver.yaml sets device too: the launch argument overrides it, and the
    # error says so instead of blaming the file.
    with Launch('bench_rig.launch.py', ['left_device:=123', f'right_device:={deck.right_device}'],
                tmp_path / 'launch.log') as launch:
        code = launch.wait_exit(60)
        out = launch.output()
    assert code not in (None, 0), f'launch exit {code}:\n{out[-3000:]}'
    assert 'a node failed to start' in out
    assert ('/whisker/left/whisker_driver from the launch file (launch argument left_device): '
            'whisker_driver.ros__parameters.device: is a integer (123), expected a string') in out, \
        out[-3000:]


def test_bench_rig_missing_device_stops_the_launch_naming_it(tmp_path):
    from test_launch_lifecycle import lifecycle_built
    if lifecycle_built('whisker_driver'):
        pytest.skip('lifecycle drivers stay unconfigured instead of stopping the launch: '
                    'test_launch_lifecycle.py::test_lifecycle_bench_rig_missing_device_stays_unconfigured')
    missing = tmp_path / 'ttyACM_missing'
    with Launch('bench_rig.launch.py', [f'left_device:={missing}', f'right_device:={missing}'],
                tmp_path / 'launch.log') as launch:
        code = launch.wait_exit(60)
        out = launch.output()
    assert code not in (None, 0), f'launch exit {code}:\n{out[-3000:]}'
    assert str(missing) in out and 'does not exist' in out, out[-3000:]


def test_bench_rig_diagnostics_stall_and_frame_errors(deck, tmp_path):
    """/diagnostics of each driver (whisker_driver DriverHealth, 1 s period): OK while the deck
    streams; whisker 1 silent -> its check ERROR "stalled" (the other stays OK); whisker 2
    sending a malformed line per frame (half its lines) -> ERROR "frame errors"."""
    try:
        from diagnostic_msgs.msg import DiagnosticArray
    except ImportError:
        pytest.skip('diagnostic_msgs not installed: the drivers publish no /diagnostics '
                    '(ROS 2 toolchain without its extras overlay)')
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    left, right = 'whisker_driver: whisker deck /whisker/left', 'whisker_driver: whisker deck /whisker/right'
    with Launch('bench_rig.launch.py', [f'left_device:={deck.left_device}',
                                        f'right_device:={deck.right_device}'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        g.wait_for_nodes(NODES, launch)
        latest = {}

        def on_array(a):
            for s in a.status:
                latest[s.name] = s
        g.node.create_subscription(DiagnosticArray, '/diagnostics', on_array, QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.BEST_EFFORT))

        def level(name):
            s = latest.get(name)
            return None if s is None else (s.level[0] if isinstance(s.level, bytes) else int(s.level))

        def describe():
            return {n: (level(n), s.message) for n, s in latest.items()}
        g.spin_until(lambda: level(left) == 0 and level(right) == 0, 10,
                     f'both drivers OK while streaming: {describe()}', launch)
        assert latest[left].hardware_id == deck.left_device
        assert {kv.key for kv in latest[left].values} >= {'samples_in_period', 'sample_age_s', 'device_errors',
                                                          'dropped_lines', 'dropped_frames'}
        deck.left_paused.set()
        g.spin_until(lambda: level(left) == 2 and 'stalled' in latest[left].message, 6,
                     f'left ERROR stalled: {describe()}', launch)
        assert level(right) == 0, describe()
        deck.left_paused.clear()
        deck.right_garbage.set()
        g.spin_until(lambda: level(right) == 2 and 'frame errors' in latest[right].message, 6,
                     f'right ERROR frame errors: {describe()}', launch)
        deck.right_garbage.clear()
        g.spin_until(lambda: level(left) == 0 and level(right) == 0, 6,
                     f'both OK again: {describe()}', launch)
