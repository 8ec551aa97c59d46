#!/usr/bin/env python3
"""Tactile-depth dataset from SITL flights (paper 000, Methods "Data collection for
tactile depth estimation").

Runs `tactile sim SCENARIO --out RUN --seed k` for k = first_seed .. first_seed+flights-1
(one flight per seed), reads each run's bag with `rosbags` (message definitions stored in
the bag) and writes

    OUT/dataset.npz   one row per (flight, 50 Hz stamp) at which at least one whisker has
                      a true contact and a ready TDORC (arrays documented in DATASET_KEYS)
    OUT/dataset.csv   one row per (flight, stamp, whisker) sample used for training:
                      true contact and ready TDORC on that whisker
    OUT/runs/flight_<k>/   the raw `tactile sim` outputs (removed with --no-keep-runs)

Inputs are the TDORC-compensated signals S_p[3] (000 eq. 4-11, /whisker/<side>/signal
`compensated`), labels the true depth along body x (/ground_truth/whisker/<side>/contact
`depth`, 000 "depth d"). Usage:

    make_dataset.py --scenario config/scenarios/depth_whiteboard.yaml --flights 12 --out out/wb
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

SIDES = ("left", "right")

# Whisker base geometry in the body frame (x forward, y left) of the simulated whiskered
# Crazyflie (tactile_sim CrazyflieParams defaults: whisker_base_x = 5 cm ahead of the
# centre of mass, whisker_spacing = 5 cm, 000 "two whiskers mounted 5 cm apart").
DEFAULT_BASE_X = 0.05
DEFAULT_SPACING = 0.05

MIN_HEIGHT = 0.2  # [m] samples below it (take-off, landing, landed) are not used

DATASET_KEYS = {
    "flight": "(N,) int: flight id (= seed)",
    "t": "(N,) float: stamp [s] (simulated clock of the flight)",
    "sp": "(N, 2, 3) float: compensated S_p [Pa] of (left, right) x 3 barometers (000 eq. 11)",
    "sc": "(N, 2, 3) float: calibrated S_c = S_r - N_td [Pa] before the band-pass (000 eq. 5)",
    "depth": "(N, 2) float: true depth [m] along body x, NaN without contact",
    "contact": "(N, 2) bool: true contact (ground truth)",
    "ready": "(N, 2) bool: TDORC calibrated_ready",
    "detected": "(N, 2) bool: TDORC contact flag",
    "pose": "(N, 3) float: true x [m], y [m], yaw [rad] (/ground_truth/odom, same stamp)",
    "z": "(N,) float: true height [m]",
    "wall": "(F, 4) float: per flight: flight id, point x, point y, wall direction angle [rad] "
            "(line fitted to the true contact points; NaN if fewer than 2)",
    "wall_fit_residual": "(F,) float: RMS distance of the true contact points to the fitted line [m]",
    "base_x": "whisker base ahead of the centre of mass [m]",
    "spacing": "lateral distance between the whisker bases [m]",
    "scenario": "scenario file name",
    "seeds": "(F,) int: seeds flown",
    "arena_yaw_deg": "(F,) float: arena rotation of each flight (metrics.json)",
}


def _stamp_ns(header):
    return int(header.stamp.sec) * 10**9 + int(header.stamp.nanosec)


def read_bag(path, topics):
    """Messages of `topics` in the rosbag2 directory `path`, deserialized with the
    definitions stored in the bag: {topic: [msg, ...]} in log order."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    out = {t: [] for t in topics}
    with Reader(path) as reader:
        conns = [c for c in reader.connections if c.topic in out]
        for conn in conns:
            store.register(get_types_from_msg(conn.msgdef.data, conn.msgtype))
        for conn, _, raw in reader.messages(connections=conns):
            out[conn.topic].append(store.deserialize_cdr(raw, conn.msgtype))
    return out


