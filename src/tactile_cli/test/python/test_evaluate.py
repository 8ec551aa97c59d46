"""`tactile evaluate` against `tactile sim`:

- the bag `tactile sim` records of a whisker_fsm flight, evaluated by `tactile evaluate`,
  gives exactly the metrics `tactile sim` computed in process (same evaluation code, same
  messages): the DDS end-to-end tests (tactile_ros_tests/test/test_e2e_*.py) rest on it;
- a bag whose evaluation topics were thinned (some ground-truth samples lost, as a
  best-effort DDS subscription may lose them) still evaluates, and the lost samples show in
  the "topics" counts;
- a bag without the FSM state topic and a scenario of an unsupported graph are refused,
  naming the bag / scenario file and what is missing;
- the same for XPLORER's box traversal: loop closure and the contact map from the bag equal
  the in-flight metrics.
"""
import json
import os
import subprocess
from pathlib import Path

import pytest
from rosbags.rosbag2 import Reader, Writer

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = os.environ["TACTILE_CONFIG_DIR"]
SCENARIOS = Path(CONFIG) / "scenarios"
# The shortest whisker_fsm course (two baffles) keeps the test at a few seconds.
SCENARIO = SCENARIOS / "whisker_baffles_two_fsm.yaml"
SEED = 3


def tactile(*args):
    return subprocess.run([TACTILE, "--config", CONFIG, *map(str, args)], capture_output=True, text=True)


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    out = tmp_path_factory.mktemp("sim")
    r = tactile("sim", SCENARIO, "--out", out, "--seed", SEED, "--no-png", "--quiet")
    assert r.returncode == 0, r.stderr
    return out


def test_evaluate_of_the_sim_bag_equals_the_sim_metrics(flown, tmp_path):
    r = tactile("evaluate", flown / "bag", "--scenario", SCENARIO, "--seed", SEED, "--out", tmp_path)
    assert r.returncode == 0, r.stderr
    sim = json.loads((flown / "metrics.json").read_text())
    ev = json.loads((tmp_path / "metrics.json").read_text())
    assert ev["source"] == "bag"
    for key in ("scenario", "seed", "graph", "vehicle", "success", "collisions", "arena_yaw_deg"):
        assert ev[key] == sim[key], key
    # Every wall-following metric, bit for bit.
    assert ev["fsm"] == sim["fsm"]
    assert sim["fsm"]["wall_following_contact_samples"] > 100  # the course was flown along walls
    for topic in ("/ground_truth/whisker/left/contact", "/fsm_state"):
        assert ev["topics"][topic] == sim["topics"][topic]


def copy_bag(src: Path, dst: Path, keep):
    """Copies the bag, keeping the messages for which keep(topic, index) is true; a topic
    for which keep(topic, -1) is false is left out altogether (no connection)."""
    with Reader(src) as reader, Writer(dst, version=8) as writer:
        conns = {c.id: writer.add_connection(c.topic, c.msgtype, msgdef=c.msgdef.data, rihs01=c.digest)
                 for c in reader.connections if keep(c.topic, -1)}
        seen = {}
        for c, stamp, raw in reader.messages():
            i = seen[c.topic] = seen.get(c.topic, -1) + 1
            if keep(c.topic, i):
                writer.write(conns[c.id], stamp, raw)


def test_lost_truth_samples_show_in_the_counts(flown, tmp_path):
    thinned = tmp_path / "thinned"
    copy_bag(flown / "bag", thinned,
             lambda t, i: not (t.startswith("/ground_truth/whisker/") and i % 10 == 0))
    r = tactile("evaluate", thinned, "--scenario", SCENARIO, "--seed", SEED, "--out", tmp_path / "ev")
    assert r.returncode == 0, r.stderr
    sim = json.loads((flown / "metrics.json").read_text())
    ev = json.loads((tmp_path / "ev" / "metrics.json").read_text())
    n_sim = sim["topics"]["/ground_truth/whisker/left/contact"]
    assert ev["topics"]["/ground_truth/whisker/left/contact"] == n_sim - (n_sim + 9) // 10
    assert ev["fsm"]["reached_target"] == sim["fsm"]["reached_target"]
    # A tenth of the samples gone: the fraction moves, but not far.
    assert ev["fsm"]["depth_in_band_fraction"] == pytest.approx(sim["fsm"]["depth_in_band_fraction"], abs=0.05)


def test_a_bag_without_the_fsm_state_is_refused(flown, tmp_path):
    stripped = tmp_path / "stripped"
    copy_bag(flown / "bag", stripped, lambda t, i: t != "/fsm_state")
    r = tactile("evaluate", stripped, "--scenario", SCENARIO, "--out", tmp_path / "ev")
    assert r.returncode == 1
    assert str(stripped) in r.stderr and "/fsm_state" in r.stderr


XPLORER = SCENARIOS / "xplorer_box_traversal.yaml"


