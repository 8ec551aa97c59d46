"""Records topics of a SITL flight over DDS into a rosbag2 (sqlite3) bag, for
`tactile evaluate BAG --scenario S --out DIR`.

The toolchain this workspace is tested with has no rosbag2, so this is a small recorder:
rclpy subscriptions with raw=True (the CDR bytes as they came over DDS, never
deserialized) written with the `rosbags` package. Each message is stored at its header
stamp (simulated time: every recorded type starts with a std_msgs/Header), so the bag's
timeline is the simulator's, as in the bags `tactile sim` writes. The recording ends
when the simulator publishes /sim/done (std_msgs/Bool, transient local) or at a timeout.

    python sitl_recorder.py --out bag --scenario-graph whisker_fsm --timeout 120

Topics per graph: GRAPH_TOPICS. Sensor topics are published reliable (REP 2003); the
subscriptions are best effort with a deep queue, as every sensor subscriber's (SensorDataQoS), and a sample lost anyway shows as a
lower count in the evaluated metrics' "topics" than in `tactile sim`'s.
"""

from __future__ import annotations

import argparse
import importlib
import struct
import sys
import threading
import time
from pathlib import Path

WORKSPACE = Path(__file__).resolve().parents[3]
MSG_DIR = WORKSPACE / 'src' / 'tactile_msgs' / 'msg'

# topic -> (type, reliable). Reliable where the publisher is reliable (state topics are
# published on transitions only: one lost message would be a lost transition).
GRAPH_TOPICS = {
    'whisker_fsm': {
        '/ground_truth/whisker/left/contact': ('tactile_msgs/msg/WhiskerGroundTruth', False),
        '/ground_truth/whisker/right/contact': ('tactile_msgs/msg/WhiskerGroundTruth', False),
        '/fsm_state': ('tactile_msgs/msg/FsmState', True),
        '/collisions': ('tactile_msgs/msg/CollisionEvent', False),
    },
    'xplorer': {
        '/odom': ('nav_msgs/msg/Odometry', False),
        '/xplorer/wrench_body': ('geometry_msgs/msg/WrenchStamped', False),
        '/arm_imu': ('tactile_msgs/msg/ArmImuArray', False),
        '/xplorer/fsm_state': ('tactile_msgs/msg/FsmState', True),
        '/collisions': ('tactile_msgs/msg/CollisionEvent', False),
    },
    'wall_effect': {
        '/ground_truth/wall': ('tactile_msgs/msg/WallEstimate', False),
        '/ground_truth/odom': ('nav_msgs/msg/Odometry', False),
        '/wall_effect/setpoint': ('nav_msgs/msg/Odometry', True),
        '/wall_effect/estimate': ('tactile_msgs/msg/WallEstimate', False),
        '/collisions': ('tactile_msgs/msg/CollisionEvent', False),
    },
}

# The simulator's topics among GRAPH_TOPICS that it publishes from t = 0: the simulator
# holds its first step until these have a subscriber in another process
# (launch argument wait_for_subscribers), so the recording starts at t = 0.
SIM_TOPICS = {
    'whisker_fsm': ['/ground_truth/whisker/left/contact', '/ground_truth/whisker/right/contact'],
    'xplorer': ['/odom', '/arm_imu'],
    'wall_effect': ['/ground_truth/wall', '/ground_truth/odom'],
}

DONE_TOPIC = '/sim/done'


def typestore():
    """The Kilted types plus tactile_msgs from the .msg files of this workspace."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    store = get_typestore(Stores.ROS2_KILTED)
    types = {}
    for f in sorted(MSG_DIR.glob('*.msg')):
        types.update(get_types_from_msg(f.read_text(), f'tactile_msgs/msg/{f.stem}'))
    store.register(types)
    return store


def header_stamp_ns(data: bytes) -> int:
    """builtin_interfaces/Time at the start of a CDR message (after the 4-byte
    encapsulation header): int32 sec, uint32 nanosec, in the encapsulation's byte order."""
    if len(data) < 12:
        raise ValueError(f'CDR message of {len(data)} bytes has no header stamp')
    order = '<' if data[1] & 1 else '>'
    sec, nanosec = struct.unpack_from(order + 'iI', data, 4)
    return sec * 1_000_000_000 + nanosec


