"""Ctrl-C / SIGTERM on the commands a user waits on: a child `tactile` process is signalled
mid-run and its outputs are checked (tactile_cli README, "Signals"). Before the signal
handling, an interrupted sweep (default jobs) left no table or summary, and `sim --trials`
left no aggregate metrics."""
import csv
import json
import os
import signal
import subprocess
import time

import pytest

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = os.environ["TACTILE_CONFIG_DIR"]


def start(args, tmp_path):
    return subprocess.Popen([TACTILE, *args, "--config", CONFIG], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def wait_for_line(proc, needle, timeout_s=240):
    """Reads stderr until a line contains `needle`; returns the lines read."""
    lines = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        lines.append(line)
        if needle in line:
            return lines
    proc.kill()
    pytest.fail(f"no line with {needle!r} within {timeout_s} s: {''.join(lines)[-2000:]}")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_sweep_interrupted_keeps_table_and_summary(tmp_path, sig):
    out = tmp_path / "sweep"
    # Default jobs (all cores): the case that lost everything before.
    proc = start(["sweep", "baffles_mocap", "--count", "300", "--seed", "1000", "--no-bag", "--out", str(out)],
                 tmp_path)
    wait_for_line(proc, "[sweep] 2/")
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + sig, err
    assert "interrupted" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True
    assert 2 <= summary["flown"] < 300
    with open(out / "table.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == summary["flown"]
    assert "Interrupted" in (out / "summary.md").read_text()
    # Every row flew to its end; an environment stopped part-way left no run directory.
    flown = {r["name"] for r in rows}
    assert {p.name for p in (out / "runs").iterdir()} == flown
    for name in flown:
        m = json.loads((out / "runs" / name / "metrics.json").read_text())
        assert m["interrupted"] is False


def test_sim_trials_interrupted_writes_the_aggregate(tmp_path):
    out = tmp_path / "trials"
    scenario = os.path.join(CONFIG, "scenarios", "whisker_three_baffles_fsm.yaml")
    proc = start(["sim", scenario, "--trials", "40", "--jobs", "2", "--no-bag", "--out", str(out)], tmp_path)
    wait_for_line(proc, "trials done")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    m = json.loads((out / "metrics.json").read_text())
    assert m["interrupted"] is True
    assert 1 <= m["trials_completed"] < 40
    assert len(m["per_trial"]) == m["trials_completed"]
    assert all(not t["interrupted"] for t in m["per_trial"])
    assert "interrupted" not in m["statistics"]


def test_sim_interrupted_flight_closes_its_bag(tmp_path):
    out = tmp_path / "one"
    # A long hover (the shipped one, 3000 s instead of 66 s): signalled at its first
    # progress report (5 %), it is far from its end.
    hover = (open(os.path.join(CONFIG, "scenarios", "whisker_hover.yaml")).read()
             .replace("duration_s: 66.0", "duration_s: 3000.0").replace("duration: 62.0", "duration: 2990.0")
             .replace("arena_file: arenas/", "arena_file: " + os.path.join(CONFIG, "scenarios", "arenas") + "/"))
    scenario = tmp_path / "long_hover.yaml"
    scenario.write_text(hover)
    proc = start(["sim", str(scenario), "--out", str(out)], tmp_path)
    seen = ""
    while "  5 %" not in seen:  # the live progress line ends in \r, not \n
        c = proc.stderr.read(1)
        assert c, seen
        seen += c
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    m = json.loads((out / "metrics.json").read_text())
    assert m["interrupted"] is True and m["success"] is False
    assert 0 < m["sim_time_s"] < 3000
    # The bag was closed: its metadata counts the messages it holds.
    meta = (out / "bag" / "metadata.yaml").read_text()
    assert "message_count" in meta
