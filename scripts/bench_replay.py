#!/usr/bin/env python3
"""Replay throughput vs rosbags read+deserialize on the same bag (issue 16 item 6).

Records a whisker bag with `tactile sim SCENARIO` in each storage, then times
  (a) `tactile replay BAG` (whisker_driver -> tdorc_filter over the bag, recording its output),
  (b) rosbags: open the bag, register its definitions, read and deserialize every message,
and prints messages/s of both and their ratio. Not a test: a command users run.

Usage: scripts/bench_replay.py [--scenario config/scenarios/whisker_three_baffles_fsm.yaml]
                               [--repeat 3] [--out out/bench_replay]
Needs the workspace built (install/) and the venv (rosbags).
"""
import argparse
import shutil
import subprocess
import time
from pathlib import Path

from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

ROOT = Path(__file__).resolve().parents[1]
SEPARATOR = '=' * 80 + '\n'


def register(store, msgtype, msgdef):
    parts = msgdef.split(SEPARATOR)
    types = dict(get_types_from_msg(parts[0], msgtype))
    for part in parts[1:]:
        header, _, body = part.partition('\n')
        pkg, name = header[len('MSG: '):].strip().split('/')
        types.update(get_types_from_msg(body, f'{pkg}/msg/{name}'))
    store.register(types)


def rosbags_read(bag):
    t0 = time.perf_counter()
    store = get_typestore(Stores.ROS2_KILTED)
    n = 0
    with Reader(bag) as r:
        for c in r.connections:
            register(store, c.msgtype, c.msgdef.data)
        for c, _, raw in r.messages():
            store.deserialize_cdr(raw, c.msgtype)
            n += 1
    return n, time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--scenario', default=str(ROOT / 'config/scenarios/whisker_three_baffles_fsm.yaml'))
    ap.add_argument('--repeat', type=int, default=3)
    ap.add_argument('--out', default=str(ROOT / 'out/bench_replay'))
    a = ap.parse_args()
    tactile = shutil.which('tactile') or str(ROOT / 'install/tactile_cli/bin/tactile')
    out = Path(a.out)
    shutil.rmtree(out, ignore_errors=True)
    for storage, extra in [('sqlite3', []), ('mcap', []), ('mcap', ['--bag-compression', 'zstd'])]:
        label = storage + (f'+{extra[1]}' if extra else '')
        sim = out / f'sim_{label}'
        subprocess.run([tactile, '--config', str(ROOT / 'config'), 'sim', a.scenario, '--out', str(sim),
                        '--no-png', '--quiet', '--storage', storage, *extra], check=True,
                       stdout=subprocess.DEVNULL)
        bag = sim / 'bag'
        best_replay = best_rosbags = float('inf')
        n = 0
        for i in range(a.repeat):
            rep = out / f'replay_{label}_{i}'
            t0 = time.perf_counter()
            subprocess.run([tactile, '--config', str(ROOT / 'config'), 'replay', str(bag), '--out', str(rep),
                            '--no-png'], check=True, stdout=subprocess.DEVNULL)
            best_replay = min(best_replay, time.perf_counter() - t0)
            n, dt = rosbags_read(bag)
            best_rosbags = min(best_rosbags, dt)
        size = sum(f.stat().st_size for f in bag.iterdir() if f.name != 'metadata.yaml')
        print(f'{label:10s} {n:8d} msgs {size / n:6.1f} B/msg | tactile replay {best_replay:6.2f} s '
              f'({n / best_replay / 1e3:7.1f} k msg/s) | rosbags read+deserialize {best_rosbags:6.2f} s '
              f'({n / best_rosbags / 1e3:7.1f} k msg/s) | replay / rosbags = {best_rosbags / best_replay:4.2f}x')


if __name__ == '__main__':
    main()
