"""Shared by the launch files of this directory (loaded by path, as they are):
where the parameter files are (CONFIG_DIR), the vehicle's namespace (namespace:=), the
simulator of the sitl_* launches, and: a composable node that cannot start stops the whole
launch, and its parameter error names the file (or the launch argument) the bad value came
from.

Config: config/ is the directory beside this one, in the source tree (launch/ and config/
of the workspace, `ros2 launch launch/<file>`) and where the package tactile_bringup
installed both (share/tactile_bringup/launch and .../config, `ros2 launch tactile_bringup
<file>` from any directory). It is looked up here only; the launch files use config().

Namespace: every launch file takes namespace:= (default empty: the root, the names the
launch files always had). Every topic of the nodes is relative, so under namespace:=cf1 the
whisker FSM subscribes /cf1/whisker/depth and publishes /cf1/cmd_hover. The sitl_* launches
also remap each node's /clock to /<namespace>/clock: two simulators on one domain keep
their own simulated time.

The component container only logs a failed load (a bad parameter, a missing Crazyradio,
a serial device that is not there) and keeps running the rest of the graph, which then
waits for that node's topics for ever. Here the launch ends instead, with exit code 1 and
the component's own message (it names the node, the parameter or device and the reason).
"""

import os

from launch.actions import DeclareLaunchArgument, GroupAction, OpaqueFunction, RegisterEventHandler
from launch.event_handlers import OnProcessIO
from launch.substitution import Substitution
from launch.substitutions import LaunchConfiguration, PythonExpression, TextSubstitution
from launch_ros.parameter_descriptions import ParameterValue

LOAD_FAILURE = 'Component constructor threw an exception'

HERE = os.path.dirname(os.path.abspath(__file__))


def _config_dir():
    path = os.path.normpath(os.path.join(HERE, '..', 'config'))
    if not os.path.isdir(path):
        raise FileNotFoundError(
            f'{path}: no config/ beside {HERE} (the source tree has launch/ and config/ side by '
            'side, and so does share/tactile_bringup where the package tactile_bringup installs them)')
    return path


CONFIG_DIR = _config_dir()


def config(name):
    """config/<name>.yaml: a node's parameter file."""
    return os.path.join(CONFIG_DIR, name + '.yaml')


def scenario(name):
    """config/scenarios/<name>.yaml: a simulator scenario."""
    return os.path.join(CONFIG_DIR, 'scenarios', name + '.yaml')


def namespace_argument():
    return DeclareLaunchArgument(
        'namespace', default_value='',
        description='ROS namespace of every node and topic of this launch, e.g. cf1: '
                    '/cf1/odom, /cf1/whisker_fsm (empty: the root)')


def namespace_of(context, value=None):
    """The namespace (no leading or trailing '/'; '' at the root) of `value`, else of the
    launch argument `namespace`."""
    from launch.substitutions import LaunchConfiguration
    ns = value if value is not None else LaunchConfiguration('namespace').perform(context)
    return ns.strip().strip('/')


def in_namespace(actions, clock=False, namespace=None):
    """`actions` (containers and their nodes) under `namespace`, else the launch argument
    namespace (namespace_argument()); with clock=True every node's /clock, /tf and
    /tf_static are remapped to /<namespace>/clock, /<namespace>/tf, /<namespace>/tf_static
    (the sitl_* launches: each simulator publishes its vehicle's time, and its transforms
    are stamped on it). At the root nothing is pushed or remapped."""
    def build(context):
        from launch_ros.actions import PushRosNamespace, SetRemap
        ns = namespace_of(context, namespace)
        scoped = []
        if ns:
            scoped.append(PushRosNamespace(ns))
            if clock:
                # Each simulator's own time, and its TF on that time: /tf and /tf_static
                # move with /clock (a tool following one vehicle takes the same remaps).
                for topic in ('/clock', '/tf', '/tf_static'):
                    scoped.append(SetRemap(src=topic, dst=f'/{ns}{topic}'))
        return [GroupAction(scoped + list(actions))]
    return OpaqueFunction(function=build)


class NodeFailedToStart(RuntimeError):
    pass


def _check_output(event):
    text = event.text.decode(errors='replace') if isinstance(event.text, bytes) else event.text
    for line in text.splitlines():
        if LOAD_FAILURE in line:
            # An exception in an event handler ends `ros2 launch` with exit code 1 and
            # "Caught exception in launch ...: <message>" after shutting the processes down.
            raise NodeFailedToStart('a node failed to start: ' + line.split(LOAD_FAILURE, 1)[1]
                                    .lstrip(': '))
    return None


def stop_on_load_failure(container=None):
    """The event handler to add to a launch description: watches the output of `container`
    (a ComposableNodeContainer), or of every process of the launch when None."""
    return RegisterEventHandler(OnProcessIO(
        target_action=container, on_stdout=_check_output, on_stderr=_check_output))



