"""The operator surface of crazyflie_bridge under launch/radio.launch.py, against the simulated
Crazyflie over UDP (crazyflie_sim_server, started by the test in a session of its own so that it
outlives the launch's Ctrl-C): with autostart false (the default) the drone stays on the ground
until `takeoff`; `start_behaviour` hands over to the whisker pipeline, which flies it forward;
`land` lands it; `emergency` stops the motors, latched until `arm`; Ctrl-C of the launch lands
first; `status` and `/diagnostics` flow with their documented fields.

Heights and positions are the bridge's /odom (the simulated state estimate); the simulator's
own truth position is read from crazyflie_sim_server's exit line."""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import time
from pathlib import Path

import pytest

from launch_check import CONFIG_DIR, Graph, Launch, unique_port

SCENARIO = CONFIG_DIR / 'scenarios' / 'whisker_darkness_rigid_fsm.yaml'
GROUND_Z = 0.05   # [m] on the ground (the bridge's land_height)
HEIGHT = 0.4      # [m] take-off height asked for
HEIGHT_TOL = 0.1  # [m]
# tactile_msgs/msg/BridgeStatus, crazyflie_bridge README "Operator surface"
STATUS_FIELDS = {'header', 'mode', 'mode_name', 'armed', 'emergency_latched', 'battery_voltage',
                 'pm_state', 'supervisor_info', 'rssi', 'link_quality', 'packets_lost',
                 'log_blocks_missed', 'setpoint_age_s', 'log_age_s', 'low_battery_events'}
DIAGNOSTIC_CHECKS = {'crazyflie_bridge: battery', 'crazyflie_bridge: link',
                     'crazyflie_bridge: log stream', 'crazyflie_bridge: flight'}


class SimServer:
    """crazyflie_sim_server in its own session; stop() interrupts it and returns its exit line."""

    def __init__(self, port: int, log_path: Path):
        from ament_index_python.packages import get_package_prefix
        exe = Path(get_package_prefix('crazyflie_bridge')) / 'lib' / 'crazyflie_bridge' / 'crazyflie_sim_server'
        self.log_path = log_path
        self._log = open(log_path, 'w')
        self.proc = subprocess.Popen([str(exe), str(SCENARIO), '--port', str(port), '--seed', '5'],
                                     stdout=self._log, stderr=subprocess.STDOUT, start_new_session=True)
        end = time.monotonic() + 30
        while 'listening udp://' not in self.output():
            assert self.proc.poll() is None and time.monotonic() < end, \
                f'crazyflie_sim_server did not start: {self.output()}'
            time.sleep(0.1)

    def output(self) -> str:
        self._log.flush()
        return self.log_path.read_text(errors='replace')

    def stop(self) -> str:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._log.close()
        return self.log_path.read_text(errors='replace')

    def truth_z(self, output: str) -> float:
        m = re.search(r'truth=([-\d.]+),([-\d.]+),([-\d.]+)', output)
        assert m, f'no truth line in the simulator output: {output[-2000:]}'
        return float(m.group(3))


