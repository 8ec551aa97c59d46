"""Whisker preimage localization (paper 002) with ROS 2: the whisker stage simulator
(tactile_sim, vehicle whisker_stage: the linear stage with the whisker and the pin of 002's
bench) -> whisker_localization, composed in one container on simulated time.

    ros2 launch tactile_bringup sitl_localization.launch.py [possibilistic:=true]
    ros2 launch launch/sitl_localization.launch.py scenario:=config/scenarios/whisker_stage_table2.yaml
    ros2 launch launch/sitl_localization.launch.py simulator:=false   # fed from a bag or a stage driver

whisker_localization subscribes to the whisker's base moment (whisker/base_wrench,
geometry_msgs/WrenchStamped, torque.z = M(0)) and the base odometry (odom), and publishes
the localization result (whisker/localization, tactile_msgs/LocalizationResult) and the
pose set (whisker/pose_set, geometry_msgs/PoseArray). The simulated stage holds its
initial pose until a position setpoint arrives on cmd_position (geometry_msgs/PoseStamped,
the stage's base pose in the world): the bench protocols of 002 (Table I / II) run without
ROS through `tactile sim config/scenarios/whisker_stage_table1.yaml`, whose host graph
scripts the stage. Parameters come from config/whisker_localization.yaml (params:= another
file); the scenario, seed, real_time_factor, wait_for_subscribers and namespace are
the arguments of every sitl_* launch (launch_common.sitl_arguments).
"""
import importlib.util
import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.descriptions import ComposableNode
from launch_ros.parameter_descriptions import ParameterValue

_common_spec = importlib.util.spec_from_file_location(
    'launch_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'launch_common.py'))
launch_common = importlib.util.module_from_spec(_common_spec)
_common_spec.loader.exec_module(launch_common)


def nodes(context):
    simulator = LaunchConfiguration('simulator').perform(context) == 'true'
    localization = ComposableNode(
        package='whisker_localization',
        plugin='whisker_localization::WhiskerLocalizationComponent',
        name='whisker_localization',
        parameters=launch_common.parameters(
            LaunchConfiguration('params'),
            {'possibilistic': ParameterValue(LaunchConfiguration('possibilistic'), value_type=bool)},
            *([launch_common.SIM_TIME] if simulator else [])),
        extra_arguments=launch_common.INTRA)
    # The localization publishes its outputs from construction: the world starts once it is loaded.
    graph = [launch_common.simulator_node('whisker/localization')] if simulator else []
    return launch_common.sitl_container('whisker_localization_container', graph + [localization] + launch_common.visualization_nodes())


def generate_launch_description():
    return LaunchDescription(launch_common.sitl_arguments('whisker_stage_table1')
        + launch_common.rviz_arguments(
            'localization',
            sim_time=lambda context: LaunchConfiguration('simulator').perform(context) == 'true') + [
        DeclareLaunchArgument('params', default_value=launch_common.config('whisker_localization'),
                              description='whisker_localization parameter file'),
        DeclareLaunchArgument('possibilistic', default_value='false',
                              description='bounded-error preimages (002 eq. 23-25)'),
        DeclareLaunchArgument('simulator', default_value='true', choices=['true', 'false'],
                              description='true: the whisker stage simulator feeds the node (simulated '
                                          'time); false: the node alone on wall-clock time, fed by '
                                          'a bag or a stage driver'),
        OpaqueFunction(function=nodes),
    ])
