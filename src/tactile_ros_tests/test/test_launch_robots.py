"""The robots file of radio.launch.py (config/crazyflies.yaml, in the style of Crazyswarm2's):
launch_common.load_robots reads and checks it, and `radio.launch.py robots:=FILE` starts one
bridge + whisker pipeline per enabled robot, each under its namespace on its own link --
here two firmware emulators (crazyflie_sim_server) on two UDP ports."""

from __future__ import annotations

import importlib.util

import pytest

from launch_check import CONFIG_DIR, LAUNCH_DIR, Graph, Launch, unique_port
from test_launch_operator import SimServer


def launch_common():
    spec = importlib.util.spec_from_file_location('launch_common', LAUNCH_DIR / 'launch_common.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


ROBOT = "    enabled: true\n    uri: {uri}\n    initial_position: [0.0, 0.0, 0.0]\n"


def robots_file(tmp_path, text):
    path = tmp_path / 'crazyflies.yaml'
    path.write_text(text)
    return path


def test_shipped_robots_file_loads():
    robots = launch_common().load_robots(str(CONFIG_DIR / 'crazyflies.yaml'))
    assert [(r.name, r.namespace, r.uri, r.initial_position) for r in robots] == [
        ('cf1', 'cf1', 'radio://0/80/2M/E7E7E7E7E7', [0.0, 0.0, 0.0])]  # cf2 is disabled


def test_robots_file_namespace_defaults_to_the_name_and_disabled_robots_are_skipped(tmp_path):
    path = robots_file(tmp_path, 'robots:\n  cf7:\n' + ROBOT.format(uri='udp://127.0.0.1:19900')
                       + '  cf8:\n    enabled: false\n    uri: udp://127.0.0.1:19900\n'
                       '    initial_position: [1, 2, 0]\n'
                       '  left:\n' + ROBOT.format(uri='usb://0') + '    namespace: /team/a/\n')
    robots = launch_common().load_robots(str(path))
    assert [(r.name, r.namespace) for r in robots] == [('cf7', 'cf7'), ('left', 'team/a')]


@pytest.mark.parametrize('text, error', [
    ('robots: {}\n', "expected a map 'robots'"),
    ('robots:\n  cf1:\n    uri: radio://0/80/2M\n    initial_position: [0, 0, 0]\n', 'robots.cf1.enabled: missing'),
    ('robots:\n  cf1:\n    enabled: yes please\n    uri: radio://0/80/2M\n    initial_position: [0, 0, 0]\n',
     "robots.cf1.enabled: expected true or false, got 'yes please'"),
    ('robots:\n  cf1:\n' + ROBOT.format(uri='tcp://10.0.0.1'), "robots.cf1.uri: expected a Crazyflie URI"),
    ('robots:\n  cf1:\n    enabled: true\n    uri: radio://0/80/2M\n    initial_position: [0, .nan, 0]\n',
     'robots.cf1.initial_position: expected [x, y, z] in m'),
    ('robots:\n  cf1:\n    enabled: true\n    uri: radio://0/80/2M\n    initial_position: [0, 0]\n',
     'robots.cf1.initial_position: expected [x, y, z] in m'),
    ('robots:\n  cf1:\n' + ROBOT.format(uri='radio://0/80/2M') + '    namespace: cf-1\n',
     "robots.cf1.namespace: expected a ROS namespace"),
    ('robots:\n  cf1:\n' + ROBOT.format(uri='radio://0/80/2M') + '    initial_pose: [0, 0, 0]\n',
     'robots.cf1: unknown key initial_pose'),
    ('robots:\n  a:\n' + ROBOT.format(uri='radio://0/80/2M/E7') + '    namespace: cf1\n'
     '  b:\n' + ROBOT.format(uri='radio://0/80/2M/E8') + '    namespace: cf1\n',
     "robots.b.namespace: cf1 is also robot a's"),
    ('robots:\n  a:\n' + ROBOT.format(uri='radio://0/80/2M/E7') + '  b:\n' + ROBOT.format(uri='radio://0/80/2M/E7'),
     "robots.b.uri: radio://0/80/2M/E7 is also robot a's"),
    ('robots:\n  a:\n    enabled: false\n    uri: radio://0/80/2M\n    initial_position: [0, 0, 0]\n',
     'no robot is enabled'),
])
def test_robots_file_errors_name_the_file_robot_and_key(tmp_path, text, error):
    common = launch_common()
    path = robots_file(tmp_path, text)
    with pytest.raises(common.RobotsFileError) as e:
        common.load_robots(str(path))
    assert str(e.value).startswith(f'{path}: ') and error in str(e.value), str(e.value)


def test_radio_launch_starts_one_namespaced_bridge_per_enabled_robot(tmp_path):
    ports = [unique_port(19850 + 300), unique_port(19850 + 400)]
    servers = [SimServer(p, tmp_path / f'sim_server_{p}.log') for p in ports]
    path = robots_file(tmp_path, 'robots:\n'
                       + ''.join(f'  cf{i + 1}:\n' + ROBOT.format(uri=f'udp://127.0.0.1:{p}')
                                 .replace('[0.0, 0.0, 0.0]', '[1.5, -0.5, 0.0]' if i else '[0.0, 0.0, 0.0]')
                                 for i, p in enumerate(ports))
                       + '  cf3:\n    enabled: false\n    uri: udp://127.0.0.1:9\n'
                       '    initial_position: [2.0, 0.0, 0.0]\n')
    from nav_msgs.msg import Odometry
    from rclpy.qos import qos_profile_sensor_data
    launch = Launch('radio.launch.py', [f'robots:={path}'], tmp_path / 'launch.log')
    try:
        with Graph() as g:
            g.wait_for_nodes([f'/cf{i}/{n}' for i in (1, 2) for n in
                              ('radio_container', 'crazyflie_bridge', 'whisker/left/tdorc_filter',
                               'tactile_depth', 'whisker_fsm')], launch, timeout=90.0)
            odom = {1: [], 2: []}
            for i in (1, 2):
                # best effort: the bridge publishes its odometry with the sensor-data QoS
                g.node.create_subscription(Odometry, f'/cf{i}/odom', lambda m, i=i: odom[i].append(m),
                                           qos_profile_sensor_data)
            g.spin_until(lambda: all(len(v) >= 5 for v in odom.values()), 60,
                         'odometry of both robots', launch)
            names = g.node_names()
            topics = set(g.topic_types())
            # Each robot's initial_position reached its bridge (its map -> odom translation).
            positions = {i: list(g.get_parameters(f'/cf{i}/crazyflie_bridge', ['initial_position'])
                                 ['initial_position']) for i in (1, 2)}
    finally:
        launch.stop()
        outputs = [s.stop() for s in servers]
    assert positions == {1: [0.0, 0.0, 0.0], 2: [1.5, -0.5, 0.0]}, positions
    assert not any(n.startswith('/cf3/') for n in names), sorted(names)  # disabled
    assert not {'/crazyflie_bridge', '/whisker_fsm'} & names, sorted(names)
    assert not {'/odom', '/cmd_hover', '/whisker/left/pressure'} & topics, sorted(topics)
    for i in (1, 2):
        assert {f'/cf{i}/odom', f'/cf{i}/cmd_hover', f'/cf{i}/whisker/left/pressure', f'/cf{i}/status'} <= topics
    for port, out in zip(ports, outputs):
        assert f'listening udp://' in out and str(port) in out
