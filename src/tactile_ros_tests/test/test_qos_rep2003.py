"""QoS per REP 2003 (issue 35, item 6) on the SITL launches: a subscriber as RViz, Foxglove
and Nav2 make one by default -- reliable, volatile, keep last 5 -- receives every documented
topic that flows during a few seconds of each SITL launch (the topics, types and rates the
launch tests document: test_launch_sitl_*.py), and every publisher of a documented topic
is reliable; the maps are reliable and transient local (a late RViz gets the last one).

A best-effort publisher (SensorDataQoS, what the drivers and the simulator used before)
does not match a reliable subscription at all: such a subscriber gets nothing.

/clock is left out: rclcpp's ClockQoS (best effort, depth 1) is what every ROS 2 node's
time source subscribes with, and RViz takes the time from it the same way."""

from __future__ import annotations

import time

import pytest

import test_launch_sitl_explore as explore
import test_launch_sitl_localization as localization
import test_launch_sitl_wall_effect as wall_effect
import test_launch_sitl_whisker as whisker
import test_launch_sitl_xplorer as xplorer
from launch_check import CONFIG_DIR, Graph, Launch, message_class

# Latched topics (tactile_common/ros_qos.hpp latched_publisher): reliable + transient local.
MAPS = {'/gpis/map', '/gpis/target', '/xplorer/map', '/sim/done'}
# Published by rclcpp's time source QoS, not ours (module docstring).
NOT_OURS = {'/clock'}


def rviz_qos():
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=5, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


def publisher_qos_problems(g: Graph, topics) -> list[str]:
    """Every publisher of `topics` that is not reliable (or, for a map, not transient local)."""
    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy
    problems = []
    for topic in sorted(set(topics) - NOT_OURS):
        g.wait_for_topic(topic)
        for info in g.node.get_publishers_info_by_topic(topic):
            qos = info.qos_profile
            who = f'{topic} from {info.node_namespace.rstrip("/")}/{info.node_name}'
            if qos.reliability != ReliabilityPolicy.RELIABLE:
                problems.append(f'{who}: {qos.reliability.name}, REP 2003 wants RELIABLE')
            if topic in MAPS and qos.durability != DurabilityPolicy.TRANSIENT_LOCAL:
                problems.append(f'{who}: {qos.durability.name}, a map is TRANSIENT_LOCAL')
    return problems


def receive_reliably(g: Graph, topics: dict[str, str], seconds: float, launch: Launch) -> dict[str, int]:
    """Subscribes to every topic ({topic: type}) with the RViz QoS; spins until each has
    3 messages or `seconds` pass. The counts."""
    counts = {t: 0 for t in topics}
    subs = []
    for topic, type_name in topics.items():
        def on_message(_msg, t=topic):
            counts[t] += 1
        subs.append(g.node.create_subscription(message_class(type_name), topic, on_message, rviz_qos()))
    try:
        end = time.monotonic() + seconds
        while time.monotonic() < end and min(counts.values()) < 3 and launch.running():
            g.spin(0.1)
    finally:
        for s in subs:
            g.node.destroy_subscription(s)
    return counts


CASES = {
    'whisker': ('sitl_whisker.launch.py', ['scenario:=' + str(CONFIG_DIR / 'scenarios' / 'whisker_three_baffles_fsm.yaml')],
                whisker.NODES, whisker.RATE_TOPICS, whisker.EVENT_TOPICS),
    'explore': ('sitl_explore.launch.py', ['scenario:=' + str(CONFIG_DIR / 'scenarios' / 'whisker_room_exit_gpis.yaml')],
                explore.NODES, explore.RATE_TOPICS, explore.EVENT_TOPICS),
    'xplorer': ('sitl_xplorer.launch.py', ['scenario:=' + str(CONFIG_DIR / 'scenarios' / 'xplorer_box_traversal.yaml'),
                                           'mission:=static_wrench'],
                xplorer.NODES, xplorer.RATE_TOPICS, xplorer.EVENT_TOPICS),
    'wall_effect': ('sitl_wall_effect.launch.py', ['scenario:=' + str(CONFIG_DIR / 'scenarios' / 'ducted_track_0.yaml')],
                    wall_effect.COMMON + ['/wall_effect_nav'], wall_effect.RATE_TOPICS, wall_effect.EVENT_TOPICS),
}


@pytest.mark.parametrize('case', sorted(CASES))
def test_a_reliable_subscriber_receives_every_documented_topic(case, tmp_path):
    launch_file, args, nodes, rate_topics, event_topics = CASES[case]
    if case == 'xplorer':
        args = args + [f'ply_file:={tmp_path / "map.ply"}']
    with Launch(launch_file, args, tmp_path / 'launch.log') as launch, Graph('rviz_like_probe') as g:
        g.wait_for_nodes(nodes, launch)
        problems = publisher_qos_problems(g, list(rate_topics) + list(event_topics))
        counts = receive_reliably(g, {t: v[0] for t, v in rate_topics.items()}, 30.0, launch)
        out = launch.output()
    silent = [f'{t}: {n} messages' for t, n in counts.items() if n < 3]
    assert not problems and not silent, (
        'publisher QoS: ' + '; '.join(problems) + '\nreliable subscriber got too few: ' + '; '.join(silent) +
        f'\nlaunch output:\n{out[-3000:]}')


def test_localization_results_reach_a_reliable_subscriber(tmp_path):
    # The node alone, driven by the test as a stage (simulator:=false): with the simulator it
    # would also pair the simulator's samples, stamped on another clock, with the test's.
    with Launch('sitl_localization.launch.py', ['simulator:=false'], tmp_path / 'launch.log') as launch, \
            Graph('rviz_like_probe') as g:
        g.wait_for_nodes(localization.NODES, launch)
        from geometry_msgs.msg import PoseArray
        from tactile_msgs.msg import LocalizationResult
        results, sets = [], []
        g.node.create_subscription(LocalizationResult, '/whisker/localization', results.append, rviz_qos())
        g.node.create_subscription(PoseArray, '/whisker/pose_set', sets.append, rviz_qos())
        stamps = localization.drive(g, 2.0)
        # Outputs still in flight when the drive ends (a loaded machine) are waited for.
        g.spin_until(lambda: len(results) >= 0.9 * len(stamps) and len(sets) >= len(results), 10.0,
                     f'results and pose sets of {len(stamps)} samples', launch)
        g.spin(0.5)
        problems = publisher_qos_problems(g, ['/whisker/localization', '/whisker/pose_set'])
    assert not problems, problems
    assert len(results) >= 0.9 * len(stamps) and len(sets) == len(results), (len(results), len(sets), len(stamps))
