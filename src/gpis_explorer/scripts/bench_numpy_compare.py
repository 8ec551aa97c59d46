#!/usr/bin/env python3
"""Side-by-side timing and agreement of the C++ GPIS explorer update with
numpy/scipy and scikit-learn's GaussianProcessRegressor (issue 18).

Runs the Google Benchmark executable bench_gpis (JSON output), times the same
steps on the same data (scripts/gpis_peer.py: the rotated-room points of
bench/bench_gpis.cpp) in numpy/scipy and with scikit-learn, and prints one
table: C++, numpy, sklearn [ms] and the ratios peer / C++. CPU time of each
process (Google Benchmark's cpu_time for C++, time.process_time() here);
OPENBLAS_NUM_THREADS=1 for all three unless set, so each uses one core.

Steps per update (paper 000 eq. 33-46): kernel matrix + Cholesky + alpha (from
scratch) or 5 new factor rows + alpha (incremental), the mean on the grid, the
variance map (every node, or variance_cells^2 nodes interpolated: kept between
updates by the new rows in C++ and numpy; scikit-learn predicts it again),
the zero contour (contourpy for the peers), curvature, corners, the variance at
the contour points and the target. scikit-learn has no incremental update: its
incremental rows refit.

Then the agreement of one update (gpis_update_json, installed next to
bench_gpis) with both peers: grid mean, contour variance, target; and the
error single precision would make (why the C++ stays in double).

With --online (scripts/bench.sh gpis): only the ground-scale rows (2000
points on 200 x 200 and 10000 on 400 x 400, 40 x 40 variance map), the local
solver's rows (BM_LocalUpdate*, README "Local solver") next to the exact C++
solver and the peers, and one summary line per size:
  gpis online update, N points: T s (exact ..., numpy ...; from scratch ...;
  max mean error ... near the surface)

Usage: bench_numpy_compare.py [path/to/bench_gpis] [--quick] [--online] [--cpp-json FILE]
       [--max-peer-points N] (peers only up to N points; the C++ rows all)
(--quick: onboard budget only; --cpp-json: take the C++ figures from that
bench_gpis JSON instead of running it; scripts/bench.sh does both in one run)
"""
import json
import os
import subprocess
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy.linalg import cho_factor, solve_triangular  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpis_peer as gp  # noqa: E402


def cpu_time(fn, min_time=0.5, max_reps=1000, setup=None):
    """CPU seconds per call of fn (setup, untimed, before each call)."""
    reps, total = 0, 0.0
    while True:
        if setup:
            setup()
        t0 = time.process_time()
        fn()
        total += time.process_time() - t0
        reps += 1
        if total >= min_time or reps >= max_reps:
            return total / reps


def find_bench():
    if len(sys.argv) > 1 and not sys.argv[1].startswith("--"):
        return sys.argv[1]
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(":") + ["install/gpis_explorer", "install"]:
        p = os.path.join(prefix, "lib", "gpis_explorer", "bench_gpis")
        if prefix and os.path.exists(p):
            return p
    sys.exit("bench_gpis not found: pass its path as the first argument")


def peer_scratch(n, cells, vcells, grid_variance=True):
    X, y = gp.room_points(n)
    big = n > 100

    def numpy_run():
        g = gp.NumpyGpis(cells, vcells if grid_variance else 0, capacity=n)
        if not grid_variance:
            g.variance_map = lambda: None
        g.fit(X, y)
        g.update()

    def sk_run():
        gp.sklearn_update(X, y, cells, vcells if grid_variance else None)

    kw = dict(min_time=0.0, max_reps=1) if big else dict(min_time=0.5, max_reps=2000)
    return cpu_time(numpy_run, **kw), cpu_time(sk_run, **kw)


def peer_incremental(n, cells, vcells):
    X, y = gp.room_points(n)
    g = gp.NumpyGpis(cells, vcells, capacity=n)
    g.fit(X[:-5], y[:-5])
    g.update()

    def run():
        g.add(X[-5:], y[-5:])
        g.update()

    reps = 1 if n > 5000 else 3 if n > 100 else 1000
    t = 0.0
    for _ in range(reps):
        t0 = time.process_time()
        run()
        t += time.process_time() - t0
        g.pop(5)
        if n <= 100 and t >= 0.5:
            reps = _ + 1
            break
    return t / reps


