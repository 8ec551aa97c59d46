"""The shipped RViz configurations (config/rviz/*.rviz) and Foxglove layout
(config/foxglove/*.json) against the running launches (issue 35 item 3).

- Each vehicle launch file's rviz_config argument defaults to its shipped file, and
  rviz:=true where rviz2 is not installed ends the launch saying so, before any node starts.
- Each .rviz file parses; every display is of a class this test knows the message type
  of; its topic is relative (RViz started in the launch's namespace shows that vehicle) and
  its QoS is one RViz offers; the fixed frame is map.
- During the SITL launch the file belongs to, every display's topic is published with the
  display's message type and reaches a subscriber with the display's own QoS (a late one
  for the transient-local ones: the maps, the arena, robot_description), and tf2 resolves
  the fixed frame to every frame those messages are in (headers, odometry child frames,
  each marker's frame, the robot description's links): what RViz needs to draw them.
- The Foxglove layout's topics are topics of the SITL launches with the types its panels
  read.

The frame check needs tf2_ros (the Kilted toolchain's extras overlay); where the
installation has none (the Jazzy toolchain here) the live tests are skipped saying why.
"""

from __future__ import annotations

import json
import re
import subprocess
import time
import xml.etree.ElementTree as ET

import pytest
import yaml

from launch_check import CONFIG_DIR, LAUNCH_DIR, Graph, Launch, message_class, needs_tf2, unique_port

RVIZ_DIR = CONFIG_DIR / 'rviz'
FOXGLOVE_DIR = CONFIG_DIR / 'foxglove'

# rviz_default_plugins display class -> the message type it subscribes.
DISPLAY_TYPES = {
    'rviz_default_plugins/Odometry': 'nav_msgs/msg/Odometry',
    'rviz_default_plugins/MarkerArray': 'visualization_msgs/msg/MarkerArray',
    'rviz_default_plugins/PointCloud2': 'sensor_msgs/msg/PointCloud2',
    'rviz_default_plugins/Map': 'nav_msgs/msg/OccupancyGrid',
    'rviz_default_plugins/PoseArray': 'geometry_msgs/msg/PoseArray',
    'rviz_default_plugins/Pose': 'geometry_msgs/msg/PoseStamped',
    'rviz_default_plugins/Range': 'sensor_msgs/msg/Range',
    'rviz_default_plugins/Wrench': 'geometry_msgs/msg/WrenchStamped',
    'rviz_default_plugins/RobotModel': 'std_msgs/msg/String',
}
NO_TOPIC = {'rviz_default_plugins/Grid', 'rviz_default_plugins/TF'}

# The vehicle launch files, the configuration each ships, and how the live test runs it.
LAUNCH_CONFIGS = {
    'sitl_whisker.launch.py': 'whisker',
    'sitl_explore.launch.py': 'explore',
    'sitl_xplorer.launch.py': 'xplorer',
    'sitl_wall_effect.launch.py': 'wall_effect',
    'sitl_localization.launch.py': 'localization',
    'sitl.launch.py': 'crazyflie',
    'radio.launch.py': 'crazyflie',
}
LIVE = {  # config -> launch file, arguments
    'whisker': ('sitl_whisker.launch.py', ['real_time_factor:=2.0']),
    'explore': ('sitl_explore.launch.py', ['real_time_factor:=2.0']),
    'xplorer': ('sitl_xplorer.launch.py', ['real_time_factor:=2.0']),
    'wall_effect': ('sitl_wall_effect.launch.py', ['real_time_factor:=2.0']),
    'localization': ('sitl_localization.launch.py', []),
    'crazyflie': ('sitl.launch.py', ['autostart:=true']),
}


class Display:
    def __init__(self, d: dict):
        self.cls, self.name = d['Class'], d.get('Name', '')
        topic = d.get('Topic') or d.get('Description Topic') or {}
        self.topic = topic.get('Value')
        self.reliability = topic.get('Reliability Policy', 'Reliable')
        self.durability = topic.get('Durability Policy', 'Volatile')
        self.depth = int(topic.get('Depth', 5))

    def qos(self):
        from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
        return QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=self.depth,
            reliability={'Reliable': ReliabilityPolicy.RELIABLE,
                         'Best Effort': ReliabilityPolicy.BEST_EFFORT}[self.reliability],
            durability={'Volatile': DurabilityPolicy.VOLATILE,
                        'Transient Local': DurabilityPolicy.TRANSIENT_LOCAL}[self.durability])


def displays(tree: dict) -> list[Display]:
    """Every display of a parsed .rviz file, those inside groups too."""
    out = []
    for d in tree.get('Displays') or []:
        if d.get('Class') == 'rviz_common/Group':
            out += displays(d)
        else:
            out.append(Display(d))
    return out


def load(name: str):
    tree = yaml.safe_load((RVIZ_DIR / f'{name}.rviz').read_text())
    manager = tree['Visualization Manager']
    return manager['Global Options']['Fixed Frame'], displays(manager)