PARAMETER_SOURCES = 'tactile.parameter_sources'


def _text(substitutions):
    return ''.join(s.text for s in substitutions if isinstance(s, TextSubstitution))


def _launch_arguments(value):
    """The launch arguments a parameter value of a launch-file dict is taken from."""
    if isinstance(value, LaunchConfiguration):
        return [_text(value.variable_name)]
    if isinstance(value, ParameterValue):
        return _launch_arguments(value.value)
    if isinstance(value, PythonExpression):
        return _launch_arguments(value.expression)
    if isinstance(value, (list, tuple)):
        return [name for v in value for name in _launch_arguments(v)]
    return []


def _dict_keys(values, prefix=''):
    """(key, value) of a launch-file parameter dict, nested dicts flattened with '.'."""
    for key, value in values.items():
        if not isinstance(key, str):
            continue
        if isinstance(value, dict):
            yield from _dict_keys(value, prefix + key + '.')
        else:
            yield prefix + key, value


def parameters(*entries):
    """The `parameters` of a ComposableNode: `entries` (parameter files as paths or launch
    arguments, and dicts) followed by the string array tactile.parameter_sources, which
    tells the component where each value came from. `ros2 launch` reads the parameter
    files itself and hands the component plain values, so without it a bad value could
    only be blamed on the node, not on its file (tactile_common/ros_parameters.hpp reads
    it). Its entries, in launch's order: each file's path, and "launch:<key>" or
    "launch:<key>:<launch argument>" for every key a dict sets."""
    sources = []
    for entry in entries:
        if isinstance(entry, dict):
            for key, value in _dict_keys(entry):
                names = _launch_arguments(value)
                sources.append(['launch:' + key + (':' + names[0] if len(names) == 1 else '')])
        elif isinstance(entry, (str, os.PathLike)):
            sources.append([os.path.normpath(os.fspath(entry))])
        elif isinstance(entry, Substitution):
            sources.append([entry])  # a parameter file named by a launch argument
        else:
            raise TypeError(f'parameters(): a file or a dict, got {entry!r}')
    return list(entries) + ([{PARAMETER_SOURCES: sources}] if sources else [])


SIM_TIME = {'use_sim_time': True}
INTRA = [{'use_intra_process_comms': True}]


def sitl_arguments(default_scenario):
    """The launch arguments of every sitl_* launch file: scenario (default
    config/scenarios/<default_scenario>.yaml), seed, real_time_factor, wait_for_subscribers,
    namespace and frame_prefix."""
    from launch.actions import DeclareLaunchArgument as Arg
    return [
        Arg('scenario', default_value=scenario(default_scenario),
            description='scenario file of the simulator'),
        Arg('seed', default_value='-1', description="noise seed (-1: the scenario's)"),
        Arg('real_time_factor', default_value='1.0',
            description='simulated seconds per wall-clock second (1.0: real time; the '
                        'simulator publishes sim/done at the end)'),
        Arg('wait_for_subscribers', default_value='',
            description="the simulator's topics (comma-separated; relative ones in the "
                        'namespace) that must have a subscriber in another process before '
                        'the world starts, e.g. a recorder'),
        namespace_argument(),
        frame_prefix_argument(),
    ]


def frame_prefix_argument():
    """The launch argument frame_prefix of the vehicle launch files (sitl_*, sitl, radio):
    goes before every frame name the simulator or the bridge stamps and broadcasts but map
    ('' or ending in '/': cf1/ gives cf1/base_link; tactile_common/frames.hpp)."""
    from launch.actions import DeclareLaunchArgument
    return DeclareLaunchArgument(
        'frame_prefix', default_value='',
        description="prefix of the vehicle's frames ('' or ending in '/', e.g. cf1/; empty: "
                    "'<namespace>/' under a namespace, none at the root)")


def frame_prefix_value():
    """The vehicle's frame prefix: the launch argument frame_prefix, else under a namespace
    '<namespace>/' (namespace:=cf1 gives cf1/base_link: two vehicles never share a frame
    on /tf), else '' (the root: base_link)."""
    fp, ns = LaunchConfiguration('frame_prefix'), LaunchConfiguration('namespace')
    return PythonExpression(["'", fp, "' or ('", ns, "'.strip().strip('/') + '/' if '", ns,
                             "'.strip().strip('/') else '')"])


def prefixed_frame(frame):
    """A frame-name parameter value behind the vehicle's frame prefix (frame_prefix_value()),
    e.g. for xplorer_force_est's world_frame: 'odom' gives cf1/odom with frame_prefix:=cf1/."""
    return ParameterValue([frame_prefix_value(), frame], value_type=str)


