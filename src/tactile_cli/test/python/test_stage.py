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
