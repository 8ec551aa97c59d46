#!/usr/bin/env python3
"""Benchmark (not a test): latency from a whisker pressure sample to the pipeline's outputs
and CPU of the whisker pipeline under ROS 2, composed in one container with and without
intra-process communication, and one container per node.

The pipeline is the one of the launch files (radio.launch.py, sitl_whisker.launch.py):
tdorc_filter x2 -> tactile_depth -> whisker_fsm, parameters from config/, on wall-clock
time. This script is the rest of the drone: an rclpy node publishes both whiskers'
pressure (stamp = send time, with a contact every few seconds) and the odometry at 50 Hz,
and receives /whisker/depth and /cmd_hover.

  latency pressure -> depth: receipt of /whisker/depth - its stamp (the pressure pair's
      send time). Event driven: DDS in, TDORC, two signal hops, depth, DDS out.
  latency pressure -> setpoint: receipt of /cmd_hover - send time of the newest pressure
      pair sent before the FSM tick that produced it (its stamp), each pair counted once
      (at the first setpoint after it). The FSM steps on each depth's arrival (event
      driven, a 50 Hz watchdog when depth stops); a timer-driven FSM adds its timer's
      phase (0-20 ms, mean ~10 ms).
  latency pressure -> FSM step: the setpoint's stamp (the FSM's clock when it stepped, the
      same wall clock here) - the same pair's send time: the pipeline up to the decision,
      without the DDS hop of /cmd_hover back to this script.
  CPU: user+system time of the container process(es) over the window (/proc/<pid>/stat),
      in % of one core; per node in the one-container-per-node variant.

The standalone host's number for the same pipeline is lib/tactile_cli/bench_whisker_pipeline
(Google Benchmark of one 50 Hz tick through the same node logics, no transport).

    source <ROS 2>/setup.bash && source install_ros/setup.bash
    python3 src/tactile_ros_tests/bench/bench_ros_latency.py [--seconds 20] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

WORKSPACE = Path(__file__).resolve().parents[3]
CONFIG = WORKSPACE / 'config'
RATE_HZ = 50.0
NODES = [  # (package, plugin, name, namespace, config file)
    ('tdorc_filter', 'tdorc_filter::TdorcFilterComponent', 'tdorc_filter', 'whisker/left', 'tdorc_filter'),
    ('tdorc_filter', 'tdorc_filter::TdorcFilterComponent', 'tdorc_filter', 'whisker/right', 'tdorc_filter'),
    ('tactile_depth', 'tactile_depth::TactileDepthComponent', 'tactile_depth', '', 'tactile_depth'),
    ('tactile_fsm', 'tactile_fsm::WhiskerFsmComponent', 'whisker_fsm', '', 'tactile_fsm'),
]

LAUNCH_TEMPLATE = '''
from launch import LaunchDescription
from launch_ros.actions import ComposableNodeContainer
from launch_ros.descriptions import ComposableNode

NODES = {nodes!r}
INTRA = {intra!r}
SEPARATE = {separate!r}


def node(pkg, plugin, name, ns, cfg):
    return ComposableNode(package=pkg, plugin=plugin, name=name, namespace=ns,
                          parameters=[{config!r} + '/' + cfg + '.yaml'],
                          extra_arguments=[{{'use_intra_process_comms': INTRA}}])


def generate_launch_description():
    groups = [[n] for n in NODES] if SEPARATE else [NODES]
    names = (['bench_' + (n[3].replace('/', '_') + '_' if n[3] else '') + n[2] for n in NODES]
             if SEPARATE else ['bench_container'])
    return LaunchDescription([
        ComposableNodeContainer(
            name=name, namespace='', package='rclcpp_components',
            executable='component_container',
            composable_node_descriptions=[node(*n) for n in g], output='screen')
        for name, g in zip(names, groups)])
'''


def cpu_seconds(pid: int) -> float:
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def containers(pgid: int) -> dict[int, str]:
    """component_container processes of the launch's process group -> their node."""
    out = {}
    for d in Path('/proc').iterdir():
        if not d.name.isdigit():
            continue
        try:
            if os.getpgid(int(d.name)) != pgid:
                continue
            cmd = (d / 'cmdline').read_bytes().split(b'\0')
        except (OSError, ProcessLookupError):
            continue
        if cmd and cmd[0].endswith(b'component_container'):
            name = next((c.decode().split(':=')[1] for c in cmd if c.startswith(b'__node:=')), '?')
            out[int(d.name)] = name
    return out


