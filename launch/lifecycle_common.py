"""Shared by the launch files of the hardware nodes (radio, sitl, bench_rig; loaded by path,
as they are): the lifecycle of crazyflie_bridge and whisker_driver.

Where the ROS 2 installation has rclcpp_lifecycle, those packages build their components as
managed (lifecycle) nodes (share/<package>/component_kind says "lifecycle"; READMEs
"Lifecycle"). They are loaded unconfigured; here the launch configures them (opens the
device: the bridge connects, the driver opens its serial port) and, only once a node has
reached `inactive`, activates it (starts streaming) unless `activate:=false`, which leaves
them configured for the operator to check first:

    ros2 lifecycle get /crazyflie_bridge          # inactive: the radio is up
    ros2 lifecycle set /crazyflie_bridge activate # streams (nothing flies until takeoff)
    ros2 lifecycle get /cf1/crazyflie_bridge      # under namespace:=cf1 or a robots file

A failed configure (no Crazyradio, nothing answering at the URI, a missing serial device) is
logged by the node with the device and the reason, and it stays `unconfigured`; the launch
keeps running so that the operator can fix it and configure again (`ros2 lifecycle set
<node> configure`). Where the components are plain nodes (no rclcpp_lifecycle) none of this
applies: they open and stream when loaded, and a failure stops the launch
(launch_common.stop_on_load_failure).
"""

import os
import threading

from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
import launch.logging


def is_lifecycle(package: str) -> bool:
    """Whether `package`'s component was built as a lifecycle node."""
    from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
    try:
        path = os.path.join(get_package_share_directory(package), 'component_kind')
    except PackageNotFoundError:
        return False
    try:
        with open(path) as f:
            return f.read().strip() == 'lifecycle'
    except OSError:
        return False  # built before component_kind existed: a plain node


def activate_argument():
    return DeclareLaunchArgument(
        'activate', default_value='true', choices=['true', 'false'],
        description='lifecycle nodes (where rclcpp_lifecycle is installed): true activates each '
                    'hardware node once it is configured (inactive); false leaves it inactive '
                    '(device open, not streaming) for `ros2 lifecycle set <node> activate`. '
                    'Nothing flies either way until takeoff (or autostart)')


SERVICE_WAIT_S = 120.0  # a node's lifecycle services appear once its container loaded it


def _change_state(node, fqn, transition_id, context, logger):
    """Calls <fqn>/change_state; waits for the service (at most SERVICE_WAIT_S) and the
    answer until the launch shuts down. Returns the response's success (None when the
    launch shut down first or the service never appeared)."""
    import time
    from lifecycle_msgs.srv import ChangeState
    client = node.create_client(ChangeState, fqn + '/change_state')
    try:
        end = time.monotonic() + SERVICE_WAIT_S
        while not client.wait_for_service(timeout_sec=1.0):
            if context.is_shutdown:
                return None
            if time.monotonic() > end:
                logger.error(f'{fqn}/change_state not offered within {SERVICE_WAIT_S:.0f} s: '
                             'the node was not loaded; its lifecycle is left alone')
                return None
        request = ChangeState.Request()
        request.transition.id = transition_id
        done = threading.Event()
        future = client.call_async(request)
        future.add_done_callback(lambda _: done.set())
        while not done.wait(1.0):
            if context.is_shutdown:
                future.cancel()
                return None
        if future.exception() is not None:
            logger.error(f'{fqn}: change_state failed: {future.exception()}')
            return False
        return bool(future.result().success)
    finally:
        node.destroy_client(client)


def _manage(context, node_names, activate, logger):
    from launch_ros.ros_adapters import get_ros_node
    from lifecycle_msgs.msg import Transition
    node = get_ros_node(context)
    for fqn in node_names:
        ok = _change_state(node, fqn, Transition.TRANSITION_CONFIGURE, context, logger)
        if ok is None:
            if context.is_shutdown:
                return
            continue
        if not ok:
            logger.error(
                f'{fqn}: configure failed (its error above): it stays unconfigured; fix the device, '
                f'then `ros2 lifecycle set {fqn} configure` and `ros2 lifecycle set {fqn} activate`')
            continue
        if not activate:
            logger.info(f'{fqn}: inactive (device open, not streaming): check it, then '
                        f'`ros2 lifecycle set {fqn} activate`')
            continue
        ok = _change_state(node, fqn, Transition.TRANSITION_ACTIVATE, context, logger)
        if ok is None:
            if context.is_shutdown:
                return
            continue
        if ok:
            logger.info(f'{fqn}: active')
        else:
            logger.error(f'{fqn}: activate failed (its error above): it stays inactive')


def resolve_node_name(name, namespace):
    """A node name of `node_names` as fully qualified: a relative one is in `namespace`."""
    if name.startswith('/'):
        return name
    ns = namespace.strip().strip('/')
    return '/' + (ns + '/' if ns else '') + name


def manage_lifecycle(node_names):
    """The action to add to a launch description: configures each node of `node_names` (fully
    qualified, or relative: in the launch argument `namespace`, the root without one) once its
    lifecycle services are up, then activates it if it reached `inactive` and the launch
    argument `activate` is true (activate_argument())."""
    def start(context):
        logger = launch.logging.get_logger('lifecycle')
        activate = LaunchConfiguration('activate').perform(context) == 'true'
        namespace = context.launch_configurations.get('namespace', '')
        names = [resolve_node_name(n, namespace) for n in node_names]
        context.add_completion_future(context.asyncio_loop.run_in_executor(
            None, _manage, context, names, activate, logger))
        return None
    return OpaqueFunction(function=start)
