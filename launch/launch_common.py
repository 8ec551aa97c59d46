"""Shared by the launch files of this directory (loaded by path, as they are):
a composable node that cannot start stops the whole launch, and its parameter error
names the file (or the launch argument) the bad value came from.

The component container only logs a failed load (a bad parameter, a missing Crazyradio,
a serial device that is not there) and keeps running the rest of the graph, which then
waits for that node's topics for ever. Here the launch ends instead, with exit code 1 and
the component's own message (it names the node, the parameter or device and the reason).
"""

import os

from launch.actions import RegisterEventHandler
from launch.event_handlers import OnProcessIO
from launch.substitution import Substitution
from launch.substitutions import LaunchConfiguration, PythonExpression, TextSubstitution
from launch_ros.parameter_descriptions import ParameterValue

LOAD_FAILURE = 'Component constructor threw an exception'


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


def frame_prefix_argument():
    """The launch argument frame_prefix of the vehicle launch files (sitl_*, sitl, radio):
    goes before every frame name the simulator or the bridge stamps and broadcasts but map
    ('' or ending in '/': cf1/ gives cf1/base_link; tactile_common/frames.hpp)."""
    from launch.actions import DeclareLaunchArgument
    return DeclareLaunchArgument(
        'frame_prefix', default_value='',
        description="prefix of the vehicle's frames ('' or ending in '/', e.g. cf1/)")


def prefixed_frame(frame):
    """A frame-name parameter value behind the launch argument frame_prefix, e.g. for
    xplorer_force_est's world_frame: 'odom' gives cf1/odom with frame_prefix:=cf1/."""
    return ParameterValue([LaunchConfiguration('frame_prefix'), frame], value_type=str)


def simulator_node(wait_for_publisher, extra_arguments):
    """The SITL's simulator component of the sitl_* launch files (arguments scenario, seed,
    real_time_factor, wait_for_subscribers, frame_prefix). It starts the world once `wait_for_publisher`
    (the graph's controller output, loaded last) has a publisher, and holds t = 0 until the
    topics of wait_for_subscribers have a subscriber in another process (a recorder;
    comma-separated, '' starts at once)."""
    from launch_ros.descriptions import ComposableNode
    return ComposableNode(
        package='tactile_sim', plugin='tactile_sim::TactileSimComponent', name='tactile_sim',
        parameters=parameters(
            {'scenario': LaunchConfiguration('scenario'),
             'seed': LaunchConfiguration('seed'),
             'real_time_factor': ParameterValue(
                 LaunchConfiguration('real_time_factor'), value_type=float),
             'wait_for_publisher': wait_for_publisher,
             'frame_prefix': ParameterValue(LaunchConfiguration('frame_prefix'), value_type=str),
             'wait_for_subscribers': ParameterValue(
                 LaunchConfiguration('wait_for_subscribers'), value_type=str)}),
        extra_arguments=extra_arguments)
