"""SITL of the whiskered Crazyflie (paper 000) with ROS 2: simulator -> TDORC -> tactile
depth -> wall-following FSM -> hover setpoints back to the simulator, composed in one
container on simulated time.

    ros2 launch launch/sitl_whisker.launch.py scenario:=config/scenarios/whisker_three_baffles_fsm.yaml

The standalone host runs the same graph without ROS:

    tactile sim config/scenarios/whisker_three_baffles_fsm.yaml --out out/baffles

Parameters come from the files in config/ (the ones `tactile sim` reads); the scenario
and seed are launch arguments. The simulator publishes /clock; every node uses it.
"""

import importlib.util
import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch_ros.actions import ComposableNodeContainer
from launch_ros.descriptions import ComposableNode

CONFIG_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config')

_common_spec = importlib.util.spec_from_file_location(
    'launch_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'launch_common.py'))
launch_common = importlib.util.module_from_spec(_common_spec)
_common_spec.loader.exec_module(launch_common)


def config(name):
    return os.path.join(CONFIG_DIR, name + '.yaml')


def generate_launch_description():
    sim_time = {'use_sim_time': True}
    intra = [{'use_intra_process_comms': True}]
    nodes = [
        launch_common.simulator_node('/cmd_hover', intra),
    ]
    for side in ('left', 'right'):
        nodes.append(ComposableNode(
            package='tdorc_filter', plugin='tdorc_filter::TdorcFilterComponent', name='tdorc_filter',
            namespace='whisker/' + side, parameters=launch_common.parameters(
                config('tdorc_filter'), sim_time),
            extra_arguments=intra))
    nodes.append(ComposableNode(
        package='tactile_depth', plugin='tactile_depth::TactileDepthComponent', name='tactile_depth',
        parameters=launch_common.parameters(
            config('tactile_depth'), sim_time), extra_arguments=intra))
    nodes.append(ComposableNode(
        package='tactile_fsm', plugin='tactile_fsm::WhiskerFsmComponent', name='whisker_fsm',
        parameters=launch_common.parameters(
            config('tactile_fsm'), sim_time), extra_arguments=intra))
    return LaunchDescription([
        DeclareLaunchArgument('scenario', default_value=os.path.join(
            CONFIG_DIR, 'scenarios', 'whisker_three_baffles_fsm.yaml'),
            description='scenario file of the simulator'),
        launch_common.frame_prefix_argument(),
        DeclareLaunchArgument('seed', default_value='-1',
                              description="noise seed (-1: the scenario's)"),
        DeclareLaunchArgument('real_time_factor', default_value='1.0',
                              description='simulated seconds per wall-clock second (1.0: real '
                                          'time; the simulator publishes /sim/done at the end)'),
        DeclareLaunchArgument('wait_for_subscribers', default_value='',
                              description="the simulator's topics (comma-separated) that must "
                                          'have a subscriber in another process before the '
                                          'world starts, e.g. a recorder'),
        ComposableNodeContainer(
            name='sitl_whisker_container', namespace='', package='rclcpp_components',
            executable='component_container', composable_node_descriptions=nodes,
            output='screen'),
        launch_common.stop_on_load_failure(),
    ])
