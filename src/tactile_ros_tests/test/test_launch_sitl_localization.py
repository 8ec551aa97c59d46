"""launch/sitl_localization.launch.py: whisker_localization (paper 002).

- with simulator:=false the node is alone in its container and the test is its stage
  driver: it publishes the base odometry and the base moment (no contact) at 20 Hz and
  reads one result and one pose set per accepted sample;
- by default the launch starts the whisker stage simulator (tactile_sim) with it, on
  simulated time: the test moves the stage onto the pin with a position setpoint and reads
  results stamped on the simulator's clock, a contact among them."""

from __future__ import annotations

import time

from launch_check import CONFIG_DIR, Graph, Launch, assert_rate

NODES = ['/whisker_localization_container', '/whisker_localization']
RATE_HZ = 20.0


def drive(g: Graph, seconds: float) -> list[int]:
    """Publishes odometry + moment pairs with equal stamps; returns the stamps [ns]."""
    from geometry_msgs.msg import WrenchStamped
    from nav_msgs.msg import Odometry
    odom_pub = g.node.create_publisher(Odometry, '/odom', 10)
    moment_pub = g.node.create_publisher(WrenchStamped, '/whisker/base_wrench', 10)
    g.spin(1.0)  # discovery of the node's subscriptions
    stamps = []
    t0 = time.time_ns()
    for k in range(int(seconds * RATE_HZ)):
        ns = t0 + int(k * 1e9 / RATE_HZ)
        odom = Odometry()
        odom.header.stamp.sec, odom.header.stamp.nanosec = divmod(ns, 1_000_000_000)
        odom.header.frame_id = 'map'
        odom.pose.pose.position.x = 0.001 * k
        odom.pose.pose.orientation.w = 1.0
        moment = WrenchStamped()
        moment.header.stamp = odom.header.stamp
        moment.wrench.torque.z = 0.0
        odom_pub.publish(odom)
        g.spin(0.002)
        moment_pub.publish(moment)
        stamps.append(ns)
        g.spin(1.0 / RATE_HZ)
    return stamps


def test_sitl_localization_results_per_moment_sample(tmp_path):
    with Launch('sitl_localization.launch.py', ['possibilistic:=true', 'simulator:=false'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        g.wait_for_nodes(NODES, launch)
        params = g.get_parameters('/whisker_localization', ['possibilistic', 'beam.youngs_modulus'])
        from geometry_msgs.msg import PoseArray
        from tactile_msgs.msg import LocalizationResult
        results, sets = [], []
        g.node.create_subscription(LocalizationResult, '/whisker/localization',
                                   lambda m: results.append(m), 100)
        g.node.create_subscription(PoseArray, '/whisker/pose_set', lambda m: sets.append(m), 100)
        stamps = drive(g, 2.0)
        # Outputs still in flight when the drive ends (a loaded machine) are waited for.
        g.spin_until(lambda: len(results) >= 0.9 * len(stamps) and len(sets) >= len(results), 10.0,
                     f'results and pose sets of {len(stamps)} samples', launch)
        g.spin(0.5)
        types = dict(g.node.get_topic_names_and_types())
    assert types['/whisker/localization'] == ['tactile_msgs/msg/LocalizationResult']
    assert types['/whisker/pose_set'] == ['geometry_msgs/msg/PoseArray']
    # One result per sample (the moment after its odometry), at the stage's rate and stamps.
    got = [m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for m in results]
    assert len(got) >= 0.9 * len(stamps) and set(got) <= set(stamps), (len(got), len(stamps))
    assert len(sets) == len(results)
    assert all(m.header.frame_id == 'map' and m.base_moment == 0.0 and not m.contact_valid
               for m in results)
    from launch_check import TopicSample
    assert_rate(TopicSample('/whisker/localization', '', messages=results), RATE_HZ)
    # The launch argument and the YAML reached the node.
    assert params == {'possibilistic': True, 'beam.youngs_modulus': 52.0e9}


def test_sitl_localization_bad_parameter_type_stops_the_launch_naming_the_file(tmp_path):
    bad = tmp_path / 'bad.yaml'
    text = (CONFIG_DIR / 'whisker_localization.yaml').read_text()
    assert 'beam.youngs_modulus: 52.0e+9' in text
    # YAML 1.1 (the launch system's parser) reads 52.0e9 as a string.
    bad.write_text(text.replace('beam.youngs_modulus: 52.0e+9', 'beam.youngs_modulus: 52.0e9'))
    with Launch('sitl_localization.launch.py', [f'params:={bad}', 'simulator:=false'],
                tmp_path / 'launch.log') as launch:
        code = launch.wait_exit(60)
        out = launch.output()
    assert code not in (None, 0), f'launch exit {code}:\n{out[-3000:]}'
    assert 'a node failed to start' in out
    assert 'beam.youngs_modulus' in out and 'expected a double' in out and 'YAML 1.1' in out, out[-3000:]
    assert f'/whisker_localization from {bad}: whisker_localization.ros__parameters.beam.youngs_modulus: ' \
        'is a string (52.0e9), expected a double' in out, out[-3000:]


def test_sitl_localization_starts_its_simulator(tmp_path):
    """The default launch flies the whisker stage simulator with the node: the stage, moved
    by a position setpoint so that the pin bends the whisker, gives base moments, and the
    node's results are stamped on the simulator's clock (simulated seconds from 0, not wall
    time), a valid contact among them."""
    from geometry_msgs.msg import PoseStamped
    from tactile_msgs.msg import LocalizationResult
    with Launch('sitl_localization.launch.py', ['real_time_factor:=4.0'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        g.wait_for_nodes(['/whisker_localization_container', '/tactile_sim', '/whisker_localization'],
                         launch)
        results = []
        g.node.create_subscription(LocalizationResult, '/whisker/localization',
                                   lambda m: results.append(m), 1000)
        setpoint = g.node.create_publisher(PoseStamped, '/cmd_position', 10)
        # whisker_stage_table1: base at (0, 0.02), whisker along +x, the pin at (0.1, 0):
        # a base at (0.05, -0.002) touches it 50 mm along the whisker, 2 mm deflected.
        target = PoseStamped()
        target.header.frame_id = 'odom'
        target.pose.position.x, target.pose.position.y = 0.05, -0.002
        target.pose.orientation.w = 1.0
        end = time.monotonic() + 60.0
        while time.monotonic() < end and not any(m.contact_valid for m in results):
            setpoint.publish(target)
            g.spin(0.2)
        sim = g.get_parameters('/tactile_sim', ['scenario'])
        out = launch.output()
    assert sim['scenario'] == str(CONFIG_DIR / 'scenarios' / 'whisker_stage_table1.yaml')
    assert results, out[-3000:]
    stamps = [m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in results]
    assert max(stamps) < 600.0, max(stamps)  # simulated time, not the wall clock's ~1.7e9 s
    assert any(m.contact_valid for m in results), (len(results), out[-3000:])
