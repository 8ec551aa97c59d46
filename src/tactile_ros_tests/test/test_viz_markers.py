"""The visualization node (tactile_viz) in a SITL launch, and the simulator's sim/arena.

sitl_whisker with frame_prefix cf1/ (the default three-baffles scenario):
- /visualization/markers carries the whisker contacts once the whiskers touch a baffle:
  reliable MarkerArrays whose ADD markers are in frames tf2 resolves from map (the contact
  frame is the prefixed odometry frame cf1/odom), namespaced and with the input's stamp;
- /sim/arena is latched: a subscriber that joins seconds later gets the arena (a DELETEALL,
  then one CUBE per wall in frame map), as RViz started after the simulator does;
- /visualization and its grids are in the graph: /gpis/mean_grid and /gpis/variance_grid
  are offered transient local (latched) as OccupancyGrid.

Needs visualization_msgs in the ROS 2 installation (the Kilted toolchain with the
ros-visualization-msgs wheel; without it tactile_viz builds no component): skipped otherwise.
The frame check needs tf2_ros (the Kilted extras overlay).
"""

from __future__ import annotations

import pytest

from launch_check import Graph, Launch, HAVE_TF2

try:
    import visualization_msgs.msg  # noqa: F401
    HAVE_VIZ = True
except ImportError:
    HAVE_VIZ = False

needs_viz = pytest.mark.skipif(
    not HAVE_VIZ, reason='no visualization_msgs in this ROS 2 installation: no tactile_viz component, no sim/arena')


def launch_common():
    import importlib.util
    from launch_check import WORKSPACE
    spec = importlib.util.spec_from_file_location('launch_common', WORKSPACE / 'launch' / 'launch_common.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_viz_launch_helper_is_empty_without_the_component(monkeypatch):
    """Where tactile_viz registered no component (built without visualization_msgs), the
    sitl_* launches get no visualization node (and a warning) instead of a load failure
    that would stop them."""
    import os
    prefixes = [p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep)
                if p and os.path.basename(p.rstrip('/')) != 'tactile_viz']
    monkeypatch.setenv('AMENT_PREFIX_PATH', os.pathsep.join(prefixes))
    assert launch_common().visualization_nodes() == []


@needs_viz
def test_viz_launch_helper_loads_the_component_where_installed():
    nodes = launch_common().visualization_nodes()
    assert [(n.package[0].text, n.node_plugin[0].text) for n in nodes] == [
        ('tactile_viz', 'tactile_viz::VisualizationComponent')]


@pytest.fixture(scope='module')
def whisker_cf1(tmp_path_factory):
    log = tmp_path_factory.mktemp('viz') / 'sitl_whisker.log'
    with Launch('sitl_whisker.launch.py', ['frame_prefix:=cf1/'], log) as launch, Graph('viz_probe') as g:
        g.wait_for_nodes(['/tactile_sim', '/visualization'], launch)
        yield launch, g


@needs_viz
def test_viz_sim_arena_is_latched_for_a_late_subscriber(whisker_cf1):
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from visualization_msgs.msg import Marker, MarkerArray
    launch, g = whisker_cf1
    g.spin_until(lambda: g.node.count_publishers('/sim/arena') > 0, 30.0, 'a publisher of /sim/arena', launch)
    g.spin(3.0)  # joins late
    got = []
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    sub = g.node.create_subscription(MarkerArray, '/sim/arena', got.append, qos)
    try:
        g.spin_until(lambda: got, 30.0, 'the latched /sim/arena', launch)
    finally:
        g.node.destroy_subscription(sub)
    markers = got[-1].markers
    assert markers[0].action == Marker.DELETEALL
    walls = [m for m in markers[1:] if m.ns == 'arena_walls']
    assert len(walls) >= 3, [(m.ns, m.id) for m in markers]  # three baffles at least
    assert all(m.type == Marker.CUBE and m.header.frame_id == 'map' for m in walls)
    assert sorted(m.id for m in walls) == list(range(len(walls)))  # stable ids: the wall indices


@needs_viz
def test_viz_grids_are_offered_latched(whisker_cf1):
    from rclpy.qos import DurabilityPolicy
    launch, g = whisker_cf1
    for topic in ('/gpis/mean_grid', '/gpis/variance_grid'):
        g.spin_until(lambda t=topic: g.node.count_publishers(t) > 0, 30.0, f'a publisher of {topic}', launch)
        infos = g.node.get_publishers_info_by_topic(topic)
        assert [i.topic_type for i in infos] == ['nav_msgs/msg/OccupancyGrid'], infos
        assert infos[0].qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL, infos[0].qos_profile


@needs_viz
def test_viz_markers_of_the_whisker_contacts_in_frames_that_resolve(whisker_cf1):
    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy
    from visualization_msgs.msg import Marker, MarkerArray
    launch, g = whisker_cf1
    g.spin_until(lambda: g.node.count_publishers('/visualization/markers') > 0, 30.0,
                 'a publisher of /visualization/markers', launch)
    info = g.node.get_publishers_info_by_topic('/visualization/markers')[0]
    assert info.topic_type == 'visualization_msgs/msg/MarkerArray'
    assert info.qos_profile.reliability == ReliabilityPolicy.RELIABLE
    assert info.qos_profile.durability == DurabilityPolicy.VOLATILE
    got = []
    sub = g.node.create_subscription(MarkerArray, '/visualization/markers', got.append, 10)
    if HAVE_TF2:
        from tf2_ros import Buffer, TransformListener
        buffer = Buffer()
        listener = TransformListener(buffer, g.node, spin_thread=False)  # noqa: F841
    try:
        # The FSM hovers to initialise TDORC, then flies at 0.2 m/s to the first baffle.
        g.spin_until(lambda: any(m.action == Marker.ADD for a in got for m in a.markers), 120.0,
                     'whisker contact markers on /visualization/markers', launch)
        adds = [m for a in got for m in a.markers if m.action == Marker.ADD]
        assert {m.ns for m in adds} <= {'whisker_contacts', 'collisions'}, {m.ns for m in adds}
        contacts = [m for m in adds if m.ns == 'whisker_contacts']
        assert contacts, [(m.ns, m.id) for m in adds]
        for m in contacts:
            assert m.type == Marker.SPHERE_LIST and m.id in (0, 1) and m.points
            assert m.header.frame_id == 'cf1/odom', m.header.frame_id
            assert m.header.stamp.sec > 0 or m.header.stamp.nanosec > 0  # the input's (simulated) stamp
        if HAVE_TF2:
            from rclpy.time import Time
            for frame in {m.header.frame_id for m in adds}:
                g.spin_until(lambda f=frame: buffer.can_transform('map', f, Time()), 30.0,
                             f'tf2: map -> {frame}', launch)
    finally:
        g.node.destroy_subscription(sub)