def _yaw_from_quaternion(q):
    return np.arctan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def extract_flight(bag_dir, flight_id, min_height=MIN_HEIGHT):
    """Rows of one flight: dict of arrays (keys of DATASET_KEYS without the per-flight ones)
    for every stamp where at least one whisker has a true contact and a ready TDORC."""
    topics = [f"/whisker/{s}/signal" for s in SIDES] + \
             [f"/ground_truth/whisker/{s}/contact" for s in SIDES] + ["/ground_truth/odom"]
    msgs = read_bag(str(bag_dir), topics)
    for t in topics:
        if not msgs[t]:
            raise RuntimeError(f"{bag_dir}: no messages on {t}")

    per_side = []
    for s in SIDES:
        sig = {_stamp_ns(m.header): m for m in msgs[f"/whisker/{s}/signal"]}
        gt = {_stamp_ns(m.header): m for m in msgs[f"/ground_truth/whisker/{s}/contact"]}
        per_side.append((sig, gt))
    # Stamps where both whiskers have a signal and a truth sample (equal stamps by design).
    stamps = sorted(set.intersection(*[set(sig) & set(gt) for sig, gt in per_side]))
    if not stamps:
        raise RuntimeError(f"{bag_dir}: no common stamps of signal and ground truth")

    n = len(stamps)
    sp = np.full((n, 2, 3), np.nan)
    sc = np.full((n, 2, 3), np.nan)
    depth = np.full((n, 2), np.nan)
    contact = np.zeros((n, 2), bool)
    ready = np.zeros((n, 2), bool)
    detected = np.zeros((n, 2), bool)
    for j, (sig, gt) in enumerate(per_side):
        for i, st in enumerate(stamps):
            m, g = sig[st], gt[st]
            sp[i, j] = list(m.compensated)
            sc[i, j] = list(m.calibrated)
            ready[i, j] = bool(m.calibrated_ready)
            detected[i, j] = bool(m.contact)
            contact[i, j] = bool(g.contact)
            depth[i, j] = float(g.depth) if g.contact else np.nan

    # True pose at the signal stamps (odometry at 100 Hz; linear interpolation, yaw unwrapped).
    od = msgs["/ground_truth/odom"]
    ot = np.array([_stamp_ns(m.header) for m in od], dtype=np.int64)
    ox = np.array([m.pose.pose.position.x for m in od])
    oy = np.array([m.pose.pose.position.y for m in od])
    oz = np.array([m.pose.pose.position.z for m in od])
    oyaw = np.unwrap(np.array([_yaw_from_quaternion(m.pose.pose.orientation) for m in od]))
    st = np.array(stamps, dtype=np.int64)
    pose = np.stack([np.interp(st, ot, ox), np.interp(st, ot, oy), np.interp(st, ot, oyaw)], axis=1)
    z = np.interp(st, ot, oz)

    # Usable sample of a whisker: true contact, ready TDORC, finite values, airborne
    # (true height >= min_height: excludes touching the wall while landed, motors off).
    usable = contact & ready & np.isfinite(depth) & np.all(np.isfinite(sp), axis=2) & np.all(np.isfinite(sc), axis=2) & (z >= min_height)[:, None]
    keep = usable.any(axis=1)
    contact = contact & usable  # a whisker's sample is used only when it is usable
    return {
        "flight": np.full(int(keep.sum()), flight_id, dtype=np.int64),
        "t": st[keep] * 1e-9,
        "sp": sp[keep],
        "sc": sc[keep],
        "depth": np.where(contact[keep], depth[keep], np.nan),
        "contact": contact[keep],
        "ready": ready[keep],
        "detected": detected[keep],
        "pose": pose[keep],
        "z": z[keep],
    }


def contact_points(pose, depth, base_x=DEFAULT_BASE_X, spacing=DEFAULT_SPACING):
    """World contact points (N, 2, 2) of (left, right): base + depth * body x."""
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    out = np.empty(depth.shape + (2,))
    for j, side in enumerate((0.5, -0.5)):
        bx = base_x + depth[:, j]
        by = side * spacing
        out[:, j, 0] = pose[:, 0] + c * bx - s * by
        out[:, j, 1] = pose[:, 1] + s * bx + c * by
    return out


def fit_wall(points):
    """Total-least-squares line through points (M, 2): (px, py, angle, rms residual)."""
    if len(points) < 2:
        return np.nan, np.nan, np.nan, np.nan
    centre = points.mean(axis=0)
    _, sv, vt = np.linalg.svd(points - centre, full_matrices=False)
    direction = vt[0]
    return centre[0], centre[1], float(np.arctan2(direction[1], direction[0])), float(sv[-1] / np.sqrt(len(points)))


def write_csv(path, data):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["flight", "t_s", "whisker", "sp1_pa", "sp2_pa", "sp3_pa", "depth_m", "contact",
                    "tdorc_ready", "tdorc_contact", "x_m", "y_m", "yaw_rad"])
        for i in range(len(data["t"])):
            for j, side in enumerate(SIDES):
                if not data["contact"][i, j]:
                    continue
                w.writerow([int(data["flight"][i]), f"{data['t'][i]:.3f}", side,
                            *[repr(float(v)) for v in data["sp"][i, j]], repr(float(data["depth"][i, j])),
                            1, int(data["ready"][i, j]), int(data["detected"][i, j]),
                            *[repr(float(v)) for v in data["pose"][i]]])


