"""Frames per REP 105 and the robot description during SITL launches (issue 35 items 1, 2).

- tf2 (rclpy Buffer + TransformListener) resolves map -> <prefix>whisker_left through
  map -> odom (static identity), odom -> base_link (the simulator's or the bridge's
  dynamic transform of its odometry) and base_link -> whisker_left (static, from the
  vehicle geometry), with and without frame_prefix;
- ground truth has its own pair (ground_truth/odom -> ground_truth/base_link), not the
  estimate's;
- robot_description (std_msgs/String, reliable, transient local) reaches a subscriber that
  joins late, parses as URDF, has the expected links, and its fixed joints are the static
  transforms tf2 resolves.

The transforms need tf2_ros (the Kilted toolchain's extras overlay); where the ROS 2
installation has none (the Jazzy toolchain here) the components broadcast none, those tests
are skipped saying why, and the robot_description tests still run.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import pytest
import yaml

from launch_check import CONFIG_DIR, Graph, Launch, unique_port, HAVE_TF2, needs_tf2

WHISKER_LINKS = {'base_link', 'whisker_left', 'whisker_right', 'imu_link', 'tof_down', 'flow'}
XPLORER_LINKS = {'base_link', 'imu_link'} | {f'{k}{i}' for i in range(4) for k in ('arm', 'rotor')} | {
    f'arm{i}_imu' for i in range(4)}


def late_robot_description(g: Graph, launch: Launch, late_s: float = 3.0, timeout: float = 30.0) -> str:
    """The URDF on /robot_description, subscribed `late_s` after the publisher appeared."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String
    g.spin_until(lambda: g.node.count_publishers('/robot_description') > 0, timeout,
                 'a publisher of /robot_description', launch)
    g.spin(late_s)
    got = []
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    sub = g.node.create_subscription(String, '/robot_description', got.append, qos)
    try:
        g.spin_until(lambda: got, timeout, 'the latched /robot_description', launch)
    finally:
        g.node.destroy_subscription(sub)
    return got[-1].data


def urdf_joints(urdf: str, robot: str, links: set[str], prefix: str) -> dict:
    """Parses the URDF; checks its name and links; returns {child: (parent, xyz, rpy)}."""
    root = ET.fromstring(urdf)
    assert root.tag == 'robot' and root.get('name') == robot, urdf[:300]
    names = {link.get('name') for link in root.findall('link')}
    assert {prefix + n for n in links} <= names, f'links {sorted(names)}'
    joints = {}
    for j in root.findall('joint'):
        assert j.get('type') == 'fixed', j.get('name')
        origin = j.find('origin')
        joints[j.find('child').get('link')] = (
            j.find('parent').get('link'), [float(v) for v in origin.get('xyz').split()],
            [float(v) for v in origin.get('rpy').split()])
    return joints


