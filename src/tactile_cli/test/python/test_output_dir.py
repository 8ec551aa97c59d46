"""A reused --out directory (include/tactile_cli/output_dir.hpp): a rerun replaces exactly
what the previous run wrote, keeps files no run wrote, and keeps the previous outputs when it
writes nothing. Before, a rerun with fewer trials left the stale trial_K/ beside its own
without a word."""
import json
import os
import subprocess

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = os.environ["TACTILE_CONFIG_DIR"]
HOVER = os.path.join(CONFIG, "scenarios", "whisker_hover.yaml")


def tactile(*args):
    return subprocess.run([TACTILE, *args, "--config", CONFIG], capture_output=True, text=True, timeout=300)


def test_rerun_replaces_its_own_outputs_only(tmp_path):
    out = tmp_path / "out"
    p = tactile("sim", HOVER, "--trials", "3", "--no-bag", "--no-png", "--out", str(out))
    assert p.returncode == 0, p.stderr
    assert {d.name for d in out.iterdir() if d.name.startswith("trial_")} == {"trial_0", "trial_1", "trial_2"}
    (out / "notes.txt").write_text("mine")

    p = tactile("sim", HOVER, "--trials", "2", "--no-bag", "--no-png", "--out", str(out))
    assert p.returncode == 0, p.stderr
    assert "replacing the previous run's outputs" in p.stderr
    assert "notes.txt" in p.stderr  # named as not written by a run, and kept
    assert {d.name for d in out.iterdir() if d.name.startswith("trial_")} == {"trial_0", "trial_1"}
    assert (out / "notes.txt").read_text() == "mine"
    assert json.loads((out / "metrics.json").read_text())["trials"] == 2
    assert not (out / ".tactile_previous").exists()
    record = json.loads((out / ".tactile_outputs.json").read_text())
    assert "notes.txt" not in record["entries"] and "trial_1" in record["entries"]


def test_a_run_that_writes_nothing_keeps_the_previous_outputs(tmp_path):
    out = tmp_path / "out"
    assert tactile("sim", HOVER, "--no-bag", "--out", str(out)).returncode == 0
    before = (out / "metrics.json").read_text()
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nduration_s: -1\n")
    p = tactile("sim", str(bad), "--out", str(out))
    assert p.returncode == 1 and "duration_s" in p.stderr
    assert "previous outputs" in p.stderr and "kept" in p.stderr
    assert (out / "metrics.json").read_text() == before
    assert (out / "topview.png").exists()
    assert not (out / ".tactile_previous").exists()