class Bridge:
    """Latest /status, /odom and /diagnostics of the bridge, and its services."""

    def __init__(self, g: Graph):
        from nav_msgs.msg import Odometry
        from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
        from tactile_msgs.msg import BridgeStatus
        self.g = g
        self.status: list = []
        self.odom: list = []
        self.diagnostics: list = []
        qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                         reliability=ReliabilityPolicy.BEST_EFFORT)
        g.node.create_subscription(BridgeStatus, '/status', self.status.append, qos)
        g.node.create_subscription(Odometry, '/odom', self.odom.append, qos)
        if has_diagnostics():
            from diagnostic_msgs.msg import DiagnosticArray
            g.node.create_subscription(DiagnosticArray, '/diagnostics', self.diagnostics.append, qos)

    def mode(self) -> int | None:
        return self.status[-1].mode if self.status else None

    def z(self) -> float:
        return self.odom[-1].pose.pose.position.z if self.odom else math.nan

    def x(self) -> float:
        return self.odom[-1].pose.pose.position.x if self.odom else math.nan

    def call(self, name: str, **fields):
        from builtin_interfaces.msg import Duration
        import tactile_msgs.srv as srv
        types = {'takeoff': srv.Takeoff, 'land': srv.Land, 'go_to': srv.GoTo, 'emergency': srv.Stop,
                 'arm': srv.Arm, 'notify_setpoints_stop': srv.NotifySetpointsStop,
                 'start_behaviour': srv.StartBehaviour}
        request = types[name].Request()
        for key, value in fields.items():
            if key == 'duration':
                value = Duration(sec=int(value), nanosec=int(round((value - int(value)) * 1e9)))
            setattr(request, key, value)
        return self.g.call(types[name], '/' + name, request)


def has_diagnostics() -> bool:
    try:
        import diagnostic_msgs.msg  # noqa: F401
        return True
    except ImportError:
        return False


@pytest.fixture
def flight(tmp_path):
    port = unique_port(19850 + 100)
    server = SimServer(port, tmp_path / 'sim_server.log')
    launch = Launch('radio.launch.py', [f'uri:=udp://127.0.0.1:{port}'], tmp_path / 'launch.log')
    g = Graph()
    try:
        g.wait_for_nodes(['/crazyflie_bridge', '/whisker_fsm'], launch)
        bridge = Bridge(g)
        g.spin_until(lambda: len(bridge.status) > 0 and len(bridge.odom) > 0, 30, 'first /status and /odom', launch)
        bridge.port = port
        yield server, launch, g, bridge
    finally:
        g.close()
        launch.stop()
        server.stop()


def take_off(bridge: Bridge, g: Graph, launch: Launch):
    """The operator's sequence: arm (the supervisor's arming request), then take off."""
    from tactile_msgs.msg import BridgeStatus
    bridge.call('arm', arm=True)
    bridge.call('takeoff', height=HEIGHT, duration=2.0)
    g.spin_until(lambda: bridge.mode() == BridgeStatus.MODE_HOVERING, 15, 'hovering after takeoff', launch)
    g.spin_until(lambda: abs(bridge.z() - HEIGHT) < HEIGHT_TOL, 5, f'height {HEIGHT} m after takeoff', launch)


