"""launch/sitl.launch.py: crazyflie_sim_server (the simulated Crazyflie behind CRTP on UDP,
wall-clock physics) and the radio.launch.py pipeline with the bridge on
udp://127.0.0.1:<port>: the bridge's log blocks -> TDORC x2 -> tactile_depth -> whisker_fsm
-> hover setpoints back over CRTP. With autostart:=true (take-off on connect, as before the
operator surface): the operator's sequence is test_launch_operator.py's."""

from __future__ import annotations

import re

from launch_check import Graph, Launch, check_graph, unique_port

NODES = ['/sitl_bridge_container', '/crazyflie_bridge', '/whisker/left/tdorc_filter',
         '/whisker/right/tdorc_filter', '/tactile_depth', '/whisker_fsm']
# The bridge's log blocks: whiskers every whisker_period_ms = 20 (50 Hz), the state
# estimate every state_period_ms = 10 (100 Hz) (config/crazyflie_bridge.yaml); the
# pipeline per sample, the FSM's 50 Hz timer.
RATE_TOPICS = {
    '/whisker/left/pressure': ('tactile_msgs/msg/WhiskerPressure', 50.0, 'stamp'),
    '/whisker/right/pressure': ('tactile_msgs/msg/WhiskerPressure', 50.0, 'stamp'),
    '/odom': ('nav_msgs/msg/Odometry', 100.0, 'stamp'),
    '/whisker/left/signal': ('tactile_msgs/msg/WhiskerSignal', 50.0, 'stamp'),
    '/whisker/right/signal': ('tactile_msgs/msg/WhiskerSignal', 50.0, 'stamp'),
    '/cmd_hover': ('tactile_msgs/msg/HoverSetpoint', 50.0, 'stamp'),  # the FSM steps on each depth (50 Hz)
    # status_rate_hz (config/crazyflie_bridge_health.yaml)
    '/status': ('tactile_msgs/msg/BridgeStatus', 5.0, 'stamp'),
}
EVENT_TOPICS = {'/whisker/depth': 'tactile_msgs/msg/TactileDepth',
                '/fsm_state': 'tactile_msgs/msg/FsmState'}


def test_sitl_bridge_over_udp(tmp_path):
    port = unique_port()
    with Launch('sitl.launch.py', [f'port:={port}', 'seed:=5', 'autostart:=true'], tmp_path / 'launch.log') as launch, \
            Graph() as g:
        check_graph(g, launch, NODES, RATE_TOPICS, EVENT_TOPICS)
        bridge = g.get_parameters('/crazyflie_bridge', ['uri', 'autostart'])
        # Ctrl-C reaches the simulator and the bridge together: the simulator lingers
        # while the motors run, so the bridge's shutdown landing lands it (before
        # crazyflie_sim_server --linger it ended at once and the landing ended in an
        # emergency stop, hearing no vehicle).
        launch.stop()
        out = launch.output()
    # The port argument reached the bridge (and the server: the bridge flies it, above).
    assert bridge == {'uri': f'udp://127.0.0.1:{port}', 'autostart': True}
    assert 'lingering until the motors stop' in out, out[-3000:]
    assert re.search(r'shutdown: landed and stopped in [\d.]+ s', out), out[-3000:]
    done = re.search(r'done t=[\d.]+ truth=(-?[\d.]+),(-?[\d.]+),(-?[\d.]+)', out)
    assert done, out[-3000:]
    assert float(done.group(3)) < 0.05, done.group(0)  # on the floor, not dropped from the air
