#!/usr/bin/env python3
"""Summarises the interleaved rounds of scripts/bench.sh's `tactile sim` figures (issue 18).

Reads the rounds table bench.sh writes (one row per round: wall and CPU seconds of each
measurement) and prints every figure as the median and range over the rounds, with the
number of rounds that meet the issue's goal. The --jobs 2 speed-up is each round's own
ratio (--jobs 1 and --jobs 2 of one round ran a minute apart on the same machine), not a
ratio of medians.

Usage: src/tactile_cli/bench/bench_sim_summary.py ROUNDS.tsv --sim-s 75 --trials 10 [--scenario NAME]
"""
import argparse
import csv
import statistics
import sys

COLUMNS = ("w1", "c1", "wn", "cn", "w2", "c2", "wb", "cb", "wo", "co", "ws", "wp")
GOAL_RECORDED = 500.0  # recorded, one core: >= 500x real time
GOAL_JOBS = 1.8        # --jobs 2 >= 1.8x faster than --jobs 1


def read_rounds(path):
    rows = []
    with open(path, newline="") as f:
        for n, row in enumerate(csv.DictReader(f, delimiter="\t"), start=2):
            try:
                values = {k: float(row[k]) for k in COLUMNS}
            except (KeyError, TypeError, ValueError) as e:
                raise SystemExit(f"{path}:{n}: round {row.get('round', '?')}: missing or bad figure ({e}); "
                                 "a `tactile sim` run of that round failed")
            bad = [k for k, v in values.items() if not v > 0.0]
            if bad:
                raise SystemExit(f"{path}:{n}: round {row.get('round', '?')}: {', '.join(bad)} not positive "
                                 "(wall and CPU seconds divide the simulated time)")
            values["load"] = row.get("load", "")
            rows.append(values)
    if not rows:
        raise SystemExit(f"{path}: no rounds")
    return rows


def spread(values, fmt):
    """'median (min-max)' of values with fmt."""
    return f"{fmt(statistics.median(values))} ({fmt(min(values))}-{fmt(max(values))})"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rounds")
    ap.add_argument("--sim-s", type=float, required=True, help="simulated seconds per trial")
    ap.add_argument("--trials", type=int, required=True)
    ap.add_argument("--scenario", default="scenario")
    a = ap.parse_args(argv)
    if a.sim_s <= 0 or a.trials <= 0:
        raise SystemExit("--sim-s and --trials must be > 0")
    rows = read_rounds(a.rounds)
    sim_total = a.sim_s * a.trials
    x = lambda v: f"{v:.0f}x"  # noqa: E731
    r2 = lambda v: f"{v:.2f}x"  # noqa: E731
    recorded = [sim_total / r["w1"] for r in rows]
    recorded_cpu = [sim_total / r["c1"] for r in rows]
    not_recorded = [sim_total / r["wn"] for r in rows]
    not_recorded_cpu = [sim_total / r["cn"] for r in rows]
    recording_share = [100.0 * (r["c1"] - r["cn"]) / r["c1"] for r in rows]
    one_bag = [a.sim_s / r["wb"] for r in rows]
    one_nobag = [a.sim_s / r["wo"] for r in rows]
    jobs = [r["w1"] / r["w2"] for r in rows]
    ceiling = [2.0 * r["ws"] / r["wp"] for r in rows]
    n = len(rows)
    print(f"{a.scenario} ({a.sim_s:.0f} s simulated per trial), {n} interleaved rounds, median (range):")
    print(f"  recorded on one core (--trials {a.trials} --jobs 1): {spread(recorded, x)} real time per wall s, "
          f"{spread(recorded_cpu, x)} per CPU s; {sum(v >= GOAL_RECORDED for v in recorded)} of {n} rounds "
          f">= {GOAL_RECORDED:.0f}x")
    print(f"  not recorded (--no-bag): {spread(not_recorded, x)} per wall s, {spread(not_recorded_cpu, x)} per CPU s; "
          f"recording costs {spread(recording_share, lambda v: f'{v:.0f} %')} of the CPU time")
    print(f"  one run as a command (process start included): recorded {spread(one_bag, x)}, "
          f"not recorded {spread(one_nobag, x)}")
    print(f"  --trials {a.trials}: --jobs 2 vs --jobs 1, each round's ratio: {spread(jobs, r2)}; "
          f"{sum(v >= GOAL_JOBS for v in jobs)} of {n} rounds >= {GOAL_JOBS}x; the machine's ceiling for two "
          f"workers (two 5-trial processes side by side vs one alone): {spread(ceiling, r2)}")
    print("  per round (recorded x, --jobs 2 ratio, ceiling, load): " +
          "; ".join(f"{rec:.0f}x {j:.2f}x {c:.2f}x {r['load']}" for rec, j, c, r in zip(recorded, jobs, ceiling, rows)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
