"""Whiskered Crazyflie over the radio (paper 000 pipeline on the ground station):
crazyflie_bridge (CRTP over Crazyradio / USB / UDP) -> TDORC x2 -> tactile depth ->
whisker wall-following FSM -> hover setpoints back through the bridge, composed in one
container on wall-clock time.

    ros2 launch launch/radio.launch.py uri:=radio://0/80/2M/E7E7E7E7E7?safelink=1

The bridge reads the whisker deck's log variables (Whisker.Barometer1_1..3,
Whisker1.Barometer2_1..3) at 50 Hz and stateEstimate.x/y/z/yaw/vx/vy at 100 Hz in two
log blocks (config/crazyflie_bridge.yaml) and
publishes /whisker/{left,right}/pressure and /odom; /cmd_hover goes out as generic
commander hover setpoints, clamped, with the stale-input chain hover -> land -> stop
(crazyflie_bridge/README.md). The standalone host runs the same graph without ROS:

    tactile fly --uri radio://0/80/2M/E7E7E7E7E7 --out out/flight

Parameters come from config/ (crazyflie_bridge.yaml, tdorc_filter.yaml,
tactile_depth.yaml, tactile_fsm.yaml); `uri` overrides the bridge's. The FSM's first
approach steps and scans by default (tactile_fsm README "Round 12"); against a single wall
ahead set first_whisk_amplitude: 0 there for the paper's straight approach. The Crazyradio needs
the Bitcraze udev rules (or run as root / pass the device into the container). Without a
Crazyradio the bridge cannot start and the launch ends with its message ("no Crazyradio found").
"""

import importlib.util
import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import ComposableNodeContainer
from launch_ros.descriptions import ComposableNode

CONFIG_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'config')

_common_spec = importlib.util.spec_from_file_location(
    'launch_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'launch_common.py'))
launch_common = importlib.util.module_from_spec(_common_spec)
_common_spec.loader.exec_module(launch_common)


def config(name):
    return os.path.join(CONFIG_DIR, name + '.yaml')


def pipeline_nodes(bridge_overrides):
    """The bridge and the whisker pipeline (also used by sitl.launch.py)."""
    intra = [{'use_intra_process_comms': True}]
    nodes = [ComposableNode(
        package='crazyflie_bridge', plugin='crazyflie_bridge::CrazyflieBridgeComponent',
        name='crazyflie_bridge', parameters=launch_common.parameters(
            config('crazyflie_bridge'), bridge_overrides),
        extra_arguments=intra)]
    for side in ('left', 'right'):
        nodes.append(ComposableNode(
            package='tdorc_filter', plugin='tdorc_filter::TdorcFilterComponent', name='tdorc_filter',
            namespace='whisker/' + side, parameters=launch_common.parameters(
                config('tdorc_filter')), extra_arguments=intra))
    nodes.append(ComposableNode(
        package='tactile_depth', plugin='tactile_depth::TactileDepthComponent', name='tactile_depth',
        parameters=launch_common.parameters(config('tactile_depth')), extra_arguments=intra))
    nodes.append(ComposableNode(
        package='tactile_fsm', plugin='tactile_fsm::WhiskerFsmComponent', name='whisker_fsm',
        parameters=launch_common.parameters(config('tactile_fsm')), extra_arguments=intra))
    return nodes


def generate_launch_description():
    container = ComposableNodeContainer(
        name='radio_container', namespace='', package='rclcpp_components',
        executable='component_container',
        composable_node_descriptions=pipeline_nodes({'uri': LaunchConfiguration('uri')}),
        output='screen')
    return LaunchDescription([
        DeclareLaunchArgument('uri', default_value='radio://0/80/2M/E7E7E7E7E7?safelink=1',
                              description='Crazyflie link URI (radio://, usb://, udp://)'),
        container,
        launch_common.stop_on_load_failure(container),
    ])
