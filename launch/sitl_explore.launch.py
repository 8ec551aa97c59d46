"""SITL of the whiskered Crazyflie (paper 000) exploring an unknown room with ROS 2:
simulator -> TDORC -> tactile depth -> gpis_explorer (four probes, wall follow,
retreat, GPIS refit with corner penalties, target, exit) -> hover setpoints back to the
simulator, composed in one container on simulated time.

    ros2 launch launch/sitl_explore.launch.py scenario:=config/scenarios/whisker_room_exit_gpis.yaml
    ros2 launch tactile_bringup sitl_explore.launch.py namespace:=cf1 real_time_factor:=2.0

The standalone host runs the same graph without ROS:

    tactile sim config/scenarios/whisker_room_exit_gpis.yaml --out out/room --trials 5

Parameters come from the files in config/ (the ones `tactile sim` reads); the scenario
and seed are launch arguments (launch_common.sitl_arguments: also real_time_factor,
wait_for_subscribers, namespace). gpis_explorer publishes gpis/map (GpisMap) and
gpis/target (ExplorationTarget) after every GPIS update.
"""

import importlib.util
import os

from launch import LaunchDescription
from launch_ros.descriptions import ComposableNode

_common_spec = importlib.util.spec_from_file_location(
    'launch_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'launch_common.py'))
launch_common = importlib.util.module_from_spec(_common_spec)
_common_spec.loader.exec_module(launch_common)
config = launch_common.config


def generate_launch_description():
    sim_time = launch_common.SIM_TIME
    intra = launch_common.INTRA
    nodes = [launch_common.simulator_node('cmd_hover')]
    for side in ('left', 'right'):
        nodes.append(ComposableNode(
            package='tdorc_filter', plugin='tdorc_filter::TdorcFilterComponent', name='tdorc_filter',
            namespace='whisker/' + side,
            # The exploration profile after the node's file (as the `tactile` graph gpis_explore).
            parameters=launch_common.parameters(
                config('tdorc_filter'), config('profiles/exploration'), sim_time),
            extra_arguments=intra))
    nodes.append(ComposableNode(
        package='tactile_depth', plugin='tactile_depth::TactileDepthComponent', name='tactile_depth',
        parameters=launch_common.parameters(
            config('tactile_depth'), sim_time), extra_arguments=intra))
    nodes.append(ComposableNode(
        package='gpis_explorer', plugin='gpis_explorer::GpisExplorerComponent', name='gpis_explorer',
        parameters=launch_common.parameters(
            config('gpis_explorer'), sim_time), extra_arguments=intra))
    return LaunchDescription(
        launch_common.sitl_arguments('whisker_room_exit_gpis')
        + launch_common.rviz_arguments('explore', sim_time=True)
        + launch_common.sitl_container('sitl_explore_container', nodes + launch_common.visualization_nodes()))