def simulator_node(wait_for_publisher):
    """The simulator component of every sitl_* launch file (their arguments sitl_arguments()).
    It starts the world once `wait_for_publisher` (a topic of the graph's node loaded last,
    relative: in the namespace) has a publisher, and holds t = 0 until the topics of
    wait_for_subscribers have a subscriber in another process (a recorder; comma-separated,
    '' starts at once)."""
    from launch_ros.descriptions import ComposableNode
    return ComposableNode(
        package='tactile_sim', plugin='tactile_sim::TactileSimComponent', name='tactile_sim',
        parameters=parameters(
            {'scenario': LaunchConfiguration('scenario'),
             'seed': LaunchConfiguration('seed'),
             'real_time_factor': ParameterValue(
                 LaunchConfiguration('real_time_factor'), value_type=float),
             'wait_for_publisher': wait_for_publisher,
             'frame_prefix': ParameterValue(frame_prefix_value(), value_type=str),
             'wait_for_subscribers': ParameterValue(
                 LaunchConfiguration('wait_for_subscribers'), value_type=str)}),
        extra_arguments=INTRA)


def visualization_nodes(sim_time=True):
    """The visualization component (tactile_viz) of every sitl_* launch, as a list to add to
    the container's nodes: RViz markers of the graph's estimates and events on
    visualization/markers, the GPIS mean and variance grids on gpis/mean_grid and
    gpis/variance_grid (topics relative: in the launch namespace; the markers take their
    frames from the input messages, so the frame prefix needs no parameter here). On
    simulated time unless sim_time is False; parameters from config/visualization.yaml. Empty, with a warning, where
    tactile_viz was built without its component (a ROS 2 installation without
    visualization_msgs, e.g. the Jazzy toolchain): the graph runs without markers."""
    from ament_index_python import get_resource
    from launch.logging import get_logger
    from launch_ros.descriptions import ComposableNode
    plugin = 'tactile_viz::VisualizationComponent'
    try:
        registered, _ = get_resource('rclcpp_components', 'tactile_viz')
    except LookupError:
        registered = ''
    if plugin not in registered:
        get_logger('launch_common').warning(
            f'{plugin} is not installed (tactile_viz built without visualization_msgs): no visualization node')
        return []
    return [ComposableNode(
        package='tactile_viz', plugin=plugin, name='visualization',
        parameters=parameters(config('visualization'), *([SIM_TIME] if sim_time else [])),
        extra_arguments=INTRA)]


def sitl_container(name, nodes):
    """The container of a sitl_* launch: `nodes` (the simulator first) in one process, in
    the launch argument namespace with /clock remapped into it, and a failed load stops the
    launch."""
    from launch_ros.actions import ComposableNodeContainer
    container = ComposableNodeContainer(
        name=name, namespace='', package='rclcpp_components', executable='component_container',
        composable_node_descriptions=nodes, output='screen')
    return [in_namespace([container], clock=True), stop_on_load_failure(container)]


class RvizUnavailable(RuntimeError):
    pass


def rviz_config(name):
    """config/rviz/<name>.rviz: the RViz configuration shipped for a launch file."""
    return os.path.join(CONFIG_DIR, 'rviz', name + '.rviz')


def rviz_arguments(default_config, sim_time):
    """The launch arguments rviz (default false) and rviz_config (default
    config/rviz/<default_config>.rviz) of the vehicle launch files, and the action that
    starts rviz2 with them: in the launch's namespace (the configs' topics are relative, so
    namespace:=cf1 shows cf1), on simulated time with /clock, /tf and /tf_static remapped as
    the simulator's (in_namespace(clock=True)) when `sim_time` (a bool, or a function of the
    launch context giving one). rviz:=true where rviz2 is not
    installed ends the launch saying so, before any node starts."""
    return [
        DeclareLaunchArgument('rviz', default_value='false', choices=['true', 'false'],
                              description='true: start rviz2 with rviz_config'),
        DeclareLaunchArgument('rviz_config', default_value=rviz_config(default_config),
                              description='RViz configuration (config/rviz/)'),
        OpaqueFunction(function=lambda context: _rviz(context, sim_time)),
    ]


def _rviz(context, sim_time):
    from launch.substitutions import LaunchConfiguration
    if LaunchConfiguration('rviz').perform(context) != 'true':
        return []
    path = LaunchConfiguration('rviz_config').perform(context)
    if not os.path.isfile(path):
        raise RvizUnavailable(f'rviz_config:={path}: no such file')
    from ament_index_python.packages import PackageNotFoundError, get_package_prefix
    try:
        get_package_prefix('rviz2')
    except PackageNotFoundError:
        distro = os.environ.get('ROS_DISTRO', '<distro>')
        raise RvizUnavailable(
            f'rviz:=true but the package rviz2 is not installed in this ROS 2 (Debian/Ubuntu: '
            f'apt install ros-{distro}-rviz2); the graph does not need it: launch without '
            f'rviz:=true, or run rviz2 -d {path} where it is installed') from None
    from launch_ros.actions import Node
    ns = namespace_of(context)
    sim_time = sim_time(context) if callable(sim_time) else sim_time
    remaps = [(t, f'/{ns}{t}') for t in ('/clock', '/tf', '/tf_static')] if ns and sim_time else []
    return [Node(package='rviz2', executable='rviz2', name='rviz2', namespace=ns,
                 arguments=['-d', path], parameters=[{'use_sim_time': sim_time}],
                 remappings=remaps, output='screen')]


