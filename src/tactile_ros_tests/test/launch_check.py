"""Helpers of the launch tests (test_launch_*.py): start a launch file of the workspace as
`ros2 launch` in its own process group, look at the ROS graph from an rclpy node, count the
messages of a topic over a window and ask nodes for their parameters.

Rates are measured on the topic's own clock: the header stamps where the message has a
header (simulated time for the SITL launches, so the rate does not depend on how fast a
loaded machine runs the simulator), else the wall-clock receipt times. Subscriptions are
best effort (compatible with the SensorDataQoS and the reliable publishers alike) with a
deep queue.
"""

from __future__ import annotations

import importlib
import os
import signal
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

WORKSPACE = Path(__file__).resolve().parents[3]
LAUNCH_DIR = WORKSPACE / 'launch'
CONFIG_DIR = WORKSPACE / 'config'

# Rate tolerance: the simulator's and the bench rig's schedules are exact on their own
# clocks; what moves a measured rate is best-effort samples lost on a loaded 2-core CI
# runner and the jitter of wall timers (controllers) measured on receipt times over a
# few seconds. +-25% still tells every documented rate from its neighbours (a wrong
# rate_hz, a timer on the wrong clock or a doubled publisher is off by 2x or more).
RATE_TOLERANCE = 0.25


try:
    import tf2_ros  # noqa: F401
    HAVE_TF2 = True
except ImportError:
    HAVE_TF2 = False

# The transforms need tf2_ros (the Kilted toolchain's extras overlay); without it the
# components are built without /tf and /tf_static and the tests that look them up skip.
needs_tf2 = pytest.mark.skipif(
    not HAVE_TF2, reason='no tf2_ros in this ROS 2 installation (the Jazzy toolchain here): '
                         'the components are built without /tf and /tf_static')


def message_class(type_name: str):
    pkg, _, name = type_name.split('/')
    return getattr(importlib.import_module(f'{pkg}.msg'), name)


class Launch:
    """`ros2 launch launch/<file> args...` in its own process group, output to a log file;
    stop() interrupts the group (as Ctrl-C does) and kills it if it does not end. With
    `package`, `ros2 launch <package> <file>` (the installed file) in the directory `cwd`."""

    def __init__(self, launch_file: str, args=(), log_path: Path | None = None,
                 package: str | None = None, cwd: Path | None = None):
        self.log_path = Path(log_path) if log_path else Path(f'/tmp/{launch_file}.{os.getpid()}.log')
        self._log = open(self.log_path, 'w')
        where = [package, launch_file] if package else [str(LAUNCH_DIR / launch_file)]
        self.proc = subprocess.Popen(
            ['ros2', 'launch', *where, *map(str, args)],
            stdout=self._log, stderr=subprocess.STDOUT, start_new_session=True,
            # Files a launch writes relative to its directory (sitl_xplorer's ply_file) go
            # beside its log (a test's tmp_path), never into the source tree.
            env=os.environ.copy(), cwd=cwd if cwd is not None else self.log_path.parent)

    def output(self) -> str:
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors='replace')

    def running(self) -> bool:
        return self.proc.poll() is None

    def wait_exit(self, timeout: float) -> int | None:
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            return None

    def stop(self) -> int:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGINT)  # the process group we started
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        self._log.close()
        return self.proc.returncode

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


@dataclass
class TopicSample:
    topic: str
    type_name: str
    messages: list = field(default_factory=list)
    receipt_s: list = field(default_factory=list)

    def stamps_s(self):
        return [m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in self.messages]

    def rate_hz(self, clock: str = 'stamp') -> float:
        """Messages per second over the window: between the first and last header stamp
        (clock='stamp') or receipt time (clock='wall')."""
        t = self.stamps_s() if clock == 'stamp' else self.receipt_s
        if len(t) < 3 or t[-1] <= t[0]:
            return 0.0
        return (len(t) - 1) / (t[-1] - t[0])


