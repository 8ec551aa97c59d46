"""The whisker path's time rules before issue 16, for the before/after table of
the READMEs: `tactile replay`'s TDORC evaluation recomputed from a raw bag with
the numpy reference of 000 eq. 4-11 (tdorc_filter/test/test_tdorc_numpy.py)
and the previous node logic's rules: the driver passed every message through;
tdorc_filter dropped a sample whose stamp was not after the last accepted one
and reset the filter when the stamp advanced by more than 0.5 s.

    python previous_time_rules.py BAG [--config DIR]

prints TDORC's false positives, counted pairs, FPR and contact detection, as
`tactile replay` counts them (metrics.json `modes.tdorc`). On a clean bag it
gives the same counts as the current `tactile replay` (checked in the README
table: the rules only differ on bad stamps).
"""
import argparse
import sys
from pathlib import Path

import numpy as np
import yaml
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[2] / "tdorc_filter" / "test"))
from test_tdorc_numpy import reference  # noqa: E402

GAP_NS = 500_000_000  # previous max_sample_gap_s


def _ns(stamp):
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def read(bag):
    store = get_typestore(Stores.EMPTY)
    out = {}
    with Reader(bag) as r:
        for c in r.connections:
            store.register(get_types_from_msg(c.msgdef.data, c.msgtype))
        for c, t, raw in r.messages():  # bag order: receive time
            out.setdefault(c.topic, []).append(store.deserialize_cdr(raw, c.msgtype))
    return out


def evaluate(bag, config):
    with open(Path(config) / "tdorc_filter.yaml") as f:
        tp = yaml.safe_load(f)["/**/tdorc_filter"]["ros__parameters"]
    msgs = read(bag)
    result = {"false_positives": 0, "true_negatives": 0, "contact_detected": False, "whiskers": {}}
    for side in ("left", "right"):
        pressure = msgs.get(f"/whisker/{side}/pressure", [])
        truth = msgs.get(f"/ground_truth/whisker/{side}/contact", [])
        t_stamps = np.array([_ns(m.header.stamp) for m in truth], dtype=np.int64)
        t_contact = [m.contact for m in truth]
        # Previous tdorc_filter rules: drop stamp <= last, reset on a gap > 0.5 s.
        segments, last = [[]], None
        for m in pressure:
            t = _ns(m.header.stamp)
            if last is not None and t <= last:
                continue
            if last is not None and t - last > GAP_NS:
                segments.append([])
            segments[-1].append((t, np.array(m.pressure, dtype=float)))
            last = t
        fp = tn = true_c = det_c = 0
        detected = False
        for seg in segments:
            if not seg:
                continue
            S = np.array([p for _, p in seg])
            ref = reference(S, tp["mode"], n=tp["window"], threshold=tp["contact_threshold"],
                            absolute=tp["absolute_threshold"], delay=tp["learn_delay"], hold=tp["contact_hold"],
                            max_hold=tp["max_contact_hold"], release=tp["hold_release_fraction"],
                            release_samples=tp["hold_release_samples"], drop=tp["hold_release_drop"],
                            level_samples=tp["hold_level_samples"], max_slope=tp["max_drift_slope"])
            for (t, _), row in zip(seg, ref):
                i = np.searchsorted(t_stamps, t, side="right")
                in_contact = bool(t_contact[i - 1]) if i > 0 else False
                ch = row[6:9] > tp["contact_threshold"]
                if in_contact:
                    true_c += 1
                    if row[1] == 1:
                        det_c += 1
                        detected = True
                elif row[0] == 1:
                    fp += int(ch.sum())
                    tn += 3 - int(ch.sum())
        result["false_positives"] += fp
        result["true_negatives"] += tn
        result["contact_detected"] |= detected
        result["whiskers"][f"/whisker/{side}"] = {"false_positives": fp, "true_negatives": tn,
                                                  "true_contact_samples": true_c,
                                                  "detected_contact_samples": det_c}
    n = result["false_positives"] + result["true_negatives"]
    result["fpr"] = result["false_positives"] / n if n else 0.0
    return result


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("bag")
    ap.add_argument("--config", default="config")
    a = ap.parse_args(argv)
    r = evaluate(a.bag, a.config)
    det = sum(w["detected_contact_samples"] for w in r["whiskers"].values())
    print(f"FP {r['false_positives']} of {r['false_positives'] + r['true_negatives']} pairs, "
          f"FPR {100 * r['fpr']:.2f} %, contact detected {r['contact_detected']}, detected samples {det}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