def agreement(n, cells, vcells, helper):
    X, y = gp.room_points(n)
    lines = [f"{cells},4.0,{vcells}"] + [f"{a!r},{b!r},{l!r}" for (a, b), l in zip(X.tolist(), y.tolist())]
    got = json.loads(subprocess.run([helper], input="\n".join(lines) + "\n", capture_output=True, text=True,
                                    check=True).stdout)
    g = gp.NumpyGpis(cells, vcells, capacity=n)
    g.fit(X, y)
    _, mean, _ = g.update()
    gpr = gp.sklearn_gpr().fit(X, y)
    G = g.G
    m = np.array(got["grid_mean"])
    scale = np.max(np.abs(mean))
    contours = [np.array(c["points"]) for c in got["contours"]]
    cvar = np.concatenate([c["variance"] for c in got["contours"]])
    P = np.vstack(contours)
    v_np = g.variance_at(P)
    v_sk = gpr.predict(P, return_std=True)[1] ** 2
    corners = []
    for c, Pc in zip(got["contours"], contours):
        corners += gp.corners_of(Pc, gp.derivatives(Pc, X, g.alpha), c["closed"])
    split = np.cumsum([len(c) for c in contours])[:-1]
    t_np = gp.select_target(contours, np.split(v_np, split), corners, -2.0, 2.0)
    t_sk = gp.select_target(contours, np.split(v_sk, split), corners, -2.0, 2.0)
    tc = np.array(got["target"])
    # single precision: Cholesky, mean and contour variance in float32
    A = (gp.kern(X, X) + gp.NOISE * np.eye(n)).astype(np.float32)
    L32 = np.linalg.cholesky(A)
    a32 = solve_triangular(L32, solve_triangular(L32, y.astype(np.float32), lower=True), lower=True, trans="T")
    m32 = gp.kern(G, X).astype(np.float32) @ a32
    V32 = solve_triangular(L32, gp.kern(X, P).astype(np.float32), lower=True)
    v32 = 1.0 - np.sum(V32.astype(np.float64) ** 2, 0)
    return dict(
        backend=got["backend"],
        mean_np=np.max(np.abs(m - mean)) / scale, mean_sk=np.max(np.abs(m - gpr.predict(G))) / scale,
        var_np=np.max(np.abs(cvar - v_np)), var_sk=np.max(np.abs(cvar - v_sk)),
        target_np=np.linalg.norm(tc - t_np), target_sk=np.linalg.norm(tc - t_sk),
        mean_f32=np.max(np.abs(m32 - mean)) / scale, var_f32=np.max(np.abs(v32 - v_np)))


def main():
    quick = "--quick" in sys.argv
    bench = find_bench()
    if "--cpp-json" in sys.argv:  # the JSON of a bench_gpis run (scripts/bench.sh)
        with open(sys.argv[sys.argv.index("--cpp-json") + 1]) as f:
            report = json.load(f)
    else:
        report = json.loads(subprocess.run(
            [bench, "--benchmark_format=json", "--benchmark_filter=BM_Update" + ("" if not quick else
             "(/50/|Incremental/50/)")], capture_output=True, text=True, check=True).stdout)
    cpp = {b["name"].split("/iterations")[0]: b["cpu_time"] * {"ms": 1e-3, "us": 1e-6, "ns": 1e-9}[b["time_unit"]]
           for b in report["benchmarks"]}
    max_peer = int(sys.argv[sys.argv.index("--max-peer-points") + 1]) if "--max-peer-points" in sys.argv else 10 ** 9
    print(f"{'update (CPU time, one core)':52s} {'C++ [ms]':>10s} {'numpy [ms]':>11s} {'sklearn [ms]':>13s}"
          f" {'numpy/C++':>10s} {'sklearn/C++':>12s}", flush=True)

    def show(name, c, p, s):
        cs = f"{c * 1e3:10.2f}" if c else f"{'-':>10s}"
        ps = f"{p * 1e3:11.2f}" if p else f"{'-':>11s}"
        ss = f"{s * 1e3:13.2f}" if s else f"{'-':>13s}"
        r1 = f"{p / c:10.1f}" if c and p else f"{'-':>10s}"
        r2 = f"{s / c:12.1f}" if c and s else f"{'-':>12s}"
        print(f"{name:52s} {cs} {ps} {ss} {r1} {r2}", flush=True)

    gp.sklearn_gpr().fit(*gp.room_points(20))  # import and first-call costs outside the timings
    sk_scratch = {}
    peers = {}  # the ground-scale peers measured below, reused by the local solver's rows
    if "--online" in sys.argv:
        online(cpp, report, max_peer, show)
        return
    cases = [(50, 10, 0, True), (2000, 200, 40, True), (2000, 200, 0, True), (2000, 200, 0, False),
             (10000, 400, 40, True)]
    for n, cells, vc, gv in cases:
        if quick and n > 50:
            continue
        t_np, t_sk = peer_scratch(n, cells, vc, gv) if n <= max_peer else (None, None)
        sk_scratch[(n, cells, vc, gv)] = t_sk
        peers[("scratch", n)] = (t_np, t_sk) if gv and vc == 40 else peers.get(("scratch", n))
        what = "no variance map" if not gv else (f"{vc}x{vc} variance map" if vc else "variance on every node")
        show(f"update {n} pts, {cells}x{cells}, {what}", cpp.get(f"BM_Update/{n}/{cells}/{int(gv)}/{vc}"), t_np, t_sk)
    for n, cells, vc in [(50, 10, 0), (2000, 200, 40), (10000, 400, 40)]:
        if quick and n > 50:
            continue
        t_np = peer_incremental(n, cells, vc) if n <= max_peer else None
        peers[("incremental", n)] = t_np
        t_sk = (sk_scratch.get((n, cells, vc, True)) or peer_scratch(n, cells, vc)[1]) if n <= max_peer else None
        show(f"+5 pts and update {n}, {cells}x{cells}" + (f", {vc}x{vc} map" if vc else ""),
             cpp.get(f"BM_UpdateIncremental/{n}/{cells}/{vc}"), t_np, t_sk)
    print("(sklearn has no incremental update: its '+5 pts' rows refit from scratch; '-': peer not run,"
          " --max-peer-points)")
    if any(k.startswith("BM_LocalUpdate") for k in cpp):
        print("\nthe local solver (README \"Local solver\") at ground scale, the peers above:")
        online(cpp, report, max_peer, show, peers)
    helper = os.path.join(os.path.dirname(bench), "gpis_update_json")
    if os.path.exists(helper):
        print(f"\nagreement of one update with the peers (C++ backend: ", end="")
        for n, cells, vc in [(50, 10, 0)] + ([] if quick else [(2000, 200, 40)]):
            a = agreement(n, cells, vc, helper)
            if n == 50:
                print(a["backend"] + ")")
            print(f"  {n} pts, {cells}x{cells}: grid mean {a['mean_np']:.1e} (numpy) {a['mean_sk']:.1e} (sklearn)"
                  f" of max|mean|; contour variance {a['var_np']:.1e} / {a['var_sk']:.1e}; target distance"
                  f" {a['target_np']:.1e} / {a['target_sk']:.1e} m")
            print(f"  {'':{len(str(n)) + len(str(cells)) * 2 + 8}s}float32 instead: grid mean {a['mean_f32']:.1e},"
                  f" contour variance {a['var_f32']:.1e}")
    print(f"onboard state (50 points, 10x10 grid, doubles): "
          f"{(50 * 5 + 50 * 50 + 2 * 100) * 8 / 1000:.1f} kB; paper 000 Fig. S6: 20.9 kB")


