"""Bench rig: the whisker deck on two serial ports -> TDORC, composed in one container.

Run by path on a ROS 2 machine after building the workspace with colcon:

    ros2 launch launch/bench_rig.launch.py left_device:=/dev/ttyUSB0 right_device:=/dev/ttyUSB1

Whisker 1 (left) speaks the text protocol (P1:/P2:/P3:/T1:/T2:/T3: lines), whisker 2
(right) the CSV protocol, both at 115200 baud. Parameters come from the same YAML files
the standalone host reads (config/whisker_driver.yaml, config/tdorc_filter.yaml); the
launch arguments override the serial device per whisker and the TDORC parameter file
(tdorc_params:=my_tuning.yaml, to try another tuning on the bench). A node that cannot
start (bad parameter) stops the launch with its message. Where the ROS 2 installation has
rclcpp_lifecycle the drivers are lifecycle nodes: the launch configures them (opens the
serial devices) and activates each that reached `inactive` (activate:=false: configured
only, for `ros2 lifecycle set /whisker/left/whisker_driver activate`); a device that cannot
be opened is logged with its name and reason and leaves that driver `unconfigured`, the launch
running (lifecycle_common.py). Without rclcpp_lifecycle a missing device stops the launch.

Topics (relative: under namespace:=NS they are /NS/whisker/...):
        whisker/{left,right}/pressure (tactile_msgs/WhiskerPressure),
        whisker/{left,right}/signal   (tactile_msgs/WhiskerSignal),
        /diagnostics (diagnostic_msgs/DiagnosticArray, where diagnostic_updater is installed):
        "whisker_driver: whisker deck /whisker/<side>" per driver (stall, frame errors,
        device gone; thresholds in config/whisker_driver_health.yaml).
"""

import importlib.util
import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import ComposableNodeContainer
from launch_ros.descriptions import ComposableNode

_common_spec = importlib.util.spec_from_file_location(
    'launch_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'launch_common.py'))
launch_common = importlib.util.module_from_spec(_common_spec)
_common_spec.loader.exec_module(launch_common)
_lifecycle_spec = importlib.util.spec_from_file_location(
    'lifecycle_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'lifecycle_common.py'))
lifecycle_common = importlib.util.module_from_spec(_lifecycle_spec)
_lifecycle_spec.loader.exec_module(lifecycle_common)
DRIVERS = ['whisker/left/whisker_driver', 'whisker/right/whisker_driver']  # in the namespace


def whisker_nodes(side, device, tdorc_params):
    namespace = 'whisker/' + side
    return [
        ComposableNode(
            package='whisker_driver',
            plugin='whisker_driver::WhiskerDriverComponent',
            name='whisker_driver',
            namespace=namespace,
            parameters=launch_common.parameters(
                launch_common.config('whisker_driver'),
                # /diagnostics thresholds (stall, frame errors, device gone)
                launch_common.config('whisker_driver_health'),
                # Protocol, whisker_id and frame_id come from the file's
                # /**/whisker/<side>/whisker_driver section.
                {'source': 'serial', 'device': device},
            ),
            extra_arguments=[{'use_intra_process_comms': True}],
        ),
        ComposableNode(
            package='tdorc_filter',
            plugin='tdorc_filter::TdorcFilterComponent',
            name='tdorc_filter',
            namespace=namespace,
            parameters=launch_common.parameters(tdorc_params),
            extra_arguments=[{'use_intra_process_comms': True}],
        ),
    ]


def generate_launch_description():
    left_device = LaunchConfiguration('left_device')
    right_device = LaunchConfiguration('right_device')
    tdorc_params = LaunchConfiguration('tdorc_params')
    container = ComposableNodeContainer(
        name='bench_rig_container',
        namespace='',
        package='rclcpp_components',
        executable='component_container',
        composable_node_descriptions=(
            whisker_nodes('left', left_device, tdorc_params) +
            whisker_nodes('right', right_device, tdorc_params)
        ),
        output='screen',
    )
    return LaunchDescription([
        launch_common.namespace_argument(),
        DeclareLaunchArgument('left_device', default_value='/dev/ttyUSB0',
                              description='serial device of whisker 1 (text protocol)'),
        DeclareLaunchArgument('right_device', default_value='/dev/ttyUSB1',
                              description='serial device of whisker 2 (CSV protocol)'),
        DeclareLaunchArgument('tdorc_params', default_value=launch_common.config('tdorc_filter'),
                              description='parameter file of both TDORC filters'),
        launch_common.in_namespace([container]),
        launch_common.stop_on_load_failure(container),
    ] + ([lifecycle_common.activate_argument(), lifecycle_common.manage_lifecycle(DRIVERS)]
         if lifecycle_common.is_lifecycle('whisker_driver') else []))
