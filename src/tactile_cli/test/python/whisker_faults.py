"""Inject one time fault into a whisker's pressure topic of a rosbag2 bag,
written with the independent `rosbags` package (the bag's own message
definitions, CDR in and out). Used by test_replay_faults.py; also a command:

    python whisker_faults.py IN_BAG OUT_BAG CASE [--topic /whisker/left/pressure] [--index K]
    python whisker_faults.py sweep DEMO_DIR WORK_DIR --tactile EXE [--config DIR]

`sweep` takes the raw bags of a `tactile demo` output (free_flight/raw_bag,
contact/raw_bag), replays each with every case and prints TDORC's false
positives, FPR and contact detection per case next to the clean replay's
(--before: also with the time rules before issue 16, previous_time_rules.py).

CASE (sample K = the K-th message of the topic, 0-based; receive times, i.e.
the bag timestamps, stay as recorded unless said):
  ahead      header stamp of sample K 20 s ahead
  behind     header stamp of sample K 20 s behind
  swap       samples K and K+1 swapped (content, stamps, sequence numbers)
  gap        a 2 s stall: samples K .. K+99 never arrive (50 Hz)
  duplicate  sample K delivered twice (the copy received 1 ms later)
  clean      copied unchanged
"""
import argparse
import json
import shutil
import subprocess
import sys
from pathlib import Path

from rosbags.rosbag2 import Reader, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

CASES = ("clean", "ahead", "behind", "swap", "gap", "duplicate")
SECOND = 1_000_000_000


def _shift(stamp, ns):
    total = stamp.sec * SECOND + stamp.nanosec + ns
    stamp.sec, stamp.nanosec = divmod(total, SECOND)


def inject(src, dst, case, topic="/whisker/left/pressure", index=None):
    """Writes dst = src with `case` applied to `topic`; returns the index used."""
    if case not in CASES:
        raise ValueError(f"unknown case {case!r}, expected one of {CASES}")
    store = get_typestore(Stores.EMPTY)
    with Reader(src) as reader:
        for conn in reader.connections:
            store.register(get_types_from_msg(conn.msgdef.data, conn.msgtype))
        rows = [(conn, t, bytes(raw)) for conn, t, raw in reader.messages()]
        conns = list(reader.connections)
    target = [i for i, (c, _, _) in enumerate(rows) if c.topic == topic]
    if not target:
        raise ValueError(f"{src}: no topic {topic}")
    k = len(target) // 6 if index is None else index
    if not 0 <= k < len(target) - 101:
        raise ValueError(f"index {k} out of range for {len(target)} samples")
    msgtype = rows[target[0]][0].msgtype

    def msg(i):
        return store.deserialize_cdr(rows[i][2], msgtype)

    def put(i, m):
        rows[i] = (rows[i][0], rows[i][1], bytes(store.serialize_cdr(m, msgtype)))

    if case in ("ahead", "behind"):
        m = msg(target[k])
        _shift(m.header.stamp, (20 if case == "ahead" else -20) * SECOND)
        put(target[k], m)
    elif case == "swap":
        a, b = target[k], target[k + 1]
        rows[a], rows[b] = (rows[a][0], rows[a][1], rows[b][2]), (rows[b][0], rows[b][1], rows[a][2])
    elif case == "gap":
        drop = set(target[k:k + 100])
        rows = [r for i, r in enumerate(rows) if i not in drop]
    elif case == "duplicate":
        c, t, raw = rows[target[k]]
        rows.insert(target[k] + 1, (c, t + 1_000_000, raw))
    rows.sort(key=lambda r: r[1])  # stable: bag order by receive time

    dst = Path(dst)
    with Writer(dst, version=9) as writer:
        out = {}
        for c in conns:
            out[c.id] = writer.add_connection(
                c.topic, c.msgtype, msgdef=c.msgdef.data, rihs01=c.digest or "RIHS01_" + "0" * 64,
                serialization_format=c.ext.serialization_format,
                offered_qos_profiles=c.ext.offered_qos_profiles)
        for c, t, raw in rows:
            writer.write(out[c.id], t, raw)
    return k


def replay(tactile, config, bag, out):
    """Runs `tactile replay` without the plot; returns (metrics, stderr)."""
    r = subprocess.run([tactile, "--config", config, "replay", str(bag), "--out", str(out), "--no-png"],
                       capture_output=True, text=True, check=True)
    return json.loads((Path(out) / "metrics.json").read_text()), r.stderr


def sweep(demo, work, tactile, config, before=False):
    work = Path(work)
    if before:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        import previous_time_rules
    print(f"{'bag':12} {'case':10} {'FP':>6} {'FP+TN':>7} {'FPR TDORC':>10} {'FPR band-pass':>14} "
          f"{'contact':>8} {'detected samples':>17} warnings")
    for name in ("free_flight", "contact"):
        for case in CASES:
            bag = work / name / case
            if bag.exists():
                shutil.rmtree(bag)
            bag.parent.mkdir(parents=True, exist_ok=True)
            inject(Path(demo) / name / "raw_bag", bag, case)
            m, err = replay(tactile, config, bag, work / name / (case + "_out"))
            t = m["modes"]["tdorc"]
            det = sum(w["detected_contact_samples"] for w in t["whiskers"].values())
            kinds = ",".join(f"{w['kind']}={w['count']}" for w in m.get("warnings", []))
            print(f"{name:12} {case:10} {t['false_positives']:6d} {t['false_positives'] + t['true_negatives']:7d} "
                  f"{100 * t['fpr']:9.2f}% {100 * m['fpr_bandpass']:13.2f}% {str(m['contact_detected']):>8} "
                  f"{det:17d} {kinds}")
            if before:
                b = previous_time_rules.evaluate(bag, config)
                bdet = sum(w["detected_contact_samples"] for w in b["whiskers"].values())
                print(f"{'  before':23} {b['false_positives']:6d} {b['false_positives'] + b['true_negatives']:7d} "
                      f"{100 * b['fpr']:9.2f}% {'':>14} {str(b['contact_detected']):>8} {bdet:17d}", flush=True)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "sweep":
        ap = argparse.ArgumentParser(prog="whisker_faults.py sweep")
        ap.add_argument("demo")
        ap.add_argument("work")
        ap.add_argument("--tactile", required=True)
        ap.add_argument("--config", default="config")
        ap.add_argument("--before", action="store_true",
                        help="also the previous time rules (previous_time_rules.py, numpy reference)")
        a = ap.parse_args(argv[1:])
        sweep(a.demo, a.work, a.tactile, a.config, a.before)
        return 0
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("case", choices=CASES)
    ap.add_argument("--topic", default="/whisker/left/pressure")
    ap.add_argument("--index", type=int, default=None)
    a = ap.parse_args(argv)
    k = inject(a.src, a.dst, a.case, a.topic, a.index)
    print(f"{a.case} at sample {k} of {a.topic} -> {a.dst}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
