"""End-to-end: the demo's bags replayed with one time fault injected into the
left whisker (whisker_faults.py, written with the independent rosbags
package) give TDORC's false-positive rate and contact detection of the clean
replay within one sample's worth, and every repair, skip or drop is one
warning line on stderr and one entry under `warnings` in metrics.json.
"""
import json
import os
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from rosbags.rosbag2 import Reader, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import whisker_faults  # noqa: E402

TACTILE = os.environ["TACTILE_EXE"]
CONFIG = os.environ["TACTILE_CONFIG_DIR"]

# Per case: warning kind -> count expected in metrics.json, and the samples of
# the left whisker the fault takes away (the only ones allowed to be missing
# from the counts).
EXPECTED = {
    "clean": ({}, 0),
    "ahead": ({"stamps_repaired_ahead": 1}, 0),
    "behind": ({"stamps_repaired_behind": 1}, 0),
    "swap": ({"dropped_late": 1, "samples_missing": 1}, 1),
    "gap": ({"samples_missing": 100}, 100),
    "duplicate": ({"dropped_duplicate": 1}, 0),
}


def signals(bag):
    """Left whisker's TDORC output per stamp: (ready, contact, channel contacts)."""
    msgs = read_topic(bag, "/whisker/left/signal")
    return {m.header.stamp.sec * 10**9 + m.header.stamp.nanosec:
            (m.calibrated_ready, m.contact, tuple(m.channel_contact)) for m in msgs}


def read_topic(bag, topic):
    store = get_typestore(Stores.EMPTY)
    out = []
    with Reader(bag) as r:
        conns = [c for c in r.connections if c.topic == topic]
        for c in conns:
            store.register(get_types_from_msg(c.msgdef.data, c.msgtype))
        for c, _, raw in r.messages(connections=conns):
            out.append(store.deserialize_cdr(raw, c.msgtype))
    return out


