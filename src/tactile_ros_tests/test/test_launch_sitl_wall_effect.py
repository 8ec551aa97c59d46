"""launch/sitl_wall_effect.launch.py: tactile_sim -> wall_effect_ekf -> wall_effect_nav (or
wall_trajectory) -> indi_controller -> rotor thrusts, one container on simulated time
(paper 004). A few seconds of each behaviour, then stopped."""

from __future__ import annotations

from launch_check import CONFIG_DIR, Graph, Launch, check_graph

COMMON = ['/sitl_wall_effect_container', '/tactile_sim', '/wall_effect_ekf', '/indi_controller']
RATE_TOPICS = {
    '/imu': ('sensor_msgs/msg/Imu', 500.0, 'stamp'),
    '/flow': ('tactile_msgs/msg/OpticalFlow', 100.0, 'stamp'),
    '/tof': ('sensor_msgs/msg/Range', 50.0, 'stamp'),
    '/odom': ('nav_msgs/msg/Odometry', 100.0, 'stamp'),
    '/ground_truth/wall': ('tactile_msgs/msg/WallEstimate', 100.0, 'stamp'),
    # EKF and wall following on their 100 Hz timers (004: 100 Hz ground station).
    '/wall_effect/estimate': ('tactile_msgs/msg/WallEstimate', 100.0, 'stamp'),
    '/wall_effect/setpoint': ('nav_msgs/msg/Odometry', 100.0, 'stamp'),
}
EVENT_TOPICS = {'/cmd_rotor_thrust': 'tactile_msgs/msg/ThrustCommand',
                '/thrust_command': 'tactile_msgs/msg/ThrustCommand',
                # The INDI fail-safe's state (WAITING_FOR_INPUT / NOMINAL / ...), 1 Hz and on change.
                '/indi/fsm_state': 'tactile_msgs/msg/FsmState'}


def test_sitl_wall_effect_navigation(tmp_path):
    scenario = CONFIG_DIR / 'scenarios' / 'ducted_track_0.yaml'
    with Launch('sitl_wall_effect.launch.py', [f'scenario:={scenario}'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        check_graph(g, launch, COMMON + ['/wall_effect_nav'], RATE_TOPICS, EVENT_TOPICS)
        ekf = g.get_parameters('/wall_effect_ekf', ['rate_hz'])
        assert '/wall_trajectory' not in g.node_names()
    assert ekf == {'rate_hz': 100.0}


def test_sitl_wall_effect_behaviour_argument_selects_the_trajectory(tmp_path):
    scenario = CONFIG_DIR / 'scenarios' / 'ducted_estimation.yaml'
    topics = {'/wall_effect/setpoint': RATE_TOPICS['/wall_effect/setpoint']}
    with Launch('sitl_wall_effect.launch.py', [f'scenario:={scenario}', 'behaviour:=trajectory'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        check_graph(g, launch, COMMON + ['/wall_trajectory'], topics, window_s=2.0)
        assert '/wall_effect_nav' not in g.node_names()
