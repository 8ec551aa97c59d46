"""The dataset extractor (make_dataset.py) on one short real `tactile sim` flight.

Environment (set by ctest): TACTILE_EXE (the `tactile` executable) and TACTILE_CONFIG_DIR
(the repository's config/)."""
import math
import os
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import make_dataset  # noqa: E402

SHORT_SCENARIO = """
name: depth_short
duration_s: 7.5
seed: 1
arena:
  walls:
    - points: [[0.45, -1.0], [0.45, 1.0]]
      material: rigid
vehicle:
  type: whisker_crazyflie
  initial: {x: 0.0, y: 0.0, z: 0.0, yaw_deg: 0.0}
  state_estimate: mocap
graph: pilot
pilot:
  - {takeoff: 0.4, duration: 3.0}
  - {velocity: [0.2, 0.0], until: contact, timeout: 3.0}
  - {velocity: [0.0, -0.2], duration: 1.5}
  - {hover: 1.0}
"""


@pytest.mark.skipif("TACTILE_EXE" not in os.environ, reason="needs TACTILE_EXE (set by ctest)")
def test_extractor_on_a_short_sitl_flight(tmp_path):
    scen = tmp_path / "depth_short.yaml"
    scen.write_text(SHORT_SCENARIO)
    out = tmp_path / "ds"
    assert make_dataset.main(["--scenario", str(scen), "--flights", "1", "--first-seed", "4", "--out", str(out),
                              "--tactile", os.environ["TACTILE_EXE"],
                              "--config", os.environ.get("TACTILE_CONFIG_DIR", "config")]) == 0
    d = dict(np.load(out / "dataset.npz"))
    for key in make_dataset.DATASET_KEYS:
        assert key in d, key

    # Independent count from the bag: stamps with true contact, ready TDORC and height >= 0.2 m.
    bag = make_dataset.read_bag(str(out / "runs" / "flight_04" / "bag"),
                                ["/whisker/left/signal", "/ground_truth/whisker/left/contact", "/ground_truth/odom"])
    gt = {(m.header.stamp.sec, m.header.stamp.nanosec): m for m in bag["/ground_truth/whisker/left/contact"]}
    odom_t = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in bag["/ground_truth/odom"]])
    odom_z = np.array([m.pose.pose.position.z for m in bag["/ground_truth/odom"]])
    expected = []
    for m in bag["/whisker/left/signal"]:
        g = gt[(m.header.stamp.sec, m.header.stamp.nanosec)]
        t = m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec
        if g.contact and m.calibrated_ready and np.interp(t, odom_t, odom_z) >= 0.2:
            expected.append((t, list(m.compensated), g.depth, list(m.calibrated)))
    assert len(expected) > 20, "the short flight must touch the wall with a ready TDORC"
    left = d["contact"][:, 0]
    assert int(left.sum()) == len(expected)
    np.testing.assert_allclose(d["t"][left], [e[0] for e in expected], atol=1e-9)
    np.testing.assert_array_equal(d["sp"][left, 0], [e[1] for e in expected])
    np.testing.assert_array_equal(d["sc"][left, 0], [e[3] for e in expected])
    np.testing.assert_array_equal(d["depth"][left, 0], [e[2] for e in expected])
    assert np.all(d["flight"] == 4) and list(d["seeds"]) == [4]
    assert np.all(d["ready"][d["contact"]])
    assert np.all(np.isnan(d["depth"][~d["contact"]]))
    # depth within the whisker's horizontal reach (0.2 m cos 45 deg) and beyond the guard
    dep = d["depth"][d["contact"]]
    assert np.all((dep > 0.02) & (dep < 0.1415))
    # The wall fitted to the true contact points is the arena's wall x = 0.45.
    _, px, py, ang = d["wall"][0]
    assert px == pytest.approx(0.45, abs=1e-3)
    assert abs(math.cos(ang)) < 1e-2
    assert d["wall_fit_residual"][0] < 1e-3
    # CSV: one row per used (stamp, whisker) sample
    rows = (out / "dataset.csv").read_text().strip().splitlines()
    assert len(rows) == 1 + int(d["contact"].sum())