def replay(bag, out):
    r = subprocess.run([TACTILE, "--config", CONFIG, "replay", str(bag), "--out", str(out), "--no-png"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads((Path(out) / "metrics.json").read_text()), r.stderr


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("faults_demo")
    subprocess.run([TACTILE, "--config", CONFIG, "demo", "--out", str(out), "--hover", "30", "--seed", "7"],
                   check=True, capture_output=True, text=True)
    return out


@pytest.mark.parametrize("bag", ["free_flight", "contact"])
@pytest.mark.parametrize("case", list(EXPECTED))
def test_fault_costs_only_the_affected_samples(demo, tmp_path, bag, case):
    clean = json.loads((demo / bag / "metrics.json").read_text())
    faulty_bag = tmp_path / "bag"
    whisker_faults.inject(demo / bag / "raw_bag", faulty_bag, case)
    m, err = replay(faulty_bag, tmp_path / "out")

    # TDORC: false positives within one sample (3 channels) of the clean run;
    # the counted pairs lose at most the removed samples' 3 channels each.
    expected_kinds, removed = EXPECTED[case]
    c, f = clean["modes"]["tdorc"], m["modes"]["tdorc"]
    n_clean = c["false_positives"] + c["true_negatives"]
    n_fault = f["false_positives"] + f["true_negatives"]
    assert n_clean - 3 * removed - 3 <= n_fault <= n_clean + 3, (n_clean, n_fault)
    assert c["false_positives"] - 3 * removed - 3 <= f["false_positives"] <= c["false_positives"] + 3, (c, f)
    if removed == 0:
        assert abs(f["fpr"] - c["fpr"]) <= 3.0 / n_fault + 1e-12
    # Sample by sample: the TDORC output of every sample both runs have is the
    # same (contact and per-channel flags), but for at most one sample.
    differ = 0
    clean_sig = signals(demo / bag / "bag")
    fault_sig = signals(tmp_path / "out" / "bag")
    assert len(clean_sig) - removed - 1 <= len(fault_sig) <= len(clean_sig)
    for t, flags in fault_sig.items():
        assert t in clean_sig, t  # every output stamp is a true sampling time
        differ += flags != clean_sig[t]
    assert differ <= 1, differ
    assert m["contact_detected"] == clean["contact_detected"]
    assert m["ground_truth_contact"] == clean["ground_truth_contact"]
    for ns in ("/whisker/left", "/whisker/right"):
        cw, fw = c["whiskers"][ns], f["whiskers"][ns]
        assert fw["contact_detected"] == cw["contact_detected"], ns
        assert abs(fw["detected_contact_samples"] - cw["detected_contact_samples"]) <= 1, (ns, cw, fw)
    # The right whisker was not touched: identical counts.
    assert f["whiskers"]["/whisker/right"] == c["whiskers"]["/whisker/right"]

    # Nothing silent: one entry per kind with its count, one stderr line each.
    kinds = {w["kind"]: w["count"] for w in m["warnings"]}
    assert kinds == expected_kinds, m["warnings"]
    lines = [l for l in err.splitlines() if l.startswith("tactile replay: warning: ")]
    assert len(lines) == len(expected_kinds), err
    for w in m["warnings"]:
        assert f"tactile replay: warning: {w['message']}" in lines
        assert "/whisker/left/whisker_driver" in w["message"]
    if case == "clean":
        assert err == ""


def _copy_bag(src, dst, transform):
    """Copies a bag with rosbags; transform(conn, t, raw) -> list of (topic, msgtype, msgdef, t, raw)."""
    with Reader(src) as r, Writer(dst, version=9) as w:
        conns = {}
        for conn, t, raw in r.messages():
            for topic, msgtype, msgdef, t2, raw2 in transform(conn, t, bytes(raw)):
                if topic not in conns:
                    conns[topic] = w.add_connection(topic, msgtype, msgdef=msgdef, rihs01="RIHS01_" + "0" * 64)
                w.write(conns[topic], t2, raw2)


def test_whisker_topic_of_another_type_is_skipped_and_said(demo, tmp_path):
    string_cdr = b"\x00\x01\x00\x00" + struct.pack("<I", 3) + b"hi\x00"

    def t(conn, ts, raw):
        if conn.topic == "/whisker/right/pressure":
            return [(conn.topic, "std_msgs/msg/String", "string data", ts, string_cdr)]
        return [(conn.topic, conn.msgtype, conn.msgdef.data, ts, raw)]

    _copy_bag(demo / "free_flight" / "raw_bag", tmp_path / "bag", t)
    m, err = replay(tmp_path / "bag", tmp_path / "out")
    assert [w["kind"] for w in m["warnings"]] == ["skipped_topic"]
    msg = m["warnings"][0]["message"]
    assert "/whisker/right/pressure" in msg and "std_msgs/msg/String" in msg
    assert "replaying only /whisker/left/pressure" in msg
    assert f"tactile replay: warning: {msg}" in err.splitlines()
    assert list(m["modes"]["tdorc"]["whiskers"]) == ["/whisker/left"]


def test_rebuilt_metadata_and_corrupt_messages_are_said(demo, tmp_path):
    bag = tmp_path / "bag"

    def t(conn, ts, raw):
        if conn.topic == "/whisker/left/pressure" and t.n < 3:
            t.n += 1
            raw = raw[:10]  # truncated CDR: does not decode
        return [(conn.topic, conn.msgtype, conn.msgdef.data, ts, raw)]

    t.n = 0
    _copy_bag(demo / "free_flight" / "raw_bag", bag, t)
    (bag / "metadata.yaml").unlink()
    m, err = replay(bag, tmp_path / "out")
    kinds = {w["kind"]: w["count"] for w in m["warnings"]}
    assert kinds == {"metadata_rebuilt": 1, "source_errors": 3}, m["warnings"]
    assert "no metadata.yaml" in m["warnings"][0]["message"]
    lines = [l for l in err.splitlines() if l.startswith("tactile replay: warning: ")]
    assert len(lines) == 2, err


def _mcap_chunks(data):
    """(begin, end) of the top-level chunk records of an mcap file (record framing walk)."""
    spans, pos = [], 8
    while pos + 9 <= len(data):
        op, length = data[pos], struct.unpack_from("<Q", data, pos + 1)[0]
        if op == 0x06:
            spans.append((pos, pos + 9 + length))
        if op == 0x0F:
            break
        pos += 9 + length
    return spans


def _rechunk(path, chunk_size):
    """Rewrites an mcap file with the independent Python mcap writer in chunks of
    chunk_size bytes (zstd), so that a damaged chunk leaves others intact."""
    from mcap.reader import make_reader
    from mcap.writer import Writer as McapWriter

    out = path.with_suffix(".tmp")
    with open(path, "rb") as f, open(out, "wb") as g:
        reader = make_reader(f)
        writer = McapWriter(g, chunk_size=chunk_size)
        writer.start(profile="ros2", library="test")
        schemas, channels = {}, {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(channel.topic, channel.message_encoding,
                                                               schemas[schema.id], channel.metadata)
            writer.add_message(channels[channel.id], message.log_time, message.data, message.publish_time)
        writer.finish()
    out.replace(path)


def _damaged_copy(demo, tmp_path, name, damage, chunk_size=None):
    bag = tmp_path / name
    shutil.copytree(demo / "free_flight" / "raw_bag", bag)
    mcap = next(bag.glob("*.mcap"))
    if chunk_size:
        _rechunk(mcap, chunk_size)
    data = bytearray(mcap.read_bytes())
    spans = _mcap_chunks(data)
    assert len(spans) >= (2 if chunk_size else 1), len(spans)
    mcap.write_bytes(damage(data, spans))
    return bag


def test_damaged_chunk_is_skipped_counted_and_said(demo, tmp_path):
    # Issue 32: one flipped bit in a chunk refused the whole bag. The chunk is skipped and
    # the rest replayed, with one bag_damaged warning naming the chunk.
    def flip(data, spans):
        b, e = spans[1]
        data[(b + e) // 2] ^= 0x10
        return bytes(data)

    bag = _damaged_copy(demo, tmp_path, "flipped", flip, chunk_size=64 * 1024)
    m, err = replay(bag, tmp_path / "out")
    kinds = {w["kind"]: w["count"] for w in m["warnings"]}
    assert kinds.get("bag_damaged") == 1, m["warnings"]
    msg = next(w["message"] for w in m["warnings"] if w["kind"] == "bag_damaged")
    assert "1 damaged chunk(s) skipped" in msg and "lost" in msg
    assert f"tactile replay: warning: {msg}" in err.splitlines()


def test_bag_cut_inside_its_first_chunk_is_an_error(demo, tmp_path):
    # Issue 32: such a bag replayed 0 messages with exit 0 and "FPR 0.00 %".
    bag = _damaged_copy(demo, tmp_path, "cut", lambda data, spans: bytes(data[:(spans[0][0] + spans[0][1]) // 2]))
    out = tmp_path / "out"
    r = subprocess.run([TACTILE, "--config", CONFIG, "replay", str(bag), "--out", str(out), "--no-png"],
                       capture_output=True, text=True)
    assert r.returncode != 0
    assert "nothing recovered" in r.stderr and "no mcap footer" in r.stderr, r.stderr
    assert "FPR" not in r.stdout
    assert not (out / "metrics.json").exists()


def test_bag_of_a_namespaced_launch_replays_with_its_ground_truth(demo, tmp_path):
    """A launch with namespace:=cf1 records /cf1/whisker/left/pressure and
    /cf1/ground_truth/whisker/left/contact: the contact bag under those names replays as
    the root bag does, its ground truth used (the false positives counted on the truth's
    free samples), the whiskers named by their namespaced topics."""
    def ns(conn, ts, raw):
        return [("/cf1" + conn.topic, conn.msgtype, conn.msgdef.data, ts, raw)]

    src = demo / "contact" / "raw_bag"
    with Reader(src) as r:
        assert any(c.topic.startswith("/ground_truth/") for c in r.connections)
    _copy_bag(src, tmp_path / "bag", ns)
    root, _ = replay(src, tmp_path / "root")
    m, err = replay(tmp_path / "bag", tmp_path / "out")
    assert m["warnings"] == [], err
    assert m["fpr_basis"] == root["fpr_basis"] and "ground truth says no contact" in m["fpr_basis"]
    for mode, r in root["modes"].items():
        got = m["modes"][mode]
        assert list(got["whiskers"]) == ["/cf1" + w for w in r["whiskers"]]
        assert list(got["whiskers"].values()) == list(r["whiskers"].values())
