"""Two whiskered Crazyflies in SITL on one ROS domain (issue 35 item 4): sitl_whisker.launch.py
twice, namespace:=cf1 and namespace:=cf2, with different seeds, at the same time.

Every topic of the nodes is relative, so each drone's graph lives under its namespace
(/cf1/whisker/depth, /cf1/cmd_hover, and its simulated time on /cf1/clock); nothing of
theirs is at the root. Checked while both fly:

- each drone's nodes are in its namespace and none at the root;
- every topic each node publishes or subscribes is under its own namespace (apart from
  the graph's own /rosout and /parameter_events): no message of one drone can reach the
  other's nodes; /cf1/cmd_hover has cf1's FSM as its only publisher and cf1's simulator
  as its only subscriber (and likewise cf2);
- no /cmd_hover, /odom, /whisker/depth or /clock at the root.

Then each drone's flight (recorded from its namespace, evaluated by `tactile evaluate`)
has the outcome of `tactile sim` of its seed in process: the target reached and no
collision where that flight reaches it. Two FSMs reading each other's depth or
odometry, or two simulators stepping on each other's setpoints or clocks, would not
fly the course.
"""

from __future__ import annotations

import json
import time

import pytest

pytestmark = pytest.mark.e2e

from e2e import WORKSPACE, sim_in_process, tactile
from launch_check import Graph, Launch
from sitl_recorder import GRAPH_TOPICS, SIM_TOPICS, Recorder

SCENARIO = WORKSPACE / 'config' / 'scenarios' / 'whisker_three_baffles_fsm.yaml'
SEEDS = {'cf1': 1, 'cf2': 2}  # the end-to-end seeds of test_e2e_whisker.py
FACTOR = 2.0
GRAPH_TOPICS_OF_ROS = {'/rosout', '/parameter_events'}
NODES = ['tactile_sim', 'whisker/left/tdorc_filter', 'whisker/right/tdorc_filter',
         'tactile_depth', 'whisker_fsm']


def node_topics(g: Graph, fqn: str) -> set[str]:
    ns, _, name = fqn.rpartition('/')
    ns = ns or '/'
    pubs = g.node.get_publisher_names_and_types_by_node(name, ns)
    subs = g.node.get_subscriber_names_and_types_by_node(name, ns)
    return {t for t, _ in pubs} | {t for t, _ in subs}


def test_two_namespaced_drones_fly_without_cross_talk(tmp_path):
    in_process = {ns: sim_in_process(SCENARIO, seed, tmp_path / f'in_process_{ns}')
                  for ns, seed in SEEDS.items()}
    # The simulator holds t = 0 until each recorder's subscriptions matched (relative: the
    # simulator resolves them in its namespace).
    wait = ','.join(t.lstrip('/') for t in SIM_TOPICS['whisker_fsm'])
    recorders = {ns: Recorder(tmp_path / ns / 'bag', GRAPH_TOPICS['whisker_fsm'], namespace=ns)
                 for ns in SEEDS}
    launches = {}
    done = {}
    try:
        for ns, seed in SEEDS.items():
            launches[ns] = Launch('sitl_whisker.launch.py', [
                f'namespace:={ns}', f'scenario:={SCENARIO}', f'seed:={seed}',
                f'real_time_factor:={FACTOR}', f'wait_for_subscribers:={wait}'],
                tmp_path / f'launch_{ns}.log')
        with Graph() as g:
            for ns, launch in launches.items():
                g.wait_for_nodes([f'/{ns}/{n}' for n in NODES] + [f'/{ns}/sitl_whisker_container'],
                                 launch, timeout=120.0)
            g.spin(2.0)  # discovery of every endpoint
            names = g.node_names()
            at_root = {'/' + n for n in NODES} & names
            assert not at_root, f'nodes at the root: {sorted(at_root)}'
            for ns in SEEDS:
                for n in NODES:
                    foreign = {t for t in node_topics(g, f'/{ns}/{n}')
                               if not t.startswith(f'/{ns}/') and t not in GRAPH_TOPICS_OF_ROS}
                    assert not foreign, f'/{ns}/{n} uses topics outside /{ns}: {sorted(foreign)}'
                pubs = {(i.node_namespace, i.node_name)
                        for i in g.node.get_publishers_info_by_topic(f'/{ns}/cmd_hover')}
                subs = {(i.node_namespace, i.node_name)
                        for i in g.node.get_subscriptions_info_by_topic(f'/{ns}/cmd_hover')}
                assert pubs == {(f'/{ns}', 'whisker_fsm')}, pubs
                assert subs == {(f'/{ns}', 'tactile_sim')}, subs
            topics = set(g.topic_types())
            root = {'/cmd_hover', '/odom', '/whisker/depth', '/clock', '/sim/done'} & topics
            assert not root, f'topics at the root: {sorted(root)}'
        duration = 75.0
        deadline = time.monotonic() + 120.0 + 6.0 * duration / FACTOR  # two flights share the cores
        while time.monotonic() < deadline and len(done) < len(SEEDS):
            for ns, rec in recorders.items():
                if ns not in done and rec.wait_done(0.5):
                    done[ns] = True
            if not all(launch.running() for launch in launches.values()):
                break
    finally:
        for rec in recorders.values():
            rec.stop()
        for launch in launches.values():
            launch.stop()
    for ns in SEEDS:
        assert done.get(ns), (f'no /{ns}/sim/done; launch output:\n'
                              f'{launches[ns].output()[-3000:]}')
    for ns, seed in SEEDS.items():
        out = tmp_path / ns
        tactile('evaluate', out / 'bag', '--scenario', SCENARIO, '--seed', seed, '--out', out)
        dds = json.loads((out / 'metrics.json').read_text())
        ref = in_process[ns]
        print(f'{ns} (seed {seed}): success {dds["success"]} (in process {ref["success"]}), '
              f'reached {dds["fsm"]["reached_target"]}, collisions {dds["collisions"]}')
        assert dds['seed'] == seed
        assert dds['success'] == ref['success'], (ns, dds['fsm'], dds['collision_events'])
        assert dds['fsm']['reached_target'] == ref['fsm']['reached_target'], ns