def quaternion(rpy):
    """x, y, z, w of URDF roll/pitch/yaw (fixed axes)."""
    r, p, y = (a / 2 for a in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


class Tf:
    """A tf2 Buffer fed by a TransformListener on the probe node."""

    def __init__(self, g: Graph):
        from tf2_ros import Buffer, TransformListener
        self.g = g
        self.buffer = Buffer()
        self.listener = TransformListener(self.buffer, g.node, spin_thread=False)

    def lookup(self, target: str, source: str, launch: Launch, timeout: float = 30.0):
        from rclpy.time import Time
        self.g.spin_until(lambda: self.buffer.can_transform(target, source, Time()), timeout,
                          f'tf2: {target} -> {source}', launch)
        return self.buffer.lookup_transform(target, source, Time())

    def parents(self) -> dict[str, str]:
        return {f: v['parent'] for f, v in (yaml.safe_load(self.buffer.all_frames_as_yaml()) or {}).items()}


def check_static_joints_in_tf(tf: Tf, joints: dict, launch: Launch):
    """Every fixed joint of the URDF is the transform tf2 resolves between its links."""
    for child, (parent, xyz, rpy) in joints.items():
        t = tf.lookup(parent, child, launch).transform
        got = [t.translation.x, t.translation.y, t.translation.z]
        assert got == pytest.approx(xyz, abs=1e-6), f'{parent} -> {child}: {got} != URDF {xyz}'
        q = [t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w]
        want = quaternion(rpy)
        assert q == pytest.approx(want, abs=1e-6) or q == pytest.approx([-v for v in want], abs=1e-6), (
            f'{parent} -> {child}: rotation {q} != URDF rpy {rpy}')


@pytest.fixture(scope='class')
def whisker_cf1(tmp_path_factory):
    """sitl_whisker with frame_prefix cf1/ (the default three-baffles scenario), shared by
    the tests of one class and stopped after them (before the other launches)."""
    log = tmp_path_factory.mktemp('frames') / 'sitl_whisker.log'
    with Launch('sitl_whisker.launch.py', ['frame_prefix:=cf1/'], log) as launch, Graph('frames_probe') as g:
        g.wait_for_nodes(['/tactile_sim'], launch)
        yield launch, g


class TestSitlWhiskerWithFramePrefix:
    def test_robot_description_of_the_whiskered_crazyflie_reaches_a_late_subscriber(self, whisker_cf1):
        launch, g = whisker_cf1
        joints = urdf_joints(late_robot_description(g, launch), 'whiskered_crazyflie', WHISKER_LINKS, 'cf1/')
        assert joints['cf1/whisker_left'][0] == 'cf1/base_link'
        # 000's mounting (tactile_sim CrazyflieParams): bases 5 cm apart, 5 cm ahead, pitched up 45 deg.
        assert joints['cf1/whisker_left'][1] == pytest.approx([0.05, 0.025, 0.0])
        assert joints['cf1/whisker_right'][1] == pytest.approx([0.05, -0.025, 0.0])
        assert joints['cf1/whisker_left'][2] == pytest.approx([0.0, -math.pi / 4, 0.0])

    @needs_tf2
    def test_tf_resolves_map_to_the_prefixed_whisker_and_keeps_ground_truth_apart(self, whisker_cf1):
        launch, g = whisker_cf1
        tf = Tf(g)
        tf.lookup('map', 'cf1/whisker_left', launch)
        tf.lookup('map', 'cf1/ground_truth/base_link', launch)
        parents = tf.parents()
        assert parents['cf1/base_link'] == 'cf1/odom'
        assert parents['cf1/odom'] == 'map'
        assert parents['cf1/ground_truth/base_link'] == 'cf1/ground_truth/odom'
        assert parents['cf1/ground_truth/odom'] == 'map'
        unprefixed = sorted(f for f in parents if not f.startswith('cf1/'))
        assert unprefixed == [], f'frames without the prefix: {unprefixed}'
        # The static joints of the URDF are the transforms tf2 resolves.
        urdf = late_robot_description(g, launch, late_s=0.0)
        check_static_joints_in_tf(tf, urdf_joints(urdf, 'whiskered_crazyflie', WHISKER_LINKS, 'cf1/'), launch)


def test_sitl_xplorer_robot_description_and_frames_without_prefix(tmp_path):
    scenario = CONFIG_DIR / 'scenarios' / 'xplorer_box.yaml'
    with Launch('sitl_xplorer.launch.py', [f'scenario:={scenario}'], tmp_path / 'launch.log') as launch, \
            Graph('frames_probe') as g:
        g.wait_for_nodes(['/tactile_sim'], launch)
        joints = urdf_joints(late_robot_description(g, launch), 'xplorer', XPLORER_LINKS, '')
        assert joints['rotor0'][0] == 'arm0' and joints['arm0_imu'][0] == 'arm0'
        if not HAVE_TF2:
            pytest.skip('robot_description checked; no tf2_ros here for the transforms')
        tf = Tf(g)
        for frame in ('rotor0', 'arm3_imu', 'imu_link', 'ground_truth/base_link'):
            tf.lookup('map', frame, launch)
        check_static_joints_in_tf(tf, joints, launch)


@needs_tf2
def test_sitl_bridge_broadcasts_the_prefixed_tree_of_the_crazyflie(tmp_path):
    """The bridge (sitl.launch.py: the simulated Crazyflie over UDP) broadcasts map -> odom,
    odom -> base_link from the firmware's estimate and the whisker frames, all behind
    frame_prefix, and publishes the Crazyflie's URDF."""
    with Launch('sitl.launch.py', [f'port:={unique_port(19950)}', 'seed:=5', 'frame_prefix:=cf2/'],
                tmp_path / 'launch.log') as launch, Graph('frames_probe') as g:
        g.wait_for_nodes(['/crazyflie_bridge'], launch)
        joints = urdf_joints(late_robot_description(g, launch), 'whiskered_crazyflie', WHISKER_LINKS, 'cf2/')
        tf = Tf(g)
        tf.lookup('map', 'cf2/whisker_right', launch, timeout=60.0)
        assert tf.parents()['cf2/base_link'] == 'cf2/odom'
        check_static_joints_in_tf(tf, joints, launch)
