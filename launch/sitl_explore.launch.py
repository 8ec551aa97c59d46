"""SITL of the whiskered Crazyflie (paper 000) exploring an unknown room with ROS 2:
simulator -> TDORC -> tactile depth -> gpis_explorer (four probes, wall follow,
retreat, GPIS refit with corner penalties, target, exit) -> hover setpoints back to the
simulator, composed in one container on simulated time.

    ros2 launch launch/sitl_explore.launch.py scenario:=config/scenarios/whisker_room_exit_gpis.yaml

The standalone host runs the same graph without ROS:

    tactile sim config/scenarios/whisker_room_exit_gpis.yaml --out out/room --trials 5

Parameters come from the files in config/ (the ones `tactile sim` reads); the scenario
and seed are launch arguments. gpis_explorer publishes /gpis/map (GpisMap) and
/gpis/target (ExplorationTarget) after every GPIS update.
"""

import importlib.util
import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import ComposableNodeContainer
from launch_ros.descriptions import ComposableNode
from launch_ros.parameter_descriptions import ParameterValue

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
        ComposableNode(
            package='tactile_sim', plugin='tactile_sim::TactileSimComponent', name='tactile_sim',
            parameters=launch_common.parameters(
                {'scenario': LaunchConfiguration('scenario'),
                 'seed': LaunchConfiguration('seed'),
                 'frame_prefix': ParameterValue(LaunchConfiguration('frame_prefix'), value_type=str)}),
            extra_arguments=intra),
    ]
    for side in ('left', 'right'):
        nodes.append(ComposableNode(
            package='tdorc_filter', plugin='tdorc_filter::TdorcFilterComponent', name='tdorc_filter',
            namespace='whisker/' + side,
            # Probing: a held contact also ends at 1/4 of its peak S_c (tdorc_filter README).
            parameters=launch_common.parameters(
                config('tdorc_filter'), {'hold_release_fraction': 0.25}, sim_time),
            extra_arguments=intra))
    nodes.append(ComposableNode(
        package='tactile_depth', plugin='tactile_depth::TactileDepthComponent', name='tactile_depth',
        parameters=launch_common.parameters(
            config('tactile_depth'), sim_time), extra_arguments=intra))
    nodes.append(ComposableNode(
        package='gpis_explorer', plugin='gpis_explorer::GpisExplorerComponent', name='gpis_explorer',
        parameters=launch_common.parameters(
            config('gpis_explorer'), sim_time), extra_arguments=intra))
    return LaunchDescription([
        DeclareLaunchArgument('scenario', default_value=os.path.join(
            CONFIG_DIR, 'scenarios', 'whisker_room_exit_gpis.yaml'),
            description='scenario file of the simulator'),
        launch_common.frame_prefix_argument(),
        DeclareLaunchArgument('seed', default_value='-1',
                              description="noise seed (-1: the scenario's)"),
        ComposableNodeContainer(
            name='sitl_explore_container', namespace='', package='rclcpp_components',
            executable='component_container', composable_node_descriptions=nodes,
            output='screen'),
        launch_common.stop_on_load_failure(),
    ])