def test_evaluate_of_an_xplorer_sim_bag_equals_the_sim_metrics(tmp_path):
    """Loop closure from the recorded FSM states and the contact map rebuilt from the
    recorded wrench and odometry: the same numbers as the graph computed in flight."""
    sim_dir = tmp_path / "sim"
    r = tactile("sim", XPLORER, "--out", sim_dir, "--no-png", "--quiet")
    assert r.returncode == 0, r.stderr
    r = tactile("evaluate", sim_dir / "bag", "--scenario", XPLORER, "--out", tmp_path / "ev")
    assert r.returncode == 0, r.stderr
    sim = json.loads((sim_dir / "metrics.json").read_text())
    ev = json.loads((tmp_path / "ev" / "metrics.json").read_text())
    assert ev["success"] == sim["success"]
    assert sim["xplorer"]["loop_closed"]  # the paper's outcome, or the comparison says little
    for key in ("loop_closed", "final_state", "turns_recontacted", "turns_without_recontact", "turns_closing_the_loop",
                "traversal_contact_lost", "slabs", "map_raw_points", "map_points", "map_length_m",
                "map_width_m", "map_area_m2", "map_area_accuracy", "map_hull_area_accuracy", "area_accuracy"):
        assert ev["xplorer"][key] == sim["xplorer"][key], key
    # The FSM's own clock vs the stamp of its first "done" message: the same 50 Hz tick.
    assert ev["xplorer"]["loop_closure_time_s"] == pytest.approx(sim["xplorer"]["loop_closure_time_s"], abs=0.02)


def with_area_goal(tmp_path, minimum):
    """The paper's box scenario with metrics.min_area_accuracy (issue 17's goal)."""
    text = XPLORER.read_text().replace("arena_file: arenas/", f"arena_file: {SCENARIOS / 'arenas'}/")
    text = text.replace("metrics:\n", f"metrics:\n  area_accuracy_of: rectangle\n  min_area_accuracy: {minimum}\n")
    path = tmp_path / f"box_min_{minimum}.yaml"
    path.write_text(text)
    return path


def test_min_area_accuracy_gates_success_in_flight_and_from_the_bag(tmp_path):
    """metrics.min_area_accuracy: the loop closed is not enough when the map's area is
    farther from the box's than allowed; `tactile sim` and `tactile evaluate` agree."""
    strict = with_area_goal(tmp_path, 0.9999)  # no contact map is that exact
    loose = with_area_goal(tmp_path, 0.5)
    r = tactile("sim", strict, "--out", tmp_path / "sim", "--no-png", "--quiet")
    assert r.returncode == 0, r.stderr
    sim = json.loads((tmp_path / "sim" / "metrics.json").read_text())
    assert sim["xplorer"]["loop_closed"]
    assert sim["xplorer"]["min_area_accuracy"] == 0.9999
    assert 0.5 < sim["xplorer"]["area_accuracy"] < 0.9999
    assert sim["xplorer"]["area_accuracy"] == sim["xplorer"]["map_area_accuracy"]
    assert not sim["success"]
    for scenario, success in ((strict, False), (loose, True)):
        out = tmp_path / f"ev_{scenario.stem}"
        r = tactile("evaluate", tmp_path / "sim" / "bag", "--scenario", scenario, "--out", out)
        assert r.returncode == 0, r.stderr
        assert json.loads((out / "metrics.json").read_text())["success"] is success, scenario.name
    bad = tmp_path / "bad.yaml"
    bad.write_text(with_area_goal(tmp_path, 1.5).read_text())
    r = tactile("sim", bad, "--out", tmp_path / "bad", "--no-png", "--quiet")
    assert r.returncode != 0 and "metrics.min_area_accuracy" in r.stderr, r.stderr


DUCTED = SCENARIOS / "ducted_estimation.yaml"


def test_evaluate_of_a_wall_effect_sim_bag_equals_the_sim_metrics(tmp_path):
    """004 estimation flight: RMSE of distance and direction, NEES of (distance,
    direction), tracking errors recomputed from the bag equal the in-flight numbers."""
    sim_dir = tmp_path / "sim"
    r = tactile("sim", DUCTED, "--out", sim_dir, "--no-png", "--quiet")
    assert r.returncode == 0, r.stderr
    r = tactile("evaluate", sim_dir / "bag", "--scenario", DUCTED, "--out", tmp_path / "ev")
    assert r.returncode == 0, r.stderr
    sim = json.loads((sim_dir / "metrics.json").read_text())
    ev = json.loads((tmp_path / "ev" / "metrics.json").read_text())
    assert ev["success"] == sim["success"]
    assert sim["wall_effect"]["samples_within_20cm"] > 1000
    for key in ("mode", "window_s", "samples_within_20cm", "rmse_distance_cm", "rmse_direction_deg",
                "mean_distance_error_cm", "rmse_distance_all_cm", "nees_distance_direction",
                "tracking_rms_y_cm", "tracking_rms_yaw_deg"):
        assert ev["wall_effect"][key] == sim["wall_effect"][key], key


def test_an_unsupported_graph_is_refused(flown, tmp_path):
    scenario = SCENARIOS / "whisker_hover.yaml"
    r = tactile("evaluate", flown / "bag", "--scenario", scenario, "--out", tmp_path / "ev")
    assert r.returncode == 1
    assert "whisker_hover.yaml" in r.stderr and "whisker_fsm" in r.stderr and "xplorer" in r.stderr
