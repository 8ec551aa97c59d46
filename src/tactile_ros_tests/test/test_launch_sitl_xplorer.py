"""launch/sitl_xplorer.launch.py: tactile_sim -> xplorer_force_est -> xplorer_fsm ->
/cmd_position, and xplorer_mapping, one container on simulated time (paper 001). A few
seconds of the default scenario, then stopped; the contact map is written at shutdown."""

from __future__ import annotations

from launch_check import CONFIG_DIR, Graph, Launch, check_graph

NODES = ['/sitl_xplorer_container', '/tactile_sim', '/xplorer_force_est', '/xplorer_fsm',
         '/xplorer_mapping']
RATE_TOPICS = {
    '/arm_imu': ('tactile_msgs/msg/ArmImuArray', 50.0, 'stamp'),
    '/thrust_command': ('tactile_msgs/msg/ThrustCommand', 50.0, 'stamp'),
    '/odom': ('nav_msgs/msg/Odometry', 100.0, 'stamp'),
    '/imu': ('sensor_msgs/msg/Imu', 500.0, 'stamp'),
    # One force estimate per arm-IMU sample (xplorer_force_est README).
    '/xplorer/wrench': ('geometry_msgs/msg/WrenchStamped', 50.0, 'stamp'),
    '/xplorer/wrench_body': ('geometry_msgs/msg/WrenchStamped', 50.0, 'stamp'),
    '/cmd_position': ('geometry_msgs/msg/PoseStamped', 50.0, 'stamp'),  # 50 Hz FSM timer, simulated time
}
EVENT_TOPICS = {'/xplorer/fsm_state': 'tactile_msgs/msg/FsmState',
                '/xplorer/map': 'sensor_msgs/msg/PointCloud2'}  # 1 Hz, once there are contacts


def test_sitl_xplorer_graph_topics_and_arguments(tmp_path):
    scenario = CONFIG_DIR / 'scenarios' / 'xplorer_box_traversal.yaml'
    ply = tmp_path / 'map.ply'
    with Launch('sitl_xplorer.launch.py', [f'scenario:={scenario}', 'mission:=static_wrench',
                                           f'ply_file:={ply}'],
                tmp_path / 'launch.log') as launch:
        with Graph() as g:
            check_graph(g, launch, NODES, RATE_TOPICS, EVENT_TOPICS)
            fsm = g.get_parameters('/xplorer_fsm', ['mission'])
            mapping = g.get_parameters('/xplorer_mapping', ['ply_file'])
        code = launch.stop()
        out = launch.output()
    assert fsm == {'mission': 'static_wrench'}
    assert mapping == {'ply_file': str(ply)}
    # ply_file reached the mapper: it wrote the map there when the launch was stopped.
    assert ply.is_file(), f'no {ply} after the launch ended ({code}):\n{out[-3000:]}'
    assert ply.read_text(errors='replace').startswith('ply')
