"""Whiskered Crazyflie over the radio (paper 000 pipeline on the ground station):
crazyflie_bridge (CRTP over Crazyradio / USB / UDP) -> TDORC x2 -> tactile depth ->
whisker wall-following FSM -> hover setpoints back through the bridge, composed in one
container on wall-clock time.

    ros2 launch launch/radio.launch.py uri:=radio://0/80/2M/E7E7E7E7E7?safelink=1

Where the ROS 2 installation has rclcpp_lifecycle the bridge is a lifecycle node: the launch
configures it (connects: link, TOCs, log blocks) and, once it is `inactive`, activates it
(streams); activate:=false leaves it inactive, the radio up, for the operator to check
(`ros2 lifecycle get /crazyflie_bridge`, then `ros2 lifecycle set /crazyflie_bridge activate`).
A failed connect leaves it `unconfigured` with its error and the launch running
(lifecycle_common.py). Without rclcpp_lifecycle it connects when loaded.

Nothing flies until the operator asks (autostart:=false, the default): the bridge connects,
streams the sensors and stays on the ground; `takeoff`, then `start_behaviour` hands over to
the whisker FSM; `land`, `emergency`, `arm`, `go_to`, `notify_setpoints_stop` as in
crazyflie_bridge/README.md "Operator surface". autostart:=true forwards the FSM as soon as
setpoints and log data are fresh (take-off on connect: the SITL tests). Ctrl-C lands first
(within the bridge's shutdown_land_timeout_s), then stops the motors; the container is
given that long plus a margin before launch escalates to SIGTERM.

The bridge reads the whisker deck's log variables (Whisker.Barometer1_1..3,
Whisker1.Barometer2_1..3) at 50 Hz and stateEstimate.x/y/z/yaw/vx/vy at 100 Hz in two
log blocks (config/crazyflie_bridge.yaml) and
publishes /whisker/{left,right}/pressure and /odom; /cmd_hover goes out as generic
commander hover setpoints, clamped, with the stale-input chain hover -> land -> stop
(crazyflie_bridge/README.md). The standalone host runs the same graph without ROS:

    tactile fly --uri radio://0/80/2M/E7E7E7E7E7 --out out/flight

Parameters come from config/ (crazyflie_bridge.yaml, crazyflie_bridge_health.yaml, tdorc_filter.yaml,
tactile_depth.yaml, tactile_fsm.yaml); `uri` overrides the bridge's. The FSM's first
approach steps and scans by default (src/tactile_fsm/docs/whisker_fsm.md "Step and scan"); against a single wall
ahead set first_whisk_amplitude: 0 there for the paper's straight approach. The Crazyradio needs
the Bitcraze udev rules (or run as root / pass the device into the container). Without a
Crazyradio the bridge cannot connect: the plain node's load fails and the launch ends with its
message ("no Crazyradio found"); the lifecycle node logs it and stays unconfigured.
"""

import importlib.util
import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import ComposableNodeContainer
from launch_ros.descriptions import ComposableNode
from launch_ros.parameter_descriptions import ParameterValue
import yaml

_common_spec = importlib.util.spec_from_file_location(
    'launch_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'launch_common.py'))
launch_common = importlib.util.module_from_spec(_common_spec)
_common_spec.loader.exec_module(launch_common)
_lifecycle_spec = importlib.util.spec_from_file_location(
    'lifecycle_common', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'lifecycle_common.py'))
lifecycle_common = importlib.util.module_from_spec(_lifecycle_spec)
_lifecycle_spec.loader.exec_module(lifecycle_common)


config = launch_common.config


def autostart_argument():
    return DeclareLaunchArgument(
        'autostart', default_value='false', choices=['true', 'false'],
        description='true: forward the behaviour as soon as setpoints and log data are fresh '
                    '(take-off on connect); false: nothing flies until the takeoff service')


def bridge_overrides(uri, frame_prefix=None, initial_position=None):
    """The bridge's launch-argument overrides: uri, autostart and frame_prefix (the launch
    argument, or '<namespace>/' under a namespace, unless given: a robot's namespace + '/'),
    and a robot's initial_position (map -> odom) where given."""
    if frame_prefix is None:
        frame_prefix = launch_common.frame_prefix_value()
    overrides = {'uri': uri, 'autostart': ParameterValue(LaunchConfiguration('autostart'), value_type=bool),
                 'frame_prefix': ParameterValue(frame_prefix, value_type=str)}
    if initial_position is not None:
        overrides['initial_position'] = [float(v) for v in initial_position]
    return overrides