class RobotsFileError(ValueError):
    pass


class Robot:
    """One enabled robot of a robots file (load_robots)."""

    def __init__(self, name, uri, namespace, initial_position):
        self.name = name
        self.uri = uri
        self.namespace = namespace
        self.initial_position = initial_position

    def __repr__(self):
        return (f'Robot({self.name!r}, uri={self.uri!r}, namespace={self.namespace!r}, '
                f'initial_position={self.initial_position!r})')


ROBOT_KEYS = ('enabled', 'uri', 'namespace', 'initial_position', 'type')
URI_SCHEMES = ('radio://', 'usb://', 'udp://')


def _namespace_ok(ns):
    import re
    return re.fullmatch(r'[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*', ns) is not None


def load_robots(path):
    """The enabled robots of a robots file in the style of Crazyswarm2's crazyflies.yaml:

        robots:
          cf1:                          # the robot's name
            enabled: true               # false: listed, not started
            uri: radio://0/80/2M/E7E7E7E7E7
            namespace: cf1              # optional: the name (Crazyswarm2's convention)
            initial_position: [0.0, 0.0, 0.0]   # m, world frame, where it stands at take-off
            type: whisker_crazyflie     # optional, informative

    Every error names the file, the robot and the key. Namespaces and URIs of the enabled
    robots are unique; at least one robot is enabled."""
    import math
    import yaml
    try:
        with open(path) as f:
            doc = yaml.safe_load(f)
    except OSError as e:
        raise RobotsFileError(f'{path}: cannot read the robots file: {e.strerror}') from None
    except yaml.YAMLError as e:
        raise RobotsFileError(f'{path}: not YAML: {e}') from None
    if not isinstance(doc, dict) or not isinstance(doc.get('robots'), dict) or not doc['robots']:
        raise RobotsFileError(f"{path}: expected a map 'robots' of robot name -> "
                              '{enabled, uri, namespace, initial_position}')
    robots, namespaces, uris = [], {}, {}
    for name, entry in doc['robots'].items():
        where = f'{path}: robots.{name}'
        if not isinstance(entry, dict):
            raise RobotsFileError(f'{where}: expected a map with enabled, uri, initial_position')
        unknown = sorted(set(entry) - set(ROBOT_KEYS))
        if unknown:
            raise RobotsFileError(f'{where}: unknown key {unknown[0]} (keys: {", ".join(ROBOT_KEYS)})')
        for key in ('enabled', 'uri', 'initial_position'):
            if key not in entry:
                raise RobotsFileError(f'{where}.{key}: missing')
        if not isinstance(entry['enabled'], bool):
            raise RobotsFileError(f'{where}.enabled: expected true or false, got {entry["enabled"]!r}')
        uri = entry['uri']
        if not isinstance(uri, str) or not uri.startswith(URI_SCHEMES):
            raise RobotsFileError(f'{where}.uri: expected a Crazyflie URI ({", ".join(URI_SCHEMES)}), '
                                  f'got {uri!r}')
        namespace = entry.get('namespace', name)
        if not isinstance(namespace, str) or not _namespace_ok(namespace.strip('/')):
            raise RobotsFileError(f'{where}.namespace: expected a ROS namespace (letters, digits, '
                                  f"'_', tokens separated by '/'), got {namespace!r}")
        namespace = namespace.strip('/')
        position = entry['initial_position']
        if (not isinstance(position, list) or len(position) != 3 or
                not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                        for v in position)):
            raise RobotsFileError(f'{where}.initial_position: expected [x, y, z] in m (3 finite '
                                  f'numbers), got {position!r}')
        if not entry['enabled']:
            continue
        if namespace in namespaces:
            raise RobotsFileError(f'{where}.namespace: {namespace} is also robot {namespaces[namespace]}\'s')
        if uri in uris:
            raise RobotsFileError(f'{where}.uri: {uri} is also robot {uris[uri]}\'s')
        namespaces[namespace] = name
        uris[uri] = name
        robots.append(Robot(str(name), uri, namespace, [float(v) for v in position]))
    if not robots:
        raise RobotsFileError(f'{path}: no robot is enabled')
    return robots
