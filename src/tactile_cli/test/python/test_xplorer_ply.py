"""XPLORER contact maps (paper 001 Sec. IV-B) read by an independent PLY
reader (plyfile): the maps `tactile sim` writes for the box traversal and
the map `tactile export BAG --ply` rebuilds from a recorded wall traversal
open with the point count of metrics.json and bounds at the obstacle."""
import json
import os
import struct
import subprocess

import numpy as np
import pytest
from plyfile import PlyData

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = os.environ["TACTILE_CONFIG_DIR"]


def sim(scenario, out, *extra):
    subprocess.run([TACTILE, "--config", CONFIG, "sim", os.path.join(CONFIG, "scenarios", scenario),
                    "--out", str(out), "--quiet", "--no-png", *extra], check=True, capture_output=True)
    return json.loads((out / "metrics.json").read_text())


def xyz(path):
    v = PlyData.read(str(path))["vertex"]
    return np.stack([v["x"], v["y"], v["z"]], axis=1).astype(np.float64)


def test_box_traversal_maps_open_with_count_and_bounds(tmp_path):
    m = sim("xplorer_box_traversal.yaml", tmp_path, "--no-bag")["xplorer"]
    a = xyz(tmp_path / "map.ply")
    b = xyz(tmp_path / "map_binary.ply")
    assert len(a) == len(b) == m["map_raw_points"] > 0
    np.testing.assert_array_equal(a, b)
    ply = PlyData.read(str(tmp_path / "map.ply"))
    assert ply.text and "frame odom" in " ".join(ply.comments)  # the odometry poses' frame (REP 105)
    assert PlyData.read(str(tmp_path / "map_binary.ply")).byte_order == "<"
    # Box of config/scenarios/arenas/xplorer_box.yaml: x in [0.8, 1.8], y in [-0.61, 0.61].
    lo, hi = a.min(axis=0), a.max(axis=0)
    assert lo[0] > 0.8 - 0.1 and hi[0] < 1.8 + 0.1
    assert lo[1] > -0.61 - 0.1 and hi[1] < 0.61 + 0.1
    # Slabs 0.5 m tall at the 0.7 m hover height.
    assert abs(lo[2] - 0.45) < 0.1 and abs(hi[2] - 0.95) < 0.1


def test_export_rebuilds_the_map_from_a_bag(tmp_path):
    m = sim("xplorer_wall_traversal.yaml", tmp_path)["xplorer"]
    for fmt in ([], ["--binary"]):
        out = tmp_path / ("export_bin.ply" if fmt else "export.ply")
        r = subprocess.run([TACTILE, "--config", CONFIG, "export", str(tmp_path / "bag"), "--ply", str(out), *fmt],
                           check=True, capture_output=True, text=True)
        assert "points" in r.stdout
        p = xyz(out)
        # Same filtered map as the run's metrics (voxel 1 cm + outlier removal).
        assert len(p) == m["map_points"] > 0
        # The wall of xplorer_wall.yaml is at x = 1 m: slabs lie in [1.0, 1.08].
        assert p[:, 0].min() > 1.0 - 0.02 and p[:, 0].max() < 1.08 + 0.03
        # The summary with its (here empty) warnings beside the map.
        summary = json.loads(out.with_suffix(".metrics.json").read_text())
        assert summary["points"] == len(p) and summary["warnings"] == []
    # Issue 32: a bag cut inside its first mcap chunk (nothing recovered) wrote a 0-point
    # PLY with exit 0; it is an error now, and no PLY is written.
    mcap = next((tmp_path / "bag").glob("*.mcap"))
    data = mcap.read_bytes()
    pos = 8
    while data[pos] != 0x06:  # first chunk record
        pos += 9 + struct.unpack_from("<Q", data, pos + 1)[0]
    mcap.write_bytes(data[:pos + 100])
    out = tmp_path / "cut.ply"
    r = subprocess.run([TACTILE, "--config", CONFIG, "export", str(tmp_path / "bag"), "--ply", str(out)],
                       capture_output=True, text=True)
    assert r.returncode != 0 and "nothing recovered" in r.stderr, r.stderr
    assert not out.exists()


def test_export_names_the_missing_topic(tmp_path):
    (tmp_path / "empty").mkdir()
    r = subprocess.run([TACTILE, "--config", CONFIG, "export", str(tmp_path / "empty"), "--ply", str(tmp_path / "x.ply")],
                       capture_output=True, text=True)
    assert r.returncode != 0
    assert "error" in r.stderr


def rewrite_bag(src, dst, edit):
    """A copy of the bag `src` written by rosbags (mcap) to `dst`, every message through
    `edit(connection, timestamp, raw) -> (timestamp, raw)` in the bag's order."""
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer
    w = Writer(dst, version=9, storage_plugin=StoragePlugin.MCAP)
    with Reader(src) as r, w:
        conns = {c.id: w.add_connection(c.topic, c.msgtype, msgdef=c.msgdef.data, rihs01=c.digest)
                 for c in r.connections}
        for c, t, raw in r.messages():
            w.write(conns[c.id], *edit(c, t, raw))
    return dst


def export(bag, out, *extra):
    """`tactile export BAG --ply OUT` (extra options): the map's points and the summary."""
    subprocess.run([TACTILE, "--config", CONFIG, "export", str(bag), "--ply", str(out), *extra],
                   check=True, capture_output=True, text=True, timeout=120)
    return xyz(out), json.loads(out.with_suffix(".metrics.json").read_text())


