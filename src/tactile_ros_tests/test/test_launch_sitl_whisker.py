"""launch/sitl_whisker.launch.py: tactile_sim -> TDORC x2 -> tactile_depth -> whisker_fsm
-> /cmd_hover back to the simulator, one container on simulated time (paper 000 SITL).
A few simulated seconds of the default scenario (the take-off), then stopped."""

from __future__ import annotations

import time

import yaml

from launch_check import CONFIG_DIR, Graph, Launch, check_graph

NODES = ['/sitl_whisker_container', '/tactile_sim', '/whisker/left/tdorc_filter',
         '/whisker/right/tdorc_filter', '/tactile_depth', '/whisker_fsm']
# Simulator topics at their rates in simulated time (tactile_sim/docs/sitl_design.md), the
# pipeline's at the rate of the samples they come from (one signal per pressure sample, one
# depth per left/right pair), the FSM on its 50 Hz timer (wall clock).
RATE_TOPICS = {
    '/whisker/left/pressure': ('tactile_msgs/msg/WhiskerPressure', 50.0, 'stamp'),
    '/whisker/right/pressure': ('tactile_msgs/msg/WhiskerPressure', 50.0, 'stamp'),
    '/ground_truth/whisker/left/contact': ('tactile_msgs/msg/WhiskerGroundTruth', 50.0, 'stamp'),
    '/odom': ('nav_msgs/msg/Odometry', 100.0, 'stamp'),
    '/ground_truth/odom': ('nav_msgs/msg/Odometry', 100.0, 'stamp'),
    '/imu': ('sensor_msgs/msg/Imu', 100.0, 'stamp'),
    '/whisker/left/signal': ('tactile_msgs/msg/WhiskerSignal', 50.0, 'stamp'),
    '/whisker/right/signal': ('tactile_msgs/msg/WhiskerSignal', 50.0, 'stamp'),
    '/whisker/depth': ('tactile_msgs/msg/TactileDepth', 50.0, 'stamp'),
    '/cmd_hover': ('tactile_msgs/msg/HoverSetpoint', 50.0, 'stamp'),  # on each depth (50 Hz), simulated time
}
EVENT_TOPICS = {'/clock': 'rosgraph_msgs/msg/Clock', '/fsm_state': 'tactile_msgs/msg/FsmState'}


def test_sitl_whisker_graph_topics_and_arguments(tmp_path):
    scenario = CONFIG_DIR / 'scenarios' / 'whisker_three_baffles_fsm.yaml'
    with Launch('sitl_whisker.launch.py', [f'scenario:={scenario}', 'seed:=7'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        check_graph(g, launch, NODES, RATE_TOPICS, EVENT_TOPICS)
        sim = g.get_parameters('/tactile_sim', ['scenario', 'seed', 'wait_for_publisher'])
        tdorc = g.get_parameters('/whisker/right/tdorc_filter', ['window', 'use_sim_time'])
    assert sim == {'scenario': str(scenario), 'seed': 7, 'wait_for_publisher': 'cmd_hover'}
    cfg = yaml.safe_load((CONFIG_DIR / 'tdorc_filter.yaml').read_text())['/**/tdorc_filter']['ros__parameters']
    assert tdorc == {'window': cfg['window'], 'use_sim_time': True}


def test_sitl_whisker_wait_for_subscribers_of_a_topic_the_simulator_lacks_stops_it(tmp_path):
    """wait_for_subscribers names topics of the simulator's (the end-to-end tests pass the
    recorder's); a topic it does not publish stops the simulator at t = 0 with the
    parameter, the topic, the scenario and the topics it does publish."""
    with Launch('sitl_whisker.launch.py', ['wait_for_subscribers:=/no_such_topic'],
                tmp_path / 'launch.log') as launch:
        deadline = time.monotonic() + 60.0
        while time.monotonic() < deadline and 'process has died' not in launch.output():
            time.sleep(0.5)
        out = launch.output()
    assert 'process has died' in out, out[-3000:]
    assert ('wait_for_subscribers: the simulator publishes no /no_such_topic at t = 0 in '
            'scenario whisker_three_baffles_fsm') in out, out[-3000:]
    assert '/ground_truth/whisker/left/contact' in out
