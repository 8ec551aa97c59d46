"""The hardware nodes as lifecycle (managed) nodes, where the ROS 2 installation has
rclcpp_lifecycle (crazyflie_bridge and whisker_driver READMEs, "Lifecycle"; launch/
lifecycle_common.py): radio.launch.py against the simulated Crazyflie over UDP
(crazyflie_sim_server in a session of its own, as test_launch_operator.py) and
bench_rig.launch.py on pseudo terminals.

- activate:=false: the bridge goes unconfigured -> inactive (radio up: connected, nothing
  streamed, nothing sent to the motors); cleanup -> unconfigured (link closed), configure ->
  inactive again (reconnected); `ros2 lifecycle set activate` -> active: it streams,
  and still nothing reaches the motors (the simulator counts zero setpoint packets) until
  takeoff;
- configure against a URI where nothing answers fails with the bridge's error naming the URI
  and the reason; the bridge stays unconfigured and the launch keeps running;
- deactivate while hovering lands first, then stops streaming (the simulator's truth on the
  floor);
- the whisker drivers: inactive with activate:=false (device open, nothing published), then
  active and publishing; a missing device leaves its driver unconfigured with its name.

Where the ROS 2 installation has no rclcpp_lifecycle (the Jazzy toolchain here) these tests
are skipped; test_launch_radio.py, test_launch_operator.py and
test_launch_bench_rig.py cover that path."""

from __future__ import annotations

import math
import re
import subprocess
import time
from pathlib import Path

import pytest

from launch_check import Graph, Launch, unique_port
from test_launch_bench_rig import Deck
from test_launch_operator import GROUND_Z, HEIGHT, Bridge, SimServer, take_off

BRIDGE = '/crazyflie_bridge'


def component_kind(package: str) -> str:
    """'lifecycle' or 'plain': what share/<package>/component_kind says was built."""
    from ament_index_python.packages import get_package_share_directory
    path = Path(get_package_share_directory(package)) / 'component_kind'
    return path.read_text().strip() if path.exists() else 'plain'


def lifecycle_built(package: str) -> bool:
    return component_kind(package) == 'lifecycle'


def rclcpp_lifecycle_installed() -> bool:
    from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
    try:
        get_package_share_directory('rclcpp_lifecycle')
        return True
    except PackageNotFoundError:
        return False


def needs_lifecycle(package: str):
    """Skips where this ROS 2 installation has no rclcpp_lifecycle (the plain path: its own
    launch tests cover it); where it has, `package` must have been built as a lifecycle node."""
    if not rclcpp_lifecycle_installed():
        pytest.skip('no rclcpp_lifecycle in this ROS 2 installation: the hardware nodes are plain '
                    'nodes (test_launch_radio.py, test_launch_operator.py, test_launch_bench_rig.py)')
    assert lifecycle_built(package), \
        f'rclcpp_lifecycle is installed but {package} was built as a {component_kind(package)} node'


def lifecycle(verb: str, node: str, *args: str, timeout: float = 30.0) -> str:
    """`ros2 lifecycle <verb> <node> [args]`: its output (the operator's commands). Retried
    for up to 10 s while the ros2 daemon has not discovered the node yet ("Node not found")."""
    end = time.monotonic() + 10.0
    while True:
        r = subprocess.run(['ros2', 'lifecycle', verb, node, *args], capture_output=True, text=True,
                           timeout=timeout)
        out = (r.stdout + r.stderr).strip()
        if out != 'Node not found' or time.monotonic() > end:
            return out
        time.sleep(0.5)


def wait_state(node: str, state: str, launch: Launch, timeout: float = 30.0) -> str:
    """Polls `ros2 lifecycle get <node>` until it reports `state` (e.g. 'inactive [2]')."""
    end = time.monotonic() + timeout
    got = ''
    while time.monotonic() < end and launch.running():
        got = lifecycle('get', node)
        if got.startswith(state + ' ['):
            return got
        time.sleep(0.5)
    pytest.fail(f'{node}: `ros2 lifecycle get` says {got!r}, waited for {state!r}; '
                f'launch output:\n{launch.output()[-4000:]}')


def sim_setpoints(server_output: str) -> int:
    """Setpoint packets the simulated Crazyflie's commander received (its exit line)."""
    m = re.search(r'setpoints=(\d+)', server_output)
    assert m, f'no exit line in the simulator output: {server_output[-2000:]}'
    return int(m.group(1))


