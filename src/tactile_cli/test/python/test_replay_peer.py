"""End-to-end peer test of `tactile demo` / `tactile replay` outputs with the
independent Python `rosbags` package and numpy:

- rosbags opens every bag we wrote and deserializes every message of every
  topic using the message definitions stored in the bag;
- the compensated signals in the output bag equal an independent numpy
  implementation of 000 eq. 4-11 run on the raw pressures of the input bag;
- the false-positive rate and contact flag in metrics.json are recomputed
  from the bags.
"""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Reader
import yaml
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[2] / "tdorc_filter" / "test"))
from test_tdorc_numpy import reference  # noqa: E402  (numpy reference of 000 eq. 4-11)

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = os.environ["TACTILE_CONFIG_DIR"]


def read_bag(path):
    """All messages of a bag, deserialized by rosbags, grouped by topic."""
    store = get_typestore(Stores.EMPTY)
    out = {}
    with Reader(path) as reader:
        for conn in reader.connections:
            # Register the types from the definitions stored in the bag itself.
            store.register(get_types_from_msg(conn.msgdef.data, conn.msgtype))
        for conn, stamp, raw in reader.messages():
            out.setdefault(conn.topic, []).append((stamp, store.deserialize_cdr(raw, conn.msgtype)))
    return out


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    subprocess.run([TACTILE, "--config", CONFIG, "demo", "--out", str(out), "--hover", "30", "--seed", "5"],
                   check=True, capture_output=True, text=True)
    return out


@pytest.mark.parametrize("case", ["free_flight", "contact"])
def test_rosbags_reads_every_message_and_tdorc_matches_numpy(demo, case):
    raw = read_bag(demo / case / "raw_bag")
    out = read_bag(demo / case / "bag")
    assert set(raw) == {"/whisker/left/pressure", "/whisker/right/pressure",
                        "/ground_truth/whisker/left/contact", "/ground_truth/whisker/right/contact"}
    assert {"/whisker/left/signal", "/whisker/right/signal"} <= set(out)
    for side in ("left", "right"):
        pressure = raw[f"/whisker/{side}/pressure"]
        signal = out[f"/whisker/{side}/signal"]
        assert len(pressure) == len(signal) > 1000
        S = np.array([list(m.pressure) for _, m in pressure])
        # The replay passes the raw samples through unchanged.
        np.testing.assert_array_equal(np.array([list(m.raw) for _, m in signal]), S)
        # The repository's TDORC settings (config/tdorc_filter.yaml), incl. the
        # sustained-contact extension, given to the numpy reference.
        with open(Path(CONFIG) / "tdorc_filter.yaml") as f:
            tp = yaml.safe_load(f)["/**/tdorc_filter"]["ros__parameters"]
        ref = reference(S, tp["mode"], n=tp["window"], threshold=tp["contact_threshold"],
                        absolute=tp["absolute_threshold"], delay=tp["learn_delay"], hold=tp["contact_hold"],
                        max_hold=tp["max_contact_hold"], release=tp["hold_release_fraction"],
                        release_samples=tp["hold_release_samples"], drop=tp["hold_release_drop"],
                        level_samples=tp["hold_level_samples"], max_slope=tp["max_drift_slope"])
        ready = ref[:, 0] == 1
        got_sp = np.array([list(m.compensated) for _, m in signal])
        got_ready = np.array([m.calibrated_ready for _, m in signal])
        np.testing.assert_array_equal(got_ready, ready)
        np.testing.assert_allclose(got_sp[ready], ref[ready, 6:9], rtol=0, atol=1e-6)
        np.testing.assert_array_equal(np.array([m.contact for _, m in signal]), ref[:, 1] == 1)
        assert all(m.mode == 0 for _, m in signal)  # MODE_TDORC


@pytest.mark.parametrize("case", ["free_flight", "contact"])
def test_metrics_recomputed_from_bags(demo, case):
    metrics = json.loads((demo / case / "metrics.json").read_text())
    for key in ("fpr_bandpass", "fpr_tdoc", "fpr_tdorc"):
        assert 0.0 <= metrics[key] <= 1.0
    raw = read_bag(demo / case / "raw_bag")
    out = read_bag(demo / case / "bag")
    fp = tn = 0
    detected = False
    for side in ("left", "right"):
        truth = {m.header.stamp.sec * 10**9 + m.header.stamp.nanosec: m.contact
                 for _, m in raw[f"/ground_truth/whisker/{side}/contact"]}
        for _, m in out[f"/whisker/{side}/signal"]:
            t = m.header.stamp.sec * 10**9 + m.header.stamp.nanosec
            if truth[t]:
                detected |= m.contact
            elif m.calibrated_ready:
                fp += int(sum(m.channel_contact))
                tn += 3 - int(sum(m.channel_contact))
    assert metrics["fpr_tdorc"] == pytest.approx(fp / (fp + tn), abs=1e-12)
    assert metrics["contact_detected"] is detected
    assert metrics["ground_truth_contact"] is (case == "contact")
    assert metrics["contact_detected"] is (case == "contact")


def test_command_errors_name_the_path_and_exit_nonzero(tmp_path):
    res = subprocess.run([TACTILE, "--config", CONFIG, "replay", str(tmp_path / "missing"), "--out",
                          str(tmp_path / "out")], capture_output=True, text=True)
    assert res.returncode == 1
    assert str(tmp_path / "missing") in res.stderr and "does not exist" in res.stderr
    res = subprocess.run([TACTILE, "demo", "--config", str(tmp_path / "nocfg"), "--out", str(tmp_path / "o")],
                         capture_output=True, text=True)
    assert res.returncode == 1
    assert "configuration directory not found" in res.stderr
    res = subprocess.run([TACTILE, "replay"], capture_output=True, text=True)
    assert res.returncode != 0 and "bag" in res.stderr
