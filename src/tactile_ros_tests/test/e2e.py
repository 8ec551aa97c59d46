"""Helpers of the end-to-end tests over DDS (test_e2e_*.py): fly a SITL launch file with
the rclcpp components, record the evaluation topics, evaluate the bag with
`tactile evaluate`, and fly the same scenario in process with `tactile sim`.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

from sitl_recorder import GRAPH_TOPICS, SIM_TOPICS, Recorder

try:
    import rosbags  # noqa: F401  (the recorder writes its bags with it)
except ImportError as e:  # pragma: no cover
    raise ImportError('the end-to-end tests record with the rosbags package: '
                      'python -m pip install rosbags (listed in scripts/requirements.txt)') from e

WORKSPACE = Path(__file__).resolve().parents[3]

# The simulator component's last line (tactile_sim_component.cpp).
END_LINE = re.compile(
    r'tactile_sim: scenario (?P<scenario>\S+) ended: (?P<sim_s>[\d.]+) s simulated in '
    r'(?P<wall_s>[\d.]+) s wall \((?P<achieved>[\d.]+)x real time, (?P<requested>[\d.]+)x '
    r'requested\), (?P<collisions>\d+) collisions; setpoints (?P<setpoints>\d+), late '
    r'(?P<late>\d+) .*mean age (?P<mean_age_ms>[\d.]+) ms, max age (?P<max_age_ms>[\d.]+) ms')


def tactile_exe() -> str:
    """The `tactile` command of the ROS build, else of the ROS-free build, else PATH."""
    for base in ('install_ros', 'install'):
        exe = WORKSPACE / base / 'tactile_cli' / 'bin' / 'tactile'
        if exe.is_file():
            return str(exe)
    exe = shutil.which('tactile')
    if not exe:
        raise FileNotFoundError('tactile not built (install_ros/ or install/)')
    return exe


def tactile(*args) -> subprocess.CompletedProcess:
    r = subprocess.run([tactile_exe(), '--config', str(WORKSPACE / 'config'), *map(str, args)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f'tactile {" ".join(map(str, args))} failed:\n{r.stderr}')
    return r


def sim_in_process(scenario: Path, seed: int, out: Path) -> dict:
    """`tactile sim` of the scenario and seed (no bag, no picture): its metrics.json."""
    tactile('sim', scenario, '--out', out, '--seed', seed, '--no-bag', '--no-png', '--quiet')
    return json.loads((out / 'metrics.json').read_text())


@dataclass
class DdsFlight:
    metrics: dict                 # `tactile evaluate` of the recorded bag
    sim_line: dict = field(default_factory=dict)  # the simulator's end line (factor, setpoint ages)
    recorded: dict = field(default_factory=dict)  # messages recorded per topic
    wall_s: float = 0.0


def fly_over_dds(launch_file: str, scenario: Path, graph: str, seed: int, factor: float,
                 out: Path, extra_args=(), timeout_s: float | None = None) -> DdsFlight:
    """Launches `launch_file` (scenario, seed, real_time_factor), records the evaluation
    topics of `graph` until /sim/done, stops the launch, evaluates the bag."""
    out.mkdir(parents=True, exist_ok=True)
    bag = out / 'bag'
    if bag.exists():
        shutil.rmtree(bag)
    log_path = out / 'launch.log'
    duration = float(re.search(r'^duration_s:\s*([\d.]+)', scenario.read_text(), re.M).group(1))
    if timeout_s is None:
        # Generous: a loaded 2-core machine may reach a fraction of the requested factor.
        timeout_s = 60.0 + 4.0 * duration / factor
    recorder = Recorder(bag, GRAPH_TOPICS[graph])
    start = time.monotonic()
    with open(log_path, 'w') as log:
        launch = subprocess.Popen(
            ['ros2', 'launch', str(WORKSPACE / 'launch' / launch_file), f'scenario:={scenario}',
             f'seed:={seed}', f'real_time_factor:={factor}',
             f'wait_for_subscribers:={",".join(SIM_TOPICS[graph])}', *extra_args],
            stdout=log, stderr=subprocess.STDOUT, start_new_session=True, env=os.environ.copy())
        try:
            done = False
            deadline = time.monotonic() + timeout_s
            while time.monotonic() < deadline and launch.poll() is None:
                if recorder.wait_done(1.0):
                    done = True
                    break
        finally:
            recorder.stop()
            if launch.poll() is None:
                os.killpg(launch.pid, signal.SIGINT)  # the launch process group we started
                try:
                    launch.wait(30)
                except subprocess.TimeoutExpired:
                    os.killpg(launch.pid, signal.SIGKILL)
                    launch.wait()
    wall_s = time.monotonic() - start
    text = log_path.read_text()
    if not done:
        raise AssertionError(f'no /sim/done from {launch_file} within {timeout_s:.0f} s '
                             f'(launch exit {launch.returncode}); log {log_path}:\n{text[-3000:]}')
    m = END_LINE.search(text)
    sim_line = {k: (v if k == 'scenario' else float(v)) for k, v in m.groupdict().items()} if m else {}
    tactile('evaluate', bag, '--scenario', scenario, '--seed', seed, '--out', out)
    metrics = json.loads((out / 'metrics.json').read_text())
    return DdsFlight(metrics=metrics, sim_line=sim_line, recorded=dict(recorder.counts),
                     wall_s=wall_s)


def spread(values, margin: float):
    """[min - margin, max + margin] of the in-process values."""
    return min(values) - margin, max(values) + margin
