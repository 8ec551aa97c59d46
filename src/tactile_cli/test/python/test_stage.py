"""`tactile stage` runs the paper-002 bench protocols (whisker_localization)
and writes metrics.json; errors name the scenario file and key."""
import json
import os
import subprocess

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = os.environ["TACTILE_CONFIG_DIR"]


def test_stage_table1_writes_metrics(tmp_path):
    scenario = os.path.join(CONFIG, "scenarios", "bench", "whisker_loc_table1.yaml")
    p = subprocess.run([TACTILE, "stage", scenario, "--out", str(tmp_path), "--seed", "5"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    m = json.loads((tmp_path / "metrics.json").read_text())
    assert m["protocol"] == "table1" and m["seed"] == 5
    rows = [r for r in m["whisker_localization"]["table1"] if r["t_y_mm"] == 1.0]
    assert [r["p_x_mm"] for r in rows] == [35, 45, 55, 65, 70]
    assert max(r["ours_error_pct"] for r in rows) <= 1.0


def test_stage_bad_scenario(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("protocol: table9\n")
    p = subprocess.run([TACTILE, "stage", str(bad), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 1
    assert "bad.yaml" in p.stderr and "protocol" in p.stderr


def test_stage_unknown_key_is_an_error(tmp_path):
    # `trails: 2` (for trials) was ignored and the run flew the default 20 trials.
    bad = tmp_path / "typo.yaml"
    bad.write_text("protocol: table1\ntable1:\n  trails: 2\n")
    p = subprocess.run([TACTILE, "stage", str(bad), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 1
    assert "typo.yaml: table1.trails: unknown key" in p.stderr, p.stderr


def test_numbers_on_the_command_line_are_checked(tmp_path):
    scenario = os.path.join(CONFIG, "scenarios", "whisker_hover.yaml")
    cases = [
        (["sim", scenario, "--out", str(tmp_path / "a"), "--seed", "-1"], "--seed"),        # was 2^64 - 1
        (["sim", scenario, "--out", str(tmp_path / "b"), "--trials", "2147483647"], "--trials"),  # was bad_alloc
        (["bench", "--out", str(tmp_path / "c"), "--duration", "nan"], "--duration"),       # ran 0 s, exit 0
        (["bench", "--out", str(tmp_path / "d"), "--duration", "inf"], "--duration"),
        (["fly", "--out", str(tmp_path / "e"), "--duration", "nan"], "--duration"),
        (["sim", CONFIG, "--out", str(tmp_path / "f")], "is a directory"),                 # said "expected a map"
        (["fly", "--out", str(tmp_path / "g"), "--sim", scenario, "--scenario", scenario], "excludes"),  # ignored one
        (["fly", "--out", str(tmp_path / "h"), "--sim-loss", "nan"], "--sim-loss"),
        (["demo", "--out", str(tmp_path / "i"), "--hover", "inf"], "--hover"),
    ]
    for args, expected in cases:
        p = subprocess.run([TACTILE, *args, "--config", CONFIG], capture_output=True, text=True, timeout=60)
        assert p.returncode != 0, (args, p.stdout)
        assert expected in p.stderr, (args, p.stderr)
