"""SITL of XPLORER (paper 001) with ROS 2: simulator -> xplorer_force_est -> XPLORER
behaviours (admittance, exploration FSM, static wrench, ricocheting) -> position setpoints
back to the simulator, and the contact mapper, composed in one container on simulated
time.

    ros2 launch launch/sitl_xplorer.launch.py scenario:=config/scenarios/xplorer_box_traversal.yaml mission:=explore
    ros2 launch tactile_bringup sitl_xplorer.launch.py namespace:=x1

The standalone host runs the same graph without ROS:

    tactile sim config/scenarios/xplorer_box_traversal.yaml --out out/box

Parameters come from the files in config/ (the ones `tactile sim` reads); the scenario,
seed, mission and the PLY file written at shutdown are launch arguments (the scenario's
node_parameters are applied by `tactile sim` only, so pass the mission here).
"""

import importlib.util
import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.descriptions import ComposableNode

_common_spec = importlib.util.spec_from_file_location(
    'launch_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'launch_common.py'))
launch_common = importlib.util.module_from_spec(_common_spec)
_common_spec.loader.exec_module(launch_common)


config = launch_common.config


def generate_launch_description():
    sim_time = launch_common.SIM_TIME
    intra = launch_common.INTRA
    nodes = [
        launch_common.simulator_node('cmd_position'),
        ComposableNode(
            package='xplorer_force_est', plugin='xplorer_force_est::XplorerForceEstComponent',
            name='xplorer_force_est', parameters=launch_common.parameters(
                config('xplorer_force_est'), sim_time,
                {'world_frame': launch_common.prefixed_frame('odom'),
                 'body_frame': launch_common.prefixed_frame('base_link')}),
            extra_arguments=intra),
        ComposableNode(
            package='tactile_fsm', plugin='tactile_fsm::XplorerFsmComponent', name='xplorer_fsm',
            parameters=launch_common.parameters(
                config('xplorer_fsm'), sim_time,
                {'mission': LaunchConfiguration('mission'),
                 'frame_id': launch_common.prefixed_frame('odom')}),
            extra_arguments=intra),
        ComposableNode(
            package='mapping_pcl', plugin='mapping_pcl::XplorerMapComponent', name='xplorer_mapping',
            parameters=launch_common.parameters(
                config('xplorer_mapping'), sim_time,
                {'ply_file': LaunchConfiguration('ply_file'),
                 'frame_id': launch_common.prefixed_frame('odom')}),
            extra_arguments=intra),
    ]
    return LaunchDescription(launch_common.sitl_arguments('xplorer_box_traversal')
        + launch_common.rviz_arguments('xplorer', sim_time=True) + [
        DeclareLaunchArgument('mission', default_value='explore',
                              description='explore | static_wrench | ricochet | waypoint'),
        DeclareLaunchArgument('ply_file', default_value='xplorer_map.ply',
                              description='contact map written at shutdown (ASCII PLY, frame odom, or <prefix>odom: the odometry frame)'),
    ] + launch_common.sitl_container('sitl_xplorer_container', nodes + launch_common.visualization_nodes()))