def container_stop_timeout():
    """Seconds `ros2 launch` waits after SIGINT before it sends SIGTERM to the container: the
    bridge's shutdown landing is bounded by shutdown_land_timeout_s (config/crazyflie_bridge.yaml,
    else the logic's default), plus 5 s for the rest of the graph to stop."""
    with open(config('crazyflie_bridge')) as f:
        sections = yaml.safe_load(f) or {}
    params = {}
    for key in ('/**/crazyflie_bridge', 'crazyflie_bridge', '/crazyflie_bridge'):
        params.update((sections.get(key) or {}).get('ros__parameters', {}))
    return str(float(params.get('shutdown_land_timeout_s', 10.0)) + 5.0)


BRIDGE = 'crazyflie_bridge'  # in the launch's namespace (lifecycle_common.manage_lifecycle)


def bridge_lifecycle(bridges=(BRIDGE,)):
    """The `activate` argument and the configure -> activate sequence of the bridges (relative:
    in the launch argument namespace; or fully qualified) where the bridge is a lifecycle node
    (lifecycle_common.py); nothing where it is a plain node."""
    if not lifecycle_common.is_lifecycle('crazyflie_bridge'):
        return []
    return [lifecycle_common.activate_argument(), lifecycle_common.manage_lifecycle(list(bridges))]


def pipeline_nodes(bridge_overrides):
    """The bridge and the whisker pipeline (also used by sitl.launch.py)."""
    intra = [{'use_intra_process_comms': True}]
    nodes = [ComposableNode(
        package='crazyflie_bridge', plugin='crazyflie_bridge::CrazyflieBridgeComponent',
        name='crazyflie_bridge', parameters=launch_common.parameters(
            config('crazyflie_bridge'), config('crazyflie_bridge_health'), bridge_overrides),
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


def radio_container(uri, namespace=None, name='radio_container', frame_prefix=None, initial_position=None):
    """One Crazyflie: the container `name` (bridge on `uri` + the whisker pipeline) in
    `namespace` (else the launch argument namespace), its frames behind `frame_prefix`
    (else the launch argument frame_prefix), at `initial_position` in map (else the
    bridge's config), and its load-failure watch."""
    container = ComposableNodeContainer(
        name=name, namespace='', package='rclcpp_components',
        executable='component_container',
        composable_node_descriptions=pipeline_nodes(bridge_overrides(uri, frame_prefix, initial_position))
        + launch_common.visualization_nodes(sim_time=False),
        output='screen', sigterm_timeout=container_stop_timeout())
    return [launch_common.in_namespace([container], namespace=namespace),
            launch_common.stop_on_load_failure(container)]


def robots_or_one(context):
    """With robots:=FILE one container per enabled robot of the file, each in its namespace
    (launch_common.load_robots); else one on the launch arguments uri and namespace."""
    path = LaunchConfiguration('robots').perform(context)
    if not path:
        return radio_container(LaunchConfiguration('uri')) + manage_bridges([BRIDGE])
    robots = launch_common.load_robots(path)
    actions = []
    for robot in robots:  # each robot's frames behind its namespace: cf1/odom, cf1/base_link
        actions += radio_container(robot.uri, namespace=robot.namespace, frame_prefix=robot.namespace + '/',
                                   initial_position=robot.initial_position)
    return actions + manage_bridges(['/' + r.namespace + '/' + BRIDGE for r in robots])


def manage_bridges(bridges):
    if not lifecycle_common.is_lifecycle('crazyflie_bridge'):
        return []
    return [lifecycle_common.manage_lifecycle(bridges)]


def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('uri', default_value='radio://0/80/2M/E7E7E7E7E7?safelink=1',
                              description='Crazyflie link URI (radio://, usb://, udp://); not with robots'),
        launch_common.namespace_argument(),
        DeclareLaunchArgument('robots', default_value='',
                              description='robots file (config/crazyflies.yaml style): one bridge '
                                          'and pipeline per enabled robot, in its namespace, on its '
                                          'uri (uri and namespace are then not used)'),
        autostart_argument(),
        launch_common.frame_prefix_argument(),
    ] + launch_common.rviz_arguments('crazyflie', sim_time=False) + ([lifecycle_common.activate_argument()] if lifecycle_common.is_lifecycle('crazyflie_bridge')
         else []) + [
        OpaqueFunction(function=robots_or_one),  # after every argument it reads
    ])