@pytest.fixture
def sim(tmp_path):
    needs_lifecycle('crazyflie_bridge')
    port = unique_port(19850 + 150)
    server = SimServer(port, tmp_path / 'sim_server.log')
    server.port = port
    yield server
    server.stop()


def test_lifecycle_radio_up_check_then_activate_nothing_flies(sim, tmp_path):
    """unconfigured -> (launch: configure) inactive -> (operator: activate) active; nothing
    is streamed while inactive and nothing is sent to the motors after activate."""
    from tactile_msgs.msg import BridgeStatus
    with Launch('radio.launch.py', [f'uri:=udp://127.0.0.1:{sim.port}', 'activate:=false'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        g.wait_for_nodes([BRIDGE, '/whisker_fsm'], launch)
        bridge = Bridge(g)
        wait_state(BRIDGE, 'inactive', launch)
        out = launch.output()
        # loaded unconfigured, configured by the launch, left inactive for the operator
        assert out.index('unconfigured: configure opens udp://') < out.index(
            f'connected to udp://127.0.0.1:{sim.port}: CRTP protocol 10'), out[-3000:]
        assert f'{BRIDGE}: inactive (device open, not streaming)' in out, out[-3000:]
        # inactive: the radio is up, nothing streams, the services refuse
        g.spin(2.0)
        assert not bridge.status and not bridge.odom, \
            f'{len(bridge.status)} status, {len(bridge.odom)} odom messages while inactive'
        bridge.call('takeoff', height=HEIGHT, duration=2.0)
        g.spin_until(lambda: 'takeoff refused: the bridge is not active (inactive: activate it)'
                     in launch.output(), 5, 'takeoff refused while inactive', launch)
        res = bridge.call('start_behaviour')
        assert not res.success and 'not active' in res.message, res.message
        # the operator's cycle: cleanup closes the link (unconfigured), configure reconnects
        assert lifecycle('set', BRIDGE, 'cleanup') == 'Transitioning successful'
        assert lifecycle('get', BRIDGE).startswith('unconfigured [1]')
        assert f'cleanup: link to udp://127.0.0.1:{sim.port} closed' in launch.output()
        assert lifecycle('set', BRIDGE, 'configure') == 'Transitioning successful'
        assert lifecycle('get', BRIDGE).startswith('inactive [2]')
        assert launch.output().count(f'connected to udp://127.0.0.1:{sim.port}: CRTP protocol 10') == 2

        assert lifecycle('set', BRIDGE, 'activate') == 'Transitioning successful'
        assert lifecycle('get', BRIDGE).startswith('active [3]')
        g.spin_until(lambda: len(bridge.status) > 0 and len(bridge.odom) > 0, 10,
                     'status and odom after activate', launch)
        bridge.odom.clear()
        bridge.status.clear()
        g.spin(3.0)
        assert {m.mode for m in bridge.status} == {BridgeStatus.MODE_GROUNDED}
        max_z = max(m.pose.pose.position.z for m in bridge.odom)
        assert max_z < GROUND_Z, f'airborne after activate: max z {max_z:.3f} m'
    # Nothing reached the simulated commander: activating streams, it does not fly.
    server_out = sim.stop()
    assert sim_setpoints(server_out) == 0, server_out[-1000:]
    assert sim.truth_z(server_out) < GROUND_Z


def test_lifecycle_configure_fails_where_nothing_answers(tmp_path):
    needs_lifecycle('crazyflie_bridge')
    port = unique_port(19850 + 170)  # no simulator on it
    uri = f'udp://127.0.0.1:{port}'
    with Launch('radio.launch.py', [f'uri:={uri}'], tmp_path / 'launch.log') as launch, Graph() as g:
        g.wait_for_nodes([BRIDGE], launch)
        g.spin_until(lambda: 'configure failed' in launch.output(), 30, 'configure fails', launch)
        assert launch.running(), 'the launch ended: the operator could not retry'
        out = launch.output()
        # the bridge's error: the URI, the request nobody answered, the resends
        assert re.search(rf'configure failed: cannot open {re.escape(uri)}: no answer to .* from '
                         rf'{re.escape(uri)} after .*; the bridge stays unconfigured', out), out[-3000:]
        assert f'{BRIDGE}: configure failed (its error above): it stays unconfigured' in out, out[-3000:]
        assert lifecycle('get', BRIDGE).startswith('unconfigured [1]')
        # An operator's retry fails the same way and leaves it unconfigured.
        assert 'Transitioning failed' in lifecycle('set', BRIDGE, 'configure')
        assert lifecycle('get', BRIDGE).startswith('unconfigured [1]')


def test_lifecycle_deactivate_while_hovering_lands_first(sim, tmp_path):
    with Launch('radio.launch.py', [f'uri:=udp://127.0.0.1:{sim.port}'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        g.wait_for_nodes([BRIDGE, '/whisker_fsm'], launch)
        wait_state(BRIDGE, 'active', launch)
        bridge = Bridge(g)
        g.spin_until(lambda: len(bridge.status) > 0 and len(bridge.odom) > 0, 30, 'first /status and /odom',
                     launch)
        take_off(bridge, g, launch)
        bridge.odom.clear()
        assert lifecycle('set', BRIDGE, 'deactivate') == 'Transitioning successful'
        assert lifecycle('get', BRIDGE).startswith('inactive [2]')
        out = launch.output()
        assert 'deactivate: landing from mode hovering' in out, out[-3000:]
        assert re.search(r'deactivate: landed and stopped in [\d.]+ s \(mode stopped\)', out), out[-3000:]
        assert 'deactivate: streaming stopped; mode stopped' in out, out[-3000:]
        # the landing was streamed (odometry down to the floor), then nothing
        g.spin(0.5)
        assert bridge.odom and bridge.odom[-1].pose.pose.position.z < GROUND_Z + 0.05, \
            f'last odom z {bridge.odom[-1].pose.pose.position.z if bridge.odom else math.nan:.3f} m'
        n = len(bridge.odom)
        g.spin(1.0)
        assert len(bridge.odom) == n, 'odometry after deactivate'
    # still inactive when the launch stopped: the vehicle was down before (the simulator's truth)
    out = launch.output()
    assert 'shutdown (Ctrl-C / SIGTERM): landing from mode stopped' in out, out[-3000:]
    assert sim.truth_z(sim.stop()) < GROUND_Z


def test_lifecycle_bench_rig_configured_then_activated(tmp_path):
    needs_lifecycle('whisker_driver')
    deck = Deck()
    left, right = '/whisker/left/whisker_driver', '/whisker/right/whisker_driver'
    try:
        with Launch('bench_rig.launch.py', [f'left_device:={deck.left_device}',
                                            f'right_device:={deck.right_device}', 'activate:=false'],
                    tmp_path / 'launch.log') as launch, Graph() as g:
            g.wait_for_nodes([left, right], launch)
            wait_state(left, 'inactive', launch)
            wait_state(right, 'inactive', launch)
            assert f'opened {deck.left_device} (source serial)' in launch.output()
            from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
            from tactile_msgs.msg import WhiskerPressure
            got = {'left': [], 'right': []}
            qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)
            for side in got:
                g.node.create_subscription(WhiskerPressure, f'/whisker/{side}/pressure', got[side].append, qos)
            g.spin(1.5)
            assert not got['left'] and not got['right'], 'published while inactive'
            assert lifecycle('set', left, 'activate') == 'Transitioning successful'
            g.spin_until(lambda: len(got['left']) >= 25, 5, 'left pressure after activate', launch)
            assert not got['right'], 'the right driver (inactive) published'
            assert lifecycle('set', left, 'deactivate') == 'Transitioning successful'
            assert lifecycle('set', left, 'cleanup') == 'Transitioning successful'
            assert lifecycle('get', left).startswith('unconfigured [1]')
            assert f'closed {deck.left_device}' in launch.output()
    finally:
        deck.close()


def test_lifecycle_bench_rig_missing_device_stays_unconfigured(tmp_path):
    needs_lifecycle('whisker_driver')
    missing = tmp_path / 'ttyACM_missing'
    left = '/whisker/left/whisker_driver'
    with Launch('bench_rig.launch.py', [f'left_device:={missing}', f'right_device:={missing}'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        g.wait_for_nodes([left], launch)
        g.spin_until(lambda: launch.output().count('the driver stays unconfigured') >= 2, 30,
                     'both drivers fail to configure', launch)
        out = launch.output()
        assert f'configure failed: cannot open {missing}: ' in out and 'does not exist' in out, out[-3000:]
        assert launch.running()
        assert lifecycle('get', left).startswith('unconfigured [1]')
