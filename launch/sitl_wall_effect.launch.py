"""SITL of the ducted quadrotor (paper 004) with ROS 2: simulator -> wall-effect EKF ->
wall following / vector field (or 004's estimation-flight script) -> INDI controller ->
rotor thrusts back to the simulator, composed in one container on simulated time.

    ros2 launch launch/sitl_wall_effect.launch.py scenario:=config/scenarios/ducted_track_0.yaml
    ros2 launch launch/sitl_wall_effect.launch.py \\
        scenario:=config/scenarios/ducted_estimation.yaml behaviour:=trajectory

The standalone host runs the same graphs without ROS (`graph: wall_effect_nav` /
`graph: wall_effect` in the scenario):

    tactile sim config/scenarios/ducted_track_0.yaml --out out/track0

Parameters come from the files in config/ (the ones `tactile sim` reads); a scenario's
node_parameters are the host's per-node overrides and are not applied here: pass them as
launch parameters or edit the config files. The simulator publishes /clock
(/<namespace>/clock under namespace:=).
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


config = launch_common.config


def nodes(context):
    sim_time = launch_common.SIM_TIME
    intra = launch_common.INTRA
    behaviour = LaunchConfiguration('behaviour').perform(context)
    out = [
        launch_common.simulator_node('wall_effect/setpoint'),
        ComposableNode(
            package='wall_effect_ekf', plugin='wall_effect_ekf::WallEffectEkfComponent',
            name='wall_effect_ekf', parameters=launch_common.parameters(
                config('wall_effect_ekf'), sim_time),
            extra_arguments=intra),
        ComposableNode(
            package='wall_effect_ekf', plugin='wall_effect_ekf::IndiControlComponent',
            name='indi_controller', parameters=launch_common.parameters(
                config('indi_controller'), sim_time),
            extra_arguments=intra),
    ]
    if behaviour == 'trajectory':
        out.append(ComposableNode(
            package='wall_effect_ekf', plugin='wall_effect_ekf::WallTrajectoryComponent',
            name='wall_trajectory', parameters=launch_common.parameters(
                config('wall_trajectory'), sim_time,
                {'frame_prefix': ParameterValue(launch_common.frame_prefix_value(), value_type=str)}),
            extra_arguments=intra))
    else:
        out.append(ComposableNode(
            package='tactile_fsm', plugin='tactile_fsm::WallEffectNavComponent',
            name='wall_effect_nav', parameters=launch_common.parameters(
                config('wall_effect_nav'), sim_time),
            extra_arguments=intra))
    return launch_common.sitl_container('sitl_wall_effect_container', out + launch_common.visualization_nodes())


def generate_launch_description():
    return LaunchDescription(launch_common.sitl_arguments('ducted_track_0')
        + launch_common.rviz_arguments('wall_effect', sim_time=True) + [
        DeclareLaunchArgument('behaviour', default_value='navigation',
                              description="'navigation' (wall_effect_nav) or 'trajectory' "
                                          "(004 estimation-flight script)"),
        OpaqueFunction(function=nodes),
    ])
