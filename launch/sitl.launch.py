"""The bridge flies the simulated Crazyflie: crazyflie_sim_server (the SITL whiskered
drone behind the firmware side of CRTP on UDP, wall-clock physics) plus the same
container as radio.launch.py with the bridge on udp://127.0.0.1:<port>.

    ros2 launch launch/sitl.launch.py scenario:=config/scenarios/whisker_darkness_rigid_fsm.yaml
    ros2 launch tactile_bringup sitl.launch.py namespace:=cf1 port:=19851

As radio.launch.py, nothing flies until `takeoff` (then `start_behaviour`) unless
autostart:=true; a lifecycle bridge is configured and activated (activate:=false: configured only).
Ctrl-C reaches crazyflie_sim_server and the bridge together: the server lingers
(--linger) while the motors run, so the bridge's shutdown landing lands the simulated
vehicle, and ends 0.5 s after the motors stopped (at most the container's stop timeout:
shutdown_land_timeout_s + 5 s).

Any cflib-based tool (cfclient, scripts) can connect to the same simulated Crazyflie
instead: udp://127.0.0.1:19850. The standalone host does the whole flight without ROS:

    tactile fly --sim config/scenarios/whisker_darkness_rigid_fsm.yaml --out out/dark

Note: the FSM's parameters (target, band, first approach) come from config/tactile_fsm.yaml
here; `tactile fly --sim` also applies the scenario's node_parameters and metrics.target.
For the darkness scenarios those set the band 40-100 mm and the paper's straight first
approach (first_whisk_amplitude: 0; the default steps and scans, src/tactile_fsm/docs/whisker_fsm.md
"Step and scan"): to fly them here as there, set the same keys in config/tactile_fsm.yaml.
"""

import importlib.util
import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, OpaqueFunction
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution, PythonExpression
from launch_ros.substitutions import FindPackagePrefix

HERE = os.path.dirname(os.path.abspath(__file__))

_spec = importlib.util.spec_from_file_location('radio_launch', os.path.join(HERE, 'radio.launch.py'))
_radio = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_radio)


def simulated_crazyflie(context):
    """crazyflie_sim_server on the scenario; seed -1 (the default) leaves --seed out: the
    scenario's own seed (the server refuses negative seeds)."""
    seed = LaunchConfiguration('seed').perform(context)
    return [ExecuteProcess(
        cmd=[PathJoinSubstitution([FindPackagePrefix('crazyflie_bridge'), 'lib', 'crazyflie_bridge',
                                   'crazyflie_sim_server']),
             LaunchConfiguration('scenario'), '--port', LaunchConfiguration('port')]
        + ([] if seed.strip() == '-1' else ['--seed', seed])
        + ['--linger', _radio.container_stop_timeout()],
        # SIGTERM (which ends a linger at once) only after the linger's bound
        output='screen', sigterm_timeout=str(float(_radio.container_stop_timeout()) + 2.0))]


def generate_launch_description():
    port = LaunchConfiguration('port')
    server = OpaqueFunction(function=simulated_crazyflie)
    uri = PythonExpression(["'udp://127.0.0.1:' + '", port, "'"])
    return LaunchDescription([
        DeclareLaunchArgument('scenario', default_value=_radio.launch_common.scenario(
            'whisker_darkness_rigid_fsm'),
            description='scenario of the simulated Crazyflie (arena, vehicle, estimate)'),
        DeclareLaunchArgument('port', default_value='19850', description='UDP port (19850 + N)'),
        DeclareLaunchArgument('seed', default_value='-1', description="noise seed (-1: the scenario's)"),
        _radio.launch_common.namespace_argument(),
        _radio.autostart_argument(),
        _radio.launch_common.frame_prefix_argument(),
        server,
    ] + _radio.launch_common.rviz_arguments('crazyflie', sim_time=False) + _radio.radio_container(uri, name='sitl_bridge_container') + _radio.bridge_lifecycle())