class Graph:
    """An rclpy node of its own context for looking at the graph of a launch."""

    def __init__(self, name: str = 'launch_test_probe'):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.context.try_shutdown()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def spin(self, seconds: float):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=min(0.05, max(0.0, end - time.monotonic())))

    def node_names(self) -> set[str]:
        return {(ns.rstrip('/') + '/' + n) for n, ns in self.node.get_node_names_and_namespaces()}

    def wait_for_nodes(self, names, launch: Launch, timeout: float = 60.0) -> set[str]:
        """Waits until every fully qualified name in `names` is in the graph; fails with the
        missing ones and the launch output when the launch ends or the time runs out."""
        want = set(names)
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            have = self.node_names()
            if want <= have:
                return have
            if not launch.running():
                break
            self.spin(0.2)
        pytest.fail(f'nodes missing: {sorted(want - self.node_names())}; graph: '
                    f'{sorted(self.node_names())}; launch exit {launch.proc.poll()}; output:\n'
                    f'{launch.output()[-4000:]}')

    def topic_types(self) -> dict[str, list[str]]:
        return dict(self.node.get_topic_names_and_types())

    def wait_for_topic(self, topic: str, timeout: float = 30.0) -> str:
        """The single type the graph gives `topic` (waits for a publisher)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.node.count_publishers(topic) > 0:
                types = self.topic_types().get(topic, [])
                assert len(types) == 1, f'{topic} has types {types}'
                return types[0]
            self.spin(0.1)
        pytest.fail(f'no publisher of {topic} within {timeout} s; topics: {sorted(self.topic_types())}')

    def sample(self, topics: dict[str, str], window_s: float, settle_s: float = 0.0,
               min_messages: int = 3, timeout: float = 30.0) -> dict[str, TopicSample]:
        """Checks that each topic of {topic: expected type} has that type in the graph, then
        records every topic for `window_s` wall seconds (after `settle_s` of discarded
        messages). Waits up to `timeout` for each topic's first `min_messages`."""
        from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
        out = {}
        subs = []
        for topic, want in topics.items():
            got = self.wait_for_topic(topic)
            assert got == want, f'{topic}: type {got} in the graph, documented {want}'
            s = TopicSample(topic, got)
            out[topic] = s
            qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                             reliability=ReliabilityPolicy.BEST_EFFORT)
            subs.append(self.node.create_subscription(
                message_class(got), topic,
                lambda m, s=s: (s.messages.append(m), s.receipt_s.append(time.monotonic())), qos))
        try:
            if settle_s > 0:
                self.spin(settle_s)
                for s in out.values():
                    s.messages.clear()
                    s.receipt_s.clear()
            end = time.monotonic() + timeout
            while time.monotonic() < end and any(len(s.messages) < min_messages for s in out.values()):
                self.spin(0.1)
            for s in out.values():
                s.messages.clear()
                s.receipt_s.clear()
            self.spin(window_s)
        finally:
            for sub in subs:
                self.node.destroy_subscription(sub)
        return out

    def call(self, srv_type, name: str, request, timeout: float = 10.0):
        """Calls service `name` of type `srv_type` with `request`; returns the response."""
        client = self.node.create_client(srv_type, name)
        try:
            assert client.wait_for_service(timeout_sec=timeout), f'{name} not offered within {timeout} s'
            future = client.call_async(request)
            end = time.monotonic() + timeout
            while not future.done() and time.monotonic() < end:
                self.executor.spin_once(timeout_sec=0.05)
            assert future.done(), f'{name} did not answer within {timeout} s'
            return future.result()
        finally:
            self.node.destroy_client(client)

    def spin_until(self, condition, timeout: float, what: str, launch: Launch | None = None):
        """Spins until condition() is true; fails naming `what` (and the launch output)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if condition():
                return
            if launch is not None and not launch.running():
                break
            self.spin(0.05)
        if condition():
            return
        out = f'; launch output:\n{launch.output()[-4000:]}' if launch is not None else ''
        pytest.fail(f'{what}: not within {timeout} s{out}')

    def get_parameters(self, node: str, names: list[str], timeout: float = 10.0) -> dict:
        """Values of `names` from `node`'s rcl_interfaces/GetParameters service."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python
        client = self.node.create_client(GetParameters, node + '/get_parameters')
        try:
            assert client.wait_for_service(timeout_sec=timeout), f'{node}/get_parameters not offered'
            future = client.call_async(GetParameters.Request(names=names))
            end = time.monotonic() + timeout
            while not future.done() and time.monotonic() < end:
                self.executor.spin_once(timeout_sec=0.05)
            assert future.done(), f'{node}/get_parameters did not answer within {timeout} s'
            return {n: parameter_value_to_python(v) for n, v in zip(names, future.result().values)}
        finally:
            self.node.destroy_client(client)


def assert_rate(sample: TopicSample, hz: float, clock: str = 'stamp', tol: float = RATE_TOLERANCE):
    rate = sample.rate_hz(clock)
    assert abs(rate - hz) <= tol * hz, (
        f'{sample.topic}: {rate:.1f} Hz over {len(sample.messages)} messages ({clock} clock), '
        f'documented {hz} Hz (+-{tol:.0%})')


def unique_port(base: int = 19850) -> int:
    """A UDP port of this test run's DDS domain, so parallel runs do not share a simulator."""
    return base + 200 + int(os.environ.get('ROS_DOMAIN_ID', '0'))


def check_graph(g: Graph, launch: Launch, nodes, rate_topics: dict, event_topics: dict | None = None,
                window_s: float = 3.0) -> dict[str, TopicSample]:
    """The common assertions of a launch test: every node of `nodes` is up; every topic of
    `event_topics` ({topic: type}, published on events, e.g. state transitions) has a
    publisher of that type; every topic of `rate_topics` ({topic: (type, hz, clock)}) has
    that type and flows at hz (+-RATE_TOLERANCE) on `clock` ('stamp' or 'wall') over
    `window_s` wall seconds. Returns the samples."""
    g.wait_for_nodes(nodes, launch)
    for topic, want in (event_topics or {}).items():
        got = g.wait_for_topic(topic)
        assert got == want, f'{topic}: type {got} in the graph, documented {want}'
    samples = g.sample({t: v[0] for t, v in rate_topics.items()}, window_s=window_s)
    failures = []
    for topic, (_, hz, clock) in rate_topics.items():
        try:
            assert_rate(samples[topic], hz, clock)
        except AssertionError as e:
            failures.append(str(e))
    assert not failures, '\n'.join(failures)
    return samples
