"""Bags of the `tactile` commands with independent tools (issue 16 items 2 and 5).

- `tactile sim` graphs recorded with --storage mcap|sqlite3 and --bag-distro humble|jazzy|kilted
  are read by rosbags with the standard types taken from rosbags' own store of that distro
  (only tactile_msgs registered from the bag): every message deserializes. Range is in the
  distro's layout (variance in Jazzy/Kilted, none in Humble).
- A bag with both whiskers and the ground truth, rewritten by rosbags as mcap with zstd
  chunks, replays to the same metrics as the same data in sqlite3.
"""
import json
import os
import subprocess
from pathlib import Path

import pytest
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = os.environ["TACTILE_CONFIG_DIR"]
SCENARIOS = Path(CONFIG) / "scenarios"
SEPARATOR = "=" * 80 + "\n"
STORE = {"humble": Stores.ROS2_HUMBLE, "jazzy": Stores.ROS2_JAZZY, "kilted": Stores.ROS2_KILTED}


def tactile(*args):
    return subprocess.run([TACTILE, "--config", CONFIG, *map(str, args)], check=True,
                          capture_output=True, text=True)


def register_own_types(store, msgtype, msgdef):
    """Register only the types rosbags' store does not have (ours: tactile_msgs)."""
    parts = msgdef.split(SEPARATOR)
    types = dict(get_types_from_msg(parts[0], msgtype))
    for part in parts[1:]:
        header, _, body = part.partition("\n")
        pkg, name = header[len("MSG: "):].strip().split("/")
        types.update(get_types_from_msg(body, f"{pkg}/msg/{name}"))
    store.register({k: v for k, v in types.items() if k not in store.fielddefs})


# One scenario per vehicle graph with /tof (Range): whisker FSM on the Crazyflie with the
# flow deck, and the ducted wall-effect graph.
GRAPHS = ["whisker_darkness_rigid_fsm.yaml", "ducted_vf_three_round.yaml"]


@pytest.mark.parametrize("scenario,storage,distro", [
    (GRAPHS[0], "mcap", "jazzy"), (GRAPHS[0], "sqlite3", "humble"),
    (GRAPHS[1], "mcap", "kilted"), (GRAPHS[1], "sqlite3", "humble")])
def test_sim_bags_decode_in_the_distro_store(tmp_path, scenario, storage, distro):
    tactile("sim", SCENARIOS / scenario, "--out", tmp_path, "--no-png", "--quiet",
            "--storage", storage, "--bag-distro", distro)
    bag = tmp_path / "bag"
    meta = (bag / "metadata.yaml").read_text()
    assert f"storage_identifier: {storage}" in meta
    store = get_typestore(STORE[distro])
    counts = {}
    with Reader(bag) as reader:
        for c in reader.connections:
            register_own_types(store, c.msgtype, c.msgdef.data)
            if distro != "humble":
                assert c.digest == store.hash_rihs01(c.msgtype), (c.topic, c.msgtype)
        for c, _, raw in reader.messages():
            msg = store.deserialize_cdr(raw, c.msgtype)
            counts[c.msgtype] = counts.get(c.msgtype, 0) + 1
            if c.msgtype == "sensor_msgs/msg/Range":
                assert hasattr(msg, "variance") == (distro != "humble")
                # and the bytes end exactly after the last field of the layout
                assert store.serialize_cdr(msg, c.msgtype).tobytes() == bytes(raw)
    assert counts.get("sensor_msgs/msg/Range", 0) > 0, counts
    assert sum(counts.values()) > 100


def metrics_without_run_info(path):
    m = json.loads(Path(path).read_text())
    for k in list(m):
        if "wall" in k or "per_second" in k or k in ("bag", "out_dir", "input_bag"):
            m.pop(k)
    return m


def test_replay_of_a_rosbags_mcap_zstd_bag_equals_sqlite3(tmp_path):
    sim = tmp_path / "sim"
    tactile("sim", SCENARIOS / "whisker_three_baffles_fsm.yaml", "--out", sim, "--no-png", "--quiet",
            "--storage", "sqlite3")
    src = sim / "bag"
    # The same data rewritten by rosbags as mcap with zstd chunks.
    dst = tmp_path / "rosbags_mcap"
    w = Writer(dst, version=9, storage_plugin=StoragePlugin.MCAP)
    w.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    topics = set()
    with Reader(src) as r, w:
        conns = {}
        for c in r.connections:
            conns[c.id] = w.add_connection(c.topic, c.msgtype, msgdef=c.msgdef.data, rihs01=c.digest)
            topics.add(c.topic)
        for c, t, raw in r.messages():
            w.write(conns[c.id], t, raw)
    assert {"/whisker/left/pressure", "/whisker/right/pressure"} <= topics
    assert any("truth" in t for t in topics), topics
    with open(next(dst.glob("*.mcap")), "rb") as f:
        assert b"zstd" in f.read()
    tactile("replay", src, "--out", tmp_path / "r_sqlite", "--no-png", "--storage", "sqlite3")
    tactile("replay", dst, "--out", tmp_path / "r_mcap", "--no-png")
    a = metrics_without_run_info(tmp_path / "r_sqlite" / "metrics.json")
    b = metrics_without_run_info(tmp_path / "r_mcap" / "metrics.json")
    assert a == b