def online(cpp, report, max_peer, show, peers=None):
    """Ground scale: the local solver next to the exact C++ solver and the peers
    (timed here, or taken from `peers` when the full comparison measured them)."""
    counters = {b["name"].split("/iterations")[0]: b for b in report["benchmarks"]}
    summary = []
    for n, cells, vc in [(2000, 200, 40), (10000, 400, 40)]:
        big = n <= max_peer
        if peers is not None:
            t_np, t_sk = peers.get(("scratch", n)) or (None, None)
            t_sk = t_sk if n <= 2000 else None
        else:
            t_np, t_sk = peer_scratch(n, cells, vc) if big and n <= 2000 else (None, None)
        if peers is None and big and n > 2000:
            # scikit-learn's predict on the 400 x 400 grid holds the whole 160,000 x 10,000
            # kernel matrix (12.8 GB): not run at this size; numpy (blocked) alone.
            X, y = gp.room_points(n)

            def numpy_run():
                g = gp.NumpyGpis(cells, vc, capacity=n)
                g.fit(X, y)
                g.update()
            t_np = cpu_time(numpy_run, min_time=0.0, max_reps=1)
        if peers is not None:
            t_np_inc = peers.get(("incremental", n))
        else:
            t_np_inc = peer_incremental(n, cells, vc) if big else None
        ex_s = cpp.get(f"BM_Update/{n}/{cells}/1/{vc}")
        ex_i = cpp.get(f"BM_UpdateIncremental/{n}/{cells}/{vc}")
        lo_s = cpp.get(f"BM_LocalUpdate/{n}/{cells}/{vc}")
        lo_i = cpp.get(f"BM_LocalUpdateIncremental/{n}/{cells}/{vc}")
        show(f"exact, update {n} pts, {cells}x{cells}, {vc}x{vc} map", ex_s, t_np, t_sk)
        show(f"local, update {n} pts, {cells}x{cells}, {vc}x{vc} map", lo_s, t_np, t_sk)
        show(f"exact, +5 pts and update {n}, {cells}x{cells}", ex_i, t_np_inc, t_sk)
        show(f"local, +5 pts and update {n}, {cells}x{cells}", lo_i, t_np_inc, t_sk)
        c = counters.get(f"BM_LocalUpdate/{n}/{cells}/{vc}", {})

        def s_(t):
            return f"{t:.3f} s" if t else "-"
        summary.append(
            f"gpis online update, {n} points: {s_(lo_i)} (exact {s_(ex_i)}, numpy {s_(t_np_inc)}; from scratch"
            f" {s_(lo_s)}, exact {s_(ex_s)}, numpy {s_(t_np)}, sklearn {s_(t_sk)}; near the surface"
            f" ({int(c.get('near_nodes', 0))} nodes): max mean error {c.get('mean_err_max', float('nan')):.1e}"
            f" (avg {c.get('mean_err_avg', float('nan')):.1e}), max variance error"
            f" {c.get('var_err_max', float('nan')):.1e} (avg {c.get('var_err_avg', float('nan')):.1e});"
            f" {int(c.get('leaves', 0))} leaves, largest local GP {int(c.get('largest_local', 0))} points)")
    print("(numpy and sklearn are the exact GP; sklearn has no incremental update: its '+5 pts' rows refit;"
          " '-': not run, --max-peer-points)")
    for line in summary:
        print(line)


if __name__ == "__main__":
    main()