def test_operator_first_flight(flight):
    from tactile_msgs.msg import BridgeStatus
    server, launch, g, bridge = flight
    # Nothing flies on connect: 3 s on the ground while the FSM already publishes /cmd_hover.
    bridge.odom.clear()
    bridge.status.clear()
    g.spin(3.0)
    assert bridge.odom, 'no /odom on the ground'
    max_z = max(m.pose.pose.position.z for m in bridge.odom)
    assert max_z < GROUND_Z, f'airborne before takeoff: max z {max_z:.3f} m'
    assert {m.mode for m in bridge.status} == {BridgeStatus.MODE_GROUNDED}, \
        f'modes before takeoff: {sorted({m.mode_name for m in bridge.status})}'
    # status: its documented fields, at status_rate_hz (5 Hz, config/crazyflie_bridge_health.yaml)
    assert set(BridgeStatus.get_fields_and_field_types()) == STATUS_FIELDS
    assert 10 <= len(bridge.status) <= 20, f'{len(bridge.status)} status messages in 3 s, documented 5 Hz'
    last = bridge.status[-1]
    assert last.mode_name == 'grounded' and not last.emergency_latched
    assert 0.0 <= last.log_age_s < 1.0, f'log_age_s {last.log_age_s}'  # state log every 10 ms
    assert math.isnan(last.link_quality), 'UDP has no ACKs: link quality unknown (NaN)'

    # A refused command: start_behaviour answers with the reason (the other responses are
    # empty: the bridge logs it).
    res = bridge.call('start_behaviour')
    assert not res.success and 'start_behaviour refused: mode is grounded' in res.message, res.message
    bridge.call('land', height=0.0, duration=2.0)

    take_off(bridge, g, launch)

    # Hand-over: the whisker FSM's setpoints fly it forward (+x at 0.2 m/s, the scenario's course).
    res = bridge.call('start_behaviour')
    assert res.success, res.message
    x0 = bridge.x()
    g.spin_until(lambda: bridge.x() - x0 > 0.3, 8.0,
                 f'the behaviour flies forward 0.3 m (x from {x0:.2f} m; now {bridge.x():.2f} m)', launch)
    # (hover hold: a late FSM setpoint on a loaded machine, resumed within hover_hold_s)
    assert bridge.mode() in (BridgeStatus.MODE_FORWARD, BridgeStatus.MODE_HOVER_HOLD), bridge.status[-1].mode_name
    assert abs(bridge.z() - HEIGHT) < HEIGHT_TOL

    # Land from forwarding: down and stopped.
    bridge.call('land', height=0.0, duration=2.0)
    g.spin_until(lambda: bridge.mode() == BridgeStatus.MODE_STOPPED, 15, 'stopped after land', launch)
    # (touchdown is declared when the commanded height reaches land_height: the vehicle,
    # a little behind its ramp, settles from there)
    g.spin_until(lambda: bridge.z() < GROUND_Z + 0.05, 3.0, f'on the floor after landing (z {bridge.z():.3f} m)',
                 launch)
    out = launch.output()
    assert 'land refused: not airborne (mode grounded)' in out, out[-3000:]
    assert 'takeoff to 0.40 m in 2.00 s; mode taking_off' in out, out[-3000:]


def diagnostic_levels(bridge: Bridge, g: Graph, launch: Launch, want: dict, what: str):
    """Waits for a /diagnostics array with the four checks at the levels of `want`
    ({check: level}); returns its statuses by name."""
    def matching():
        for a in reversed(bridge.diagnostics):
            checks = {s.name: s for s in a.status}
            if set(checks) >= DIAGNOSTIC_CHECKS and all(level(checks[n]) == v for n, v in want.items()):
                return checks
        return None
    g.spin_until(lambda: matching() is not None, 5,
                 f'/diagnostics {what}: {want}; last: ' + (str([(s.name, level(s), s.message)
                 for s in bridge.diagnostics[-1].status]) if bridge.diagnostics else 'none'), launch)
    return matching()


def level(status) -> int:
    return status.level[0] if isinstance(status.level, bytes) else int(status.level)


def test_operator_diagnostics(flight):
    """/diagnostics (diagnostic_updater, 1 s): the four checks, their hardware id, levels and
    key-values on the ground; the flight check turns ERROR on an emergency stop."""
    if not has_diagnostics():
        pytest.skip('diagnostic_msgs not installed: the bridge publishes no /diagnostics '
                    '(ROS 2 toolchain without its extras overlay)')
    server, launch, g, bridge = flight
    OK, ERROR, STALE = 0, 2, 3
    checks = diagnostic_levels(bridge, g, launch, {
        'crazyflie_bridge: log stream': OK,
        'crazyflie_bridge: link': STALE,  # UDP has no ACKs
        'crazyflie_bridge: flight': OK}, 'on the ground')
    for name in DIAGNOSTIC_CHECKS:
        assert checks[name].hardware_id == f'crazyflie udp://127.0.0.1:{bridge.port}'
    values = {n: {kv.key: kv.value for kv in s.values} for n, s in checks.items()}
    assert values['crazyflie_bridge: flight']['mode'] == 'grounded'
    assert set(values['crazyflie_bridge: battery']) == {'battery_voltage', 'pm_state', 'low_battery_events'}
    assert set(values['crazyflie_bridge: link']) == {'link_quality', 'rssi', 'packets_lost'}
    assert set(values['crazyflie_bridge: log stream']) == {'log_age_s', 'log_blocks_missed', 'setpoint_age_s'}
    bridge.call('emergency')
    checks = diagnostic_levels(bridge, g, launch, {'crazyflie_bridge: flight': ERROR}, 'after emergency')
    assert 'emergency stop latched' in checks['crazyflie_bridge: flight'].message