def test_every_vehicle_launch_defaults_to_its_shipped_rviz_config():
    for launch_file, name in LAUNCH_CONFIGS.items():
        out = subprocess.run(['ros2', 'launch', str(LAUNCH_DIR / launch_file), '--show-args'],
                             capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stderr
        m = re.search(r"'rviz_config':\n.*\n\s+\(default: '([^']+)'\)", out.stdout)
        assert m, f'{launch_file}: no rviz_config argument:\n{out.stdout}'
        assert m.group(1) == str(RVIZ_DIR / f'{name}.rviz'), (launch_file, m.group(1))
        assert "'rviz':" in out.stdout, launch_file
    assert {f.stem for f in RVIZ_DIR.glob('*.rviz')} == set(LAUNCH_CONFIGS.values())


@pytest.mark.parametrize('name', sorted(set(LAUNCH_CONFIGS.values())))
def test_rviz_config_parses_with_known_displays_and_relative_topics(name):
    fixed, ds = load(name)
    assert fixed == 'map'
    assert ds, name
    for d in ds:
        assert d.cls in DISPLAY_TYPES or d.cls in NO_TOPIC, f'{name}: display {d.name}: unknown class {d.cls}'
        if d.cls in NO_TOPIC:
            continue
        assert d.topic and not d.topic.startswith('/'), f'{name}: display {d.name}: topic {d.topic!r} not relative'
        d.qos()  # a reliability/durability RViz offers


def rviz2_installed() -> bool:
    from ament_index_python.packages import PackageNotFoundError, get_package_prefix
    try:
        get_package_prefix('rviz2')
        return True
    except PackageNotFoundError:
        return False


@pytest.mark.skipif(rviz2_installed(), reason='rviz2 is installed: rviz:=true would open its window')
def test_rviz_true_without_rviz2_stops_the_launch_saying_so(tmp_path):
    with Launch('sitl_whisker.launch.py', ['rviz:=true'], tmp_path / 'launch.log') as launch:
        code = launch.wait_exit(60)
        out = launch.output()
    assert code not in (None, 0), out[-3000:]
    assert 'rviz:=true but the package rviz2 is not installed' in out, out[-3000:]
    assert 'component_container' not in out, 'a node started before the error:\n' + out[-3000:]


def frames_of(type_name: str, msg) -> set[str]:
    """The frames RViz needs transforms for to draw `msg`."""
    if type_name == 'std_msgs/msg/String':  # robot_description: every link
        return {link.get('name') for link in ET.fromstring(msg.data).findall('link')}
    if type_name == 'visualization_msgs/msg/MarkerArray':
        return {m.header.frame_id for m in msg.markers if m.action != 3}  # 3: DELETEALL
    frames = {msg.header.frame_id}
    if type_name == 'nav_msgs/msg/Odometry':
        frames.add(msg.child_frame_id)
    return frames


@needs_tf2
@pytest.mark.parametrize('name', sorted(LIVE))
def test_rviz_displays_get_their_topics_and_frames_resolve(name, tmp_path):
    from tf2_ros import Buffer, TransformListener
    from rclpy.time import Time
    fixed, ds = load(name)
    launch_file, args = LIVE[name]
    if launch_file == 'sitl.launch.py':
        args = args + [f'port:={unique_port()}']
    topics = [d for d in ds if d.cls in DISPLAY_TYPES]
    with Launch(launch_file, args, tmp_path / 'launch.log') as launch, Graph('rviz_like_probe') as g:
        buffer = Buffer()
        TransformListener(buffer, g.node, spin_thread=False)
        got: dict[str, list] = {d.name: [] for d in topics}
        for d in topics:
            g.node.create_subscription(message_class(DISPLAY_TYPES[d.cls]), '/' + d.topic,
                                       got[d.name].append, d.qos())
        end = time.monotonic() + 120.0
        while time.monotonic() < end and not all(got.values()) and launch.running():
            g.spin(0.1)
        types = dict(g.node.get_topic_names_and_types())
        missing = {d.topic: types.get('/' + d.topic) for d in topics if not got[d.name]}
        assert not missing, (f'{name}.rviz: no message within 120 s on {missing} (topic: the types '
                             f'published under that name)\nlaunch output:\n{launch.output()[-3000:]}')
        frames = set()
        for d in topics:
            assert types.get('/' + d.topic) == [DISPLAY_TYPES[d.cls]], (d.name, d.topic, types.get('/' + d.topic))
            for msg in got[d.name]:
                frames |= frames_of(DISPLAY_TYPES[d.cls], msg)
        assert '' not in frames, f'{name}.rviz: a message with an empty frame_id'
        g.spin_until(lambda: all(buffer.can_transform(fixed, f, Time()) for f in frames), 30.0,
                     f'{name}.rviz: tf2 {fixed} -> each of {sorted(frames)} (unresolved: '
                     f'{sorted(f for f in frames if not buffer.can_transform(fixed, f, Time()))})', launch)


def foxglove_topics(layout: dict) -> dict[str, str]:
    """{topic: the type its panel reads} of a Foxglove layout: the 3D panels' topics, the
    plots' and state transitions' message paths (`/topic.field`), the raw messages'."""
    out = {}
    for panel_id, cfg in layout['configById'].items():
        kind = panel_id.split('!')[0]
        if kind == '3D':
            for topic in cfg.get('topics', {}):
                out[topic] = '3D'
        elif kind in ('Plot', 'StateTransitions'):
            for path in cfg.get('paths', []):
                out[path['value'].split('.')[0]] = kind
        elif kind == 'RawMessages':
            out[cfg['topicPath'].split('.')[0]] = kind
    return out


def test_foxglove_layout_names_topics_of_the_sitl_launches():
    layouts = sorted(FOXGLOVE_DIR.glob('*.json'))
    assert layouts, FOXGLOVE_DIR
    documented = set()
    for name in LIVE:
        documented |= {'/' + d.topic for d in load(name)[1] if d.topic}
    # The whisker chain's and the FSMs' topics that Foxglove plots (test_launch_sitl_*.py).
    documented |= {'/whisker/depth', '/whisker/left/signal', '/whisker/right/signal', '/fsm_state',
                   '/xplorer/fsm_state', '/wall_effect/estimate', '/cmd_hover', '/tf', '/tf_static'}
    for path in layouts:
        layout = json.loads(path.read_text())
        for topic in foxglove_topics(layout):
            assert topic in documented, f'{path.name}: {topic} is not a topic of the SITL launches'