def build_dataset(run_dirs, seeds, scenario_name, base_x=DEFAULT_BASE_X, spacing=DEFAULT_SPACING):
    """Concatenate the flights of `run_dirs` (each with bag/ and metrics.json)."""
    parts, walls, resid, yaws = [], [], [], []
    for run, seed in zip(run_dirs, seeds):
        d = extract_flight(Path(run) / "bag", seed)
        parts.append(d)
        pts = contact_points(d["pose"], d["depth"], base_x, spacing)[d["contact"]]
        px, py, ang, r = fit_wall(pts)
        walls.append([seed, px, py, ang])
        resid.append(r)
        metrics_path = Path(run) / "metrics.json"
        yaw = np.nan
        if metrics_path.exists():
            yaw = json.loads(metrics_path.read_text()).get("arena_yaw_deg", np.nan)
        yaws.append(np.nan if yaw is None else float(yaw))
    data = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    data["wall"] = np.array(walls, dtype=float).reshape(-1, 4)
    data["wall_fit_residual"] = np.array(resid, dtype=float)
    data["base_x"] = np.float64(base_x)
    data["spacing"] = np.float64(spacing)
    data["scenario"] = np.str_(scenario_name)
    data["seeds"] = np.array(seeds, dtype=np.int64)
    data["arena_yaw_deg"] = np.array(yaws, dtype=float)
    return data


def vehicle_geometry(scenario_path):
    """whisker_base_x and whisker_spacing of the scenario (its vehicle.params overrides)."""
    try:
        import yaml
        doc = yaml.safe_load(Path(scenario_path).read_text()) or {}
        params = (doc.get("vehicle") or {}).get("params") or {}
    except Exception:  # the simulator validates the file; geometry falls back to defaults
        params = {}
    return float(params.get("whisker_base_x", DEFAULT_BASE_X)), float(params.get("whisker_spacing", DEFAULT_SPACING))


def default_config_dir():
    env = os.environ.get("TACTILE_CONFIG_DIR")
    if env:
        return env
    repo_config = Path(__file__).resolve().parents[3] / "config"
    return str(repo_config) if repo_config.is_dir() else "config"


def run_flights(scenario, flights, out, first_seed=1, tactile=None, config_dir=None, log=print):
    tactile = tactile or os.environ.get("TACTILE_EXE") or "tactile"
    config_dir = config_dir or default_config_dir()
    run_dirs, seeds = [], []
    for k in range(flights):
        seed = first_seed + k
        run = Path(out) / "runs" / f"flight_{seed:02d}"
        if run.exists():
            shutil.rmtree(run)
        cmd = [tactile, "--config", config_dir, "sim", str(scenario), "--out", str(run), "--seed", str(seed),
               "--quiet", "--no-png"]
        res = subprocess.run(cmd, capture_output=True, text=True)
        if res.returncode != 0:
            raise RuntimeError(f"flight {seed}: {' '.join(cmd)} failed ({res.returncode}):\n{res.stderr}")
        log(f"flight {seed}: {res.stdout.strip()}")
        run_dirs.append(run)
        seeds.append(seed)
    return run_dirs, seeds


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenario", required=True, help="scenario file (config/scenarios/depth_*.yaml)")
    ap.add_argument("--flights", type=int, default=12, help="number of flights (seeds first_seed..)")
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--tactile", default=None, help="tactile executable (default: $TACTILE_EXE or PATH)")
    ap.add_argument("--config", default=None, help="parameter directory (default: $TACTILE_CONFIG_DIR or the repo's config/)")
    ap.add_argument("--no-keep-runs", action="store_true", help="delete the per-flight sim outputs afterwards")
    args = ap.parse_args(argv)
    if args.flights < 1:
        ap.error("--flights must be >= 1")

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    run_dirs, seeds = run_flights(args.scenario, args.flights, out, args.first_seed, args.tactile, args.config)
    base_x, spacing = vehicle_geometry(args.scenario)
    data = build_dataset(run_dirs, seeds, Path(args.scenario).name, base_x, spacing)
    np.savez_compressed(out / "dataset.npz", **data)
    write_csv(out / "dataset.csv", data)
    if args.no_keep_runs:
        shutil.rmtree(out / "runs")
    per_side = data["contact"].sum(axis=0)
    depths = data["depth"][data["contact"]]
    print(f"{out / 'dataset.npz'}: {len(seeds)} flights, {len(data['t'])} stamps, samples left {per_side[0]} "
          f"right {per_side[1]}, depth {1e3 * np.nanmin(depths):.1f}..{1e3 * np.nanmax(depths):.1f} mm, "
          f"wall-fit residual max {1e3 * np.nanmax(data['wall_fit_residual']):.3f} mm")
    for seed in seeds:
        m = data["flight"] == seed
        c = data["contact"][m]
        if not c.any():
            print(f"warning: flight {seed} has no usable contact sample", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
