"""launch/sitl_explore.launch.py: tactile_sim -> TDORC x2 -> tactile_depth -> gpis_explorer
-> /cmd_hover, one container on simulated time (paper 000 room exploration). A few seconds
of the default scenario, then stopped."""

from __future__ import annotations

from launch_check import CONFIG_DIR, Graph, Launch, check_graph

NODES = ['/sitl_explore_container', '/tactile_sim', '/whisker/left/tdorc_filter',
         '/whisker/right/tdorc_filter', '/tactile_depth', '/gpis_explorer']
RATE_TOPICS = {
    '/whisker/left/pressure': ('tactile_msgs/msg/WhiskerPressure', 50.0, 'stamp'),
    '/whisker/right/signal': ('tactile_msgs/msg/WhiskerSignal', 50.0, 'stamp'),
    '/whisker/depth': ('tactile_msgs/msg/TactileDepth', 50.0, 'stamp'),
    '/odom': ('nav_msgs/msg/Odometry', 100.0, 'stamp'),
    '/cmd_hover': ('tactile_msgs/msg/HoverSetpoint', 50.0, 'stamp'),  # 50 Hz timer, simulated time
}
# After every GPIS update / on transitions (gpis_explorer README).
EVENT_TOPICS = {'/gpis/map': 'tactile_msgs/msg/GpisMap',
                '/gpis/target': 'tactile_msgs/msg/ExplorationTarget',
                '/fsm_state': 'tactile_msgs/msg/FsmState'}


def test_sitl_explore_graph_topics_and_arguments(tmp_path):
    scenario = CONFIG_DIR / 'scenarios' / 'whisker_room_exit_gpis.yaml'
    with Launch('sitl_explore.launch.py', [f'scenario:={scenario}', 'seed:=3'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        check_graph(g, launch, NODES, RATE_TOPICS, EVENT_TOPICS)
        sim = g.get_parameters('/tactile_sim', ['scenario', 'seed'])
        # The launch file's probing override of config/tdorc_filter.yaml's 0.1.
        tdorc = g.get_parameters('/whisker/left/tdorc_filter', ['hold_release_fraction'])
    assert sim == {'scenario': str(scenario), 'seed': 3}
    assert tdorc == {'hold_release_fraction': 0.25}
