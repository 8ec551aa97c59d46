"""SITL of the whiskered Crazyflie (paper 000) with ROS 2: simulator -> TDORC -> tactile
depth -> wall-following FSM -> hover setpoints back to the simulator, composed in one
container on simulated time.

    ros2 launch tactile_bringup sitl_whisker.launch.py   # installed (any directory)
    ros2 launch launch/sitl_whisker.launch.py scenario:=config/scenarios/whisker_three_baffles_fsm.yaml
    ros2 launch launch/sitl_whisker.launch.py namespace:=cf1   # /cf1/cmd_hover, /cf1/clock, ...

The standalone host runs the same graph without ROS:

    tactile sim config/scenarios/whisker_three_baffles_fsm.yaml --out out/baffles

Parameters come from the files in config/ (the ones `tactile sim` reads); the scenario
and seed are launch arguments (launch_common.sitl_arguments). The simulator publishes
/clock (/<namespace>/clock under a namespace); every node uses it.
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
    nodes = [
        launch_common.simulator_node('cmd_hover'),
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
    return LaunchDescription(
        launch_common.sitl_arguments('whisker_three_baffles_fsm')
        + launch_common.rviz_arguments('whisker', sim_time=True)
        + launch_common.sitl_container('sitl_whisker_container', nodes + launch_common.visualization_nodes()))