def test_operator_emergency_and_shutdown_landing(flight):
    from tactile_msgs.msg import BridgeStatus
    server, launch, g, bridge = flight
    take_off(bridge, g, launch)

    # Emergency from hover: motors off now (the drone drops), latched.
    bridge.call('emergency')
    g.spin_until(lambda: bridge.mode() == BridgeStatus.MODE_EMERGENCY and bridge.status[-1].emergency_latched,
                 1.0, 'emergency mode latched', launch)
    g.spin_until(lambda: bridge.z() < GROUND_Z + 0.05, 3.0, 'on the floor after the emergency stop', launch)
    # Latched: take-off is refused until arm.
    bridge.call('takeoff', height=HEIGHT, duration=2.0)
    g.spin(1.0)
    assert bridge.mode() == BridgeStatus.MODE_EMERGENCY
    assert bridge.z() < GROUND_Z + 0.05
    assert 'takeoff refused: mode is emergency' in launch.output(), launch.output()[-3000:]
    bridge.call('arm', arm=True)
    g.spin_until(lambda: not bridge.status[-1].emergency_latched, 2.0, 'latch cleared by arm', launch)

    # Fly again, then Ctrl-C the launch (not the simulator): it lands before it exits.
    take_off(bridge, g, launch)
    code = launch.stop()
    out = launch.output()
    assert 'landing from mode hovering' in out, out[-3000:]
    assert re.search(r'shutdown: landed and stopped in [\d.]+ s', out), out[-3000:]
    assert code is not None
    z = server.truth_z(server.stop())
    assert z < GROUND_Z, f'simulated truth z {z:.3f} m after the shutdown landing'


def set_bridge_parameter(g: Graph, name: str, value: float):
    """SetParameters on /crazyflie_bridge (what `ros2 param set` calls); the result."""
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters
    request = SetParameters.Request(parameters=[Parameter(
        name=name, value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value))])
    return g.call(SetParameters, '/crazyflie_bridge/set_parameters', request).results[0]


def test_operator_health_thresholds_are_live_flight_parameters_read_only(flight):
    """The bridge's health thresholds apply while it runs (the next /diagnostics uses them),
    through BridgeHealth's validation; its flight parameters are refused as read-only."""
    server, launch, g, bridge = flight
    voltage = bridge.status[-1].battery_voltage
    assert 3.3 < voltage < 4.8, f'simulated battery {voltage} V'
    r = set_bridge_parameter(g, 'battery_warn_v', 4.9)
    assert r.successful, r.reason
    assert g.get_parameters('/crazyflie_bridge', ['battery_warn_v']) == {'battery_warn_v': 4.9}
    if has_diagnostics():
        WARN = 1
        checks = diagnostic_levels(bridge, g, launch, {'crazyflie_bridge: battery': WARN}, 'battery_warn_v 4.9 V')
        assert 'battery_warn_v 4.90 V' in checks['crazyflie_bridge: battery'].message
    # Refused by validate() (error above warn): its reason, and nothing changes.
    r = set_bridge_parameter(g, 'battery_error_v', 5.0)
    assert not r.successful and 'battery_error_v' in r.reason and 'battery_warn_v' in r.reason, r.reason
    assert g.get_parameters('/crazyflie_bridge', ['battery_error_v']) == {'battery_error_v': 3.0}
    # A flight parameter: read at configure, refused.
    r = set_bridge_parameter(g, 'max_velocity', 0.3)
    assert not r.successful and 'read-only' in r.reason, r.reason
    assert launch.running(), launch.output()[-3000:]
