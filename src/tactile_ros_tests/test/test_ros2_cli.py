"""The ground station's `ros2` verbs against a launched graph (issue 34, item 4): what a user
types to look at the SITL whisker graph (`ros2 topic info -v`, `ros2 topic hz`, `ros2 param
get`, `ros2 node info`) sees the documented publishers, QoS, rates and parameter values.

The verbs come from the Kilted toolchain's extras overlay (../shared/ros2/build_ros2_extras.sh);
where this ROS 2 installation has no `ros2 topic` / `ros2 param` (the Jazzy toolchain here) the
module is skipped with that reason."""

from __future__ import annotations

import re
import subprocess
import time

import pytest
import yaml

from launch_check import CONFIG_DIR, Graph, Launch, check_graph


def _verb_available(verb: str) -> bool:
    try:
        r = subprocess.run(['ros2', verb, '--help'], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return r.returncode == 0


pytestmark = pytest.mark.skipif(
    not (_verb_available('topic') and _verb_available('param')),
    reason='no `ros2 topic` / `ros2 param` verbs in this ROS 2 installation (Kilted: '
           '../shared/ros2/build_ros2_extras.sh)')


def ros2(*args: str, timeout: float = 30.0) -> str:
    """`ros2 <args>` without the daemon (a fresh discovery per call); its output. Retried for
    up to 15 s while the graph has not been discovered yet."""
    end = time.monotonic() + 15.0
    while True:
        r = subprocess.run(['ros2', *args], capture_output=True, text=True, timeout=timeout)
        out = r.stdout + r.stderr
        if r.returncode == 0 or time.monotonic() > end:
            return out
        time.sleep(0.5)


def topic_hz(topic: str, seconds: float = 5.0) -> float:
    """The last `average rate` `ros2 topic hz` prints within `seconds` (wall clock)."""
    p = subprocess.Popen(['ros2', 'topic', 'hz', topic, '--window', '100'], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)
    try:
        out, _ = p.communicate(timeout=seconds)
    except subprocess.TimeoutExpired:
        p.terminate()
        out, _ = p.communicate(timeout=10)
    rates = re.findall(r'average rate: ([\d.]+)', out)
    assert rates, f'`ros2 topic hz {topic}` printed no rate in {seconds} s: {out[-2000:]}'
    return float(rates[-1])


def test_ros2_verbs_see_the_sitl_whisker_graph(tmp_path):
    scenario = CONFIG_DIR / 'scenarios' / 'whisker_three_baffles_fsm.yaml'
    with Launch('sitl_whisker.launch.py', [f'scenario:={scenario}', 'seed:=7'],
                tmp_path / 'launch.log') as launch, Graph() as g:
        check_graph(g, launch, ['/tactile_depth', '/whisker_fsm'], {}, {'/fsm_state': 'tactile_msgs/msg/FsmState'})

        # One publisher of the depth, tactile_depth's, reliable (REP 2003: drivers and estimators
        # publish reliable, subscribers take SensorDataQoS).
        info = ros2('topic', 'info', '-v', '/whisker/depth', '--no-daemon')
        assert 'Type: tactile_msgs/msg/TactileDepth' in info, info
        assert 'Publisher count: 1' in info, info
        pub = info.split('Subscription count')[0]
        assert re.search(r'Node name: tactile_depth', pub), info
        assert 'Reliability: RELIABLE' in pub, info   # tactile_common::data_publisher
        # The FSM's state is reliable (a bag or RViz must not miss a transition).
        state = ros2('topic', 'info', '-v', '/fsm_state', '--no-daemon')
        assert 'Reliability: RELIABLE' in state.split('Subscription count')[0], state

        # The FSM's setpoints at its 50 Hz timer (wall clock), as `ros2 topic hz` measures them.
        hz = topic_hz('/cmd_hover')
        assert 50.0 * 0.75 < hz < 50.0 * 1.25, hz

        # Parameter values as config/ gives them, through `ros2 param get`.
        cfg = yaml.safe_load((CONFIG_DIR / 'tdorc_filter.yaml').read_text())['/**/tdorc_filter']['ros__parameters']
        got = ros2('param', 'get', '/whisker/right/tdorc_filter', 'window')
        assert re.search(rf'value is: {cfg["window"]}\b', got), got
        sim_time = ros2('param', 'get', '/whisker_fsm', 'use_sim_time')
        assert 'Boolean value is: True' in sim_time, sim_time

        # `ros2 node info` lists the FSM's inputs and outputs.
        # Each call discovers the graph afresh (--no-daemon): a call can return before the
        # node's writers were discovered (seen once: every subscription listed, no
        # publisher, not even /rosout), so it is asked again for up to 15 s.
        wanted = ('/whisker/depth', '/odom', '/cmd_hover', '/fsm_state')
        end = time.monotonic() + 15.0
        while True:
            node = ros2('node', 'info', '/whisker_fsm', '--no-daemon')
            if all(t in node for t in wanted) or time.monotonic() > end:
                break
            time.sleep(0.5)
        for topic in wanted:
            assert topic in node, node
        assert launch.running(), launch.output()[-3000:]