def message_class(type_name: str):
    pkg, _, name = type_name.split('/')
    return getattr(importlib.import_module(f'{pkg}.msg'), name)


class Recorder:
    """Subscribes to `topics` ({topic: (type, reliable)}) and writes a bag at `out`
    until /sim/done or stop(). With `namespace` ('cf1') it records one vehicle of several:
    /cf1/<topic> until /cf1/sim/done, written under <topic> (the root names `tactile
    evaluate` reads, as in a bag of `tactile sim`)."""

    def __init__(self, out: Path, topics: dict, namespace: str = ''):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile,
                               ReliabilityPolicy)
        from rosbags.rosbag2 import Writer
        from std_msgs.msg import Bool

        self.out = Path(out)
        self.topics = dict(topics)
        self.counts = {t: 0 for t in topics}
        self.done = threading.Event()
        # The messages as received (topic, stamp, CDR bytes), written to the bag in stop().
        # The bag is not written from the callbacks: the sqlite3 connection the rosbags
        # writer opens may only be used by the thread that opened it (sqlite3's
        # check_same_thread), and the callbacks run in the spin thread; a write there
        # raised ProgrammingError, which ended the spin thread silently, so /sim/done was
        # never seen. Keeping the callbacks to an append also keeps the best-effort
        # queues drained while the flight runs.
        self._messages: list[tuple[str, int, bytes]] = []
        self._error: BaseException | None = None
        self._Writer = Writer
        self._context = rclpy.Context()
        rclpy.init(context=self._context)
        self._node = rclpy.create_node('sitl_recorder', context=self._context)
        prefix = '/' + namespace.strip('/') if namespace.strip('/') else ''
        for topic, (typ, reliable) in topics.items():
            qos = QoSProfile(
                history=HistoryPolicy.KEEP_LAST, depth=1000,
                reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                durability=DurabilityPolicy.VOLATILE)
            self._node.create_subscription(
                message_class(typ), prefix + topic, lambda data, t=topic: self._on_message(t, data),
                qos, raw=True)
        done_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                              reliability=ReliabilityPolicy.RELIABLE,
                              durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self._node.create_subscription(Bool, prefix + DONE_TOPIC, self._on_done, done_qos)
        self._executor = SingleThreadedExecutor(context=self._context)
        self._executor.add_node(self._node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        try:
            while not self._stop.is_set() and self._context.ok():
                self._executor.spin_once(timeout_sec=0.1)
        except BaseException as e:  # re-raised by wait_done() / stop(), never lost
            self._error = e
            self.done.set()

    def _on_message(self, topic: str, data: bytes):
        self._messages.append((topic, header_stamp_ns(data), bytes(data)))
        self.counts[topic] += 1

    def _on_done(self, msg):
        if msg.data:
            self.done.set()

    def wait_done(self, timeout: float) -> bool:
        done = self.done.wait(timeout)
        if self._error is not None:
            raise RuntimeError(f'sitl_recorder: the spin thread failed: {self._error!r}') from self._error
        return done

    def stop(self):
        """Stops spinning (the queues drained for 0.5 s first) and writes the bag."""
        time.sleep(0.5)
        self._stop.set()
        self._thread.join()
        self._executor.shutdown()
        self._node.destroy_node()
        self._context.try_shutdown()
        store = typestore()
        writer = self._Writer(self.out, version=8)
        writer.open()
        try:
            connections = {t: writer.add_connection(t, typ, typestore=store)
                           for t, (typ, _) in self.topics.items()}
            for topic, stamp, data in self._messages:
                writer.write(connections[topic], stamp, data)
        finally:
            writer.close()
        if self._error is not None:
            raise RuntimeError(f'sitl_recorder: the spin thread failed: {self._error!r}') from self._error


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--out', required=True, help='bag directory to create')
    p.add_argument('--graph', default='whisker_fsm', choices=sorted(GRAPH_TOPICS))
    p.add_argument('--timeout', type=float, default=600.0, help='wall seconds to wait for /sim/done')
    a = p.parse_args(argv)
    rec = Recorder(Path(a.out), GRAPH_TOPICS[a.graph])
    try:
        ok = rec.wait_done(a.timeout)
    except KeyboardInterrupt:
        ok = False
    rec.stop()
    print(f'sitl_recorder: {sum(rec.counts.values())} messages -> {a.out}'
          f'{"" if ok else " (no /sim/done)"}')
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