def test_export_replays_at_the_header_stamps_of_a_bag_recorded_with_receive_lag(tmp_path):
    """A `ros2 bag record` stores receive times: the messages in the order it received
    them, each with the recorder's clock when it did, which lags the header stamp by a
    varying delay (1-6 ms on /clock in SITL, issue 34). The same bag rewritten (rosbags)
    the way such a recorder would have stored it -- each message 1-6 ms late (seeded), the
    order kept, receive times never going back -- exports, at the header stamps (the
    default), the original bag's map point for point; `--time receive` replays at the
    lagged receive times (the summary says which clock)."""
    import random
    m = sim("xplorer_wall_traversal.yaml", tmp_path)["xplorer"]
    rng = random.Random(7)
    received, lagged = 0, 0

    def lag(c, t, raw):
        nonlocal received, lagged
        received = max(t + rng.randint(1_000_000, 6_000_000), received)
        lagged += received != t
        return received, raw

    dst = rewrite_bag(tmp_path / "bag", tmp_path / "lagged", lag)
    assert lagged > 0
    original, s0 = export(tmp_path / "bag", tmp_path / "original.ply")
    header, s1 = export(dst, tmp_path / "header.ply")
    _, s2 = export(dst, tmp_path / "receive.ply", "--time", "receive")
    assert len(original) == m["map_points"] > 0
    np.testing.assert_array_equal(header, original)
    assert (s0["time"], s1["time"], s2["time"]) == ("header", "header", "receive")
    assert s1["messages"] == s0["messages"] == s2["messages"]
    assert s1["warnings"] == []
    # An unknown clock is refused by the option parser, naming the choices.
    r = subprocess.run([TACTILE, "--config", CONFIG, "export", str(dst), "--ply", str(tmp_path / "x.ply"),
                        "--time", "bag"], capture_output=True, text=True)
    assert r.returncode != 0 and "header" in r.stderr and "receive" in r.stderr, r.stderr


def test_export_replays_stamps_off_the_bag_clock_at_bag_time(tmp_path):
    """A stamp far from the bag's time -- 10^6 s ahead on the first odometry, unset (0) on
    the last -- is replayed at the bag's timestamp and counted; before, the nodes started
    at the first stamp in stamp order and an unset one in a wall-clock bag left the
    mapper's timer ~10^11 ticks to run to the next stamp (a hang), and a far-ahead one
    was held to the end of the bag."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore
    store = get_typestore(Stores.ROS2_JAZZY)
    sim("xplorer_wall_traversal.yaml", tmp_path)
    with Reader(tmp_path / "bag") as r:
        n_odom = sum(1 for c, _, _ in r.messages() if c.topic == "/odom")
    odom, changed = 0, 0

    def restamp(c, t, raw):
        nonlocal odom, changed
        if c.topic == "/odom":
            odom += 1
            if odom in (1, n_odom):
                assert odom == 1 or t > 6_000_000_000, "the last odometry within 6 s of the start"
                msg = store.deserialize_cdr(raw, c.msgtype)
                if odom == 1:
                    msg.header.stamp.sec += 1_000_000
                else:
                    msg.header.stamp.sec, msg.header.stamp.nanosec = 0, 0
                raw = store.serialize_cdr(msg, c.msgtype)
                changed += 1
        return t, raw

    dst = rewrite_bag(tmp_path / "bag", tmp_path / "off_clock", restamp)
    assert changed == 2
    points, summary = export(dst, tmp_path / "off_clock.ply")
    kinds = {w["kind"]: w["count"] for w in summary["warnings"]}
    assert kinds.get("stamps_off_the_bag_clock_replayed_at_bag_time") == 2, summary["warnings"]
    assert summary["points"] == len(points) > 0


def test_export_of_a_namespaced_bag_with_namespace(tmp_path):
    """A launch with namespace:=cf1 records /cf1/odom, /cf1/xplorer/wrench_body, ...: the
    same bag under those names exports with --namespace cf1 the map of the root bag point
    for point, in the frame cf1/odom (the launch's frame prefix); without it the error
    names the namespace the bag has."""
    sim("xplorer_wall_traversal.yaml", tmp_path)
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer
    dst = tmp_path / "cf1_bag"
    w = Writer(dst, version=9, storage_plugin=StoragePlugin.MCAP)
    with Reader(tmp_path / "bag") as r, w:
        conns = {c.id: w.add_connection("/cf1" + c.topic, c.msgtype, msgdef=c.msgdef.data, rihs01=c.digest)
                 for c in r.connections}
        for c, t, raw in r.messages():
            w.write(conns[c.id], t, raw)
    root, _ = export(tmp_path / "bag", tmp_path / "root.ply")
    r = subprocess.run([TACTILE, "--config", CONFIG, "export", str(dst), "--ply", str(tmp_path / "x.ply")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode != 0 and "no /odom topic" in r.stderr and "/cf1/odom (--namespace cf1)" in r.stderr, r.stderr
    assert not (tmp_path / "x.ply").exists()
    ns, summary = export(dst, tmp_path / "cf1.ply", "--namespace", "cf1")
    assert len(root) > 0 and summary["warnings"] == []
    np.testing.assert_array_equal(ns, root)
    assert "frame cf1/odom" in " ".join(PlyData.read(str(tmp_path / "cf1.ply")).comments)
