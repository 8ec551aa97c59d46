"""Whisker preimage localization (paper 002) as a ROS 2 composable node.

The node subscribes to the whisker's base moment (geometry_msgs/WrenchStamped,
torque.z = M(0)) and the base odometry, and publishes the localization result
(tactile_msgs/LocalizationResult) and the pose set (geometry_msgs/PoseArray).
Parameters come from config/whisker_localization.yaml. There is no ROS node of
the linear-stage simulator yet: feed the node from a bag or a stage driver. The
bench protocols (Table I / II) run without ROS through `whisker_loc_sitl`.

    ros2 launch launch/sitl_localization.launch.py [params:=path/to.yaml] [possibilistic:=true]
"""
import importlib.util
import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import ComposableNodeContainer
from launch_ros.descriptions import ComposableNode
from launch_ros.parameter_descriptions import ParameterValue

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_PARAMS = os.path.join(HERE, "..", "config", "whisker_localization.yaml")

_common_spec = importlib.util.spec_from_file_location(
    'launch_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'launch_common.py'))
launch_common = importlib.util.module_from_spec(_common_spec)
_common_spec.loader.exec_module(launch_common)


def generate_launch_description():
    params = LaunchConfiguration("params")
    possibilistic = LaunchConfiguration("possibilistic")
    return LaunchDescription([
        DeclareLaunchArgument("params", default_value=DEFAULT_PARAMS,
                              description="whisker_localization parameter file"),
        DeclareLaunchArgument("possibilistic", default_value="false",
                              description="bounded-error preimages (002 eq. 23-25)"),
        ComposableNodeContainer(
            name="whisker_localization_container",
            namespace="",
            package="rclcpp_components",
            executable="component_container",
            composable_node_descriptions=[
                ComposableNode(
                    package="whisker_localization",
                    plugin="whisker_localization::WhiskerLocalizationComponent",
                    name="whisker_localization",
                    parameters=launch_common.parameters(
                        params, {"possibilistic": ParameterValue(possibilistic, value_type=bool)}),
                ),
            ],
            output="screen",
        ),
        launch_common.stop_on_load_failure(),
    ])
