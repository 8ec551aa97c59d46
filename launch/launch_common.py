"""Shared by the launch files of this directory (loaded by path, as they are):
a composable node that cannot start stops the whole launch.

The component container only logs a failed load (a bad parameter, a missing Crazyradio,
a serial device that is not there) and keeps running the rest of the graph, which then
waits for that node's topics for ever. Here the launch ends instead, with exit code 1 and
the component's own message (it names the node, the parameter or device and the reason).
"""

from launch.actions import RegisterEventHandler
from launch.event_handlers import OnProcessIO

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