def pressure_of(k: int, side: int) -> list[float]:
    """Slow drift plus a 1 s contact pulse every 5 s (200 Pa on the first channel)."""
    t = k / RATE_HZ
    contact = 200.0 if (t % 5.0) > 3.0 and (t % 5.0) < 4.0 else 0.0
    return [101325.0 + 1000.0 * c + 0.5 * t + contact * (1.0 - 0.3 * c) + 0.2 * math.sin(7 * t + c + side)
            for c in range(3)]


def run_variant(label: str, intra: bool, separate: bool, seconds: float, warmup: float) -> dict:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import qos_profile_sensor_data
    from nav_msgs.msg import Odometry
    from tactile_msgs.msg import HoverSetpoint, TactileDepth, WhiskerPressure

    tmp = Path(tempfile.mkdtemp(prefix='bench_ros_'))
    launch_file = tmp / 'bench.launch.py'
    launch_file.write_text(LAUNCH_TEMPLATE.format(nodes=NODES, intra=intra, separate=separate,
                                                  config=str(CONFIG)))
    log = open(tmp / 'launch.log', 'w')
    proc = subprocess.Popen(['ros2', 'launch', str(launch_file)], stdout=log, stderr=subprocess.STDOUT,
                            start_new_session=True)
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    node = rclpy.create_node('bench_ros_latency', context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    pubs = [node.create_publisher(WhiskerPressure, f'/whisker/{s}/pressure', qos_profile_sensor_data)
            for s in ('left', 'right')]
    odom_pub = node.create_publisher(Odometry, '/odom', qos_profile_sensor_data)
    sent = []  # send times [ns], also the stamps
    depth_lat, setpoint_lat, step_lat = [], [], []
    lock = threading.Lock()
    recording = threading.Event()

    def on_depth(m):
        if recording.is_set():
            depth_lat.append(time.time_ns() - (m.header.stamp.sec * 10**9 + m.header.stamp.nanosec))

    answered = set()  # send times of the pressure pairs a setpoint already answered

    def on_setpoint(m):
        if not recording.is_set():
            return
        now = time.time_ns()
        tick = m.header.stamp.sec * 10**9 + m.header.stamp.nanosec
        with lock:
            before = [s for s in sent[-10:] if s <= tick]
        # Each pair counts once, at the first setpoint of a tick after it: a later tick
        # with no newer pair (the event-driven FSM's watchdog, or a second tick of a timer
        # faster than the pairs) answers nothing new.
        if before and before[-1] not in answered:
            answered.add(before[-1])
            setpoint_lat.append(now - before[-1])
            step_lat.append(tick - before[-1])

    node.create_subscription(TactileDepth, '/whisker/depth', on_depth, qos_profile_sensor_data)
    node.create_subscription(HoverSetpoint, '/cmd_hover', on_setpoint, 10)
    stop = threading.Event()

    def publisher():
        k = 0
        nxt = time.monotonic()
        while not stop.is_set():
            ns = time.time_ns()
            sec, nsec = divmod(ns, 10**9)
            odom = Odometry()
            odom.header.stamp.sec, odom.header.stamp.nanosec = sec, nsec
            odom.header.frame_id = 'odom'
            odom.pose.pose.position.z = 0.4
            odom.pose.pose.orientation.w = 1.0
            odom_pub.publish(odom)
            for side, pub in enumerate(pubs):
                m = WhiskerPressure()
                m.header.stamp.sec, m.header.stamp.nanosec = sec, nsec
                m.header.frame_id = 'whisker_left' if side == 0 else 'whisker_right'
                m.whisker_id = side
                m.pressure = pressure_of(k, side)
                m.temperature = [25.0, 25.0, 25.0]
                m.sequence = k
                pub.publish(m)
            with lock:
                sent.append(ns)
            k += 1
            nxt += 1.0 / RATE_HZ
            time.sleep(max(0.0, nxt - time.monotonic()))

    spin_stop = threading.Event()

    def spin():
        while not spin_stop.is_set():
            ex.spin_once(timeout_sec=0.05)

    spinner = threading.Thread(target=spin, daemon=True)
    spinner.start()
    try:
        # wait for the four nodes
        end = time.monotonic() + 90
        want = {'/whisker/left/tdorc_filter', '/whisker/right/tdorc_filter', '/tactile_depth', '/whisker_fsm'}
        while time.monotonic() < end:
            have = {ns.rstrip('/') + '/' + n for n, ns in node.get_node_names_and_namespaces()}
            if want <= have:
                break
            time.sleep(0.2)
        else:
            raise RuntimeError(f'{label}: nodes did not come up; log {tmp / "launch.log"}')
        pub_thread = threading.Thread(target=publisher, daemon=True)
        pub_thread.start()
        time.sleep(warmup)  # TDORC windows fill (100 samples = 2 s), discovery settles
        pids = containers(os.getpgid(proc.pid))
        cpu0 = {p: cpu_seconds(p) for p in pids}
        load0 = os.getloadavg()[0]
        t0 = time.monotonic()
        recording.set()
        time.sleep(seconds)
        recording.clear()
        dt = time.monotonic() - t0
        cpu = {pids[p]: 100.0 * (cpu_seconds(p) - cpu0[p]) / dt for p in pids}
        stop.set()
        pub_thread.join()
    finally:
        spin_stop.set()
        spinner.join()
        ex.shutdown()
        node.destroy_node()
        ctx.try_shutdown()
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
            try:
                proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
        log.close()

    def stats(v):
        if not v:
            return {'n': 0}
        v = sorted(x / 1e6 for x in v)
        return {'n': len(v), 'mean_ms': statistics.fmean(v), 'p50_ms': v[len(v) // 2],
                'p99_ms': v[min(len(v) - 1, int(0.99 * len(v)))], 'max_ms': v[-1]}
    return {'variant': label, 'intra_process': intra, 'one_container_per_node': separate,
            'seconds': dt, 'load_1min_at_start': load0,
            'pressure_to_depth': stats(depth_lat), 'pressure_to_setpoint': stats(setpoint_lat),
            'pressure_to_fsm_step': stats(step_lat),
            'cpu_percent_of_one_core': cpu, 'cpu_percent_total': sum(cpu.values())}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--seconds', type=float, default=20.0, help='measured window per variant')
    p.add_argument('--warmup', type=float, default=4.0)
    p.add_argument('--json', type=Path, help='write the results here')
    p.add_argument('--variants', default='intra,no_intra,separate')
    a = p.parse_args(argv)
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    variants = {'intra': (True, False), 'no_intra': (False, False), 'separate': (False, True)}
    results = []
    for name in a.variants.split(','):
        intra, separate = variants[name]
        r = run_variant(name, intra, separate, a.seconds, a.warmup)
        results.append(r)
        d, s, k = r['pressure_to_depth'], r['pressure_to_setpoint'], r['pressure_to_fsm_step']
        print(f"{name:9s} depth: mean {d.get('mean_ms', float('nan')):.2f} p50 {d.get('p50_ms', float('nan')):.2f} "
              f"p99 {d.get('p99_ms', float('nan')):.2f} ms (n={d['n']}); setpoint: mean "
              f"{s.get('mean_ms', float('nan')):.2f} p50 {s.get('p50_ms', float('nan')):.2f} "
              f"p99 {s.get('p99_ms', float('nan')):.2f} ms (n={s['n']}); FSM step: p50 "
              f"{k.get('p50_ms', float('nan')):.2f} p99 {k.get('p99_ms', float('nan')):.2f} ms; CPU "
              + ', '.join(f'{k} {v:.1f}%' for k, v in r['cpu_percent_of_one_core'].items())
              + f"; load {r['load_1min_at_start']:.1f}", flush=True)
    if a.json:
        a.json.write_text(json.dumps({'date': time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime()),
                                      'machine': f'{os.cpu_count()} cores', 'results': results}, indent=2))
    return 0


if __name__ == '__main__':
    sys.exit(main())
