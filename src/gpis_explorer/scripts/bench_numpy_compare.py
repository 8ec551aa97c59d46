#!/usr/bin/env python3
"""Side-by-side timing of the C++ GPIS explorer and a numpy/scipy reference.

Runs the Google Benchmark executable bench_gpis (path as the first argument,
default: lib/gpis_explorer/bench_gpis under $AMENT_PREFIX_PATH / ./install) with
JSON output, times the same steps in numpy/scipy on the same kind of data, and
prints one table with the ratio numpy / C++ (CPU time of this process for
numpy, CPU time reported by Google Benchmark for C++).

Steps per update (paper 000 eq. 33-46): kernel matrix + Cholesky + alpha,
mean (and variance) on the grid, zero contour (contourpy, the marching-squares
code matplotlib uses), gradient/Hessian/curvature at the contour points,
variance at the contour points, corner clustering and target.

Usage: bench_numpy_compare.py [path/to/bench_gpis] [--quick]
"""
import json
import os
import subprocess
import sys
import time

import contourpy
import numpy as np
from scipy.linalg import cho_factor, cho_solve, solve_triangular
from scipy.spatial.distance import cdist

BETA, C, NOISE, Q, PEN = 0.5, 1.0, 1e-2, -1.0, 0.2


def room_points(n, seed=42):
    rng = np.random.default_rng(seed)
    X = np.zeros((n, 2))
    y = np.zeros(n)
    for i in range(n):
        if i % 5 == 4:
            X[i] = rng.uniform(-0.7, 0.7, 2)
            y[i] = -1.0
        else:
            t = rng.uniform(-1, 1)
            X[i] = [(t, -1.0), (t, 1.0), (-1.0, t), (1.0, t)][i % 4]
            X[i] += rng.normal(0, 0.01, 2)
    a = 0.3
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return X @ R.T, y


def kern(A, B):
    return (C ** 2 + cdist(A, B, "sqeuclidean")) ** (-BETA)


def update(X, y, cells, grid_variance=True, size=4.0):
    cf = cho_factor(kern(X, X) + NOISE * np.eye(len(X)), lower=True)
    alpha = cho_solve(cf, y)
    g = np.linspace(-size / 2, size / 2, cells)
    gx, gy = np.meshgrid(g, g)
    G = np.stack([gx.ravel(), gy.ravel()], 1)
    mean = np.empty(len(G))
    var = np.full(len(G), np.nan)
    for s in range(0, len(G), 512):
        Ks = kern(G[s:s + 512], X)
        mean[s:s + 512] = Ks @ alpha
        if grid_variance:
            V = solve_triangular(cf[0], Ks.T, lower=True)
            var[s:s + 512] = C ** (-2 * BETA) - np.sum(V * V, 0)
    lines = contourpy.contour_generator(gx, gy, mean.reshape(cells, cells)).lines(0.0)
    corners, best, target = [], -np.inf, None
    for P in lines:
        D = P[:, None, :] - X[None, :, :]
        s = C ** 2 + np.sum(D * D, 2)
        s1 = s ** (-BETA - 1)
        grad = np.einsum("ij,ijk->ik", -2 * BETA * s1 * alpha, D)
        w = 4 * BETA * (BETA + 1) * s1 / s * alpha
        H = np.einsum("ij,ijk,ijl->ikl", w, D, D) + np.einsum("ij->i", -2 * BETA * s1 * alpha)[:, None, None] * np.eye(2)
        gn = np.linalg.norm(grad, axis=1)
        kappa = (np.einsum("ni,nij,nj->n", grad, H, grad) - gn ** 2 * np.trace(H, axis1=1, axis2=2)) / gn ** 3
        mask = kappa < Q
        idx = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
        for a, b in zip(idx[::2], idx[1::2]):
            corners.append(P[a:b].mean(0))
        Kp = kern(P, X)
        V = solve_triangular(cf[0], Kp.T, lower=True)
        pv = C ** (-2 * BETA) - np.sum(V * V, 0)
        pen = np.zeros(len(P))
        for ck in corners:
            pen = np.minimum(pen, -np.exp(-np.sum((P - ck) ** 2, 1) / (2 * PEN ** 2)))
        acq = pv + pen
        k = int(np.argmax(acq))
        if acq[k] > best:
            best, target = acq[k], P[k]
    return target, mean, var


def incremental_add(L, X, y, x, label):
    """New Cholesky row for x (O(n^2)), then alpha by two triangular solves."""
    l = solve_triangular(L, kern(X, x[None, :])[:, 0], lower=True)
    d = np.sqrt(C ** (-2 * BETA) + NOISE - l @ l)
    n = len(L)
    L2 = np.zeros((n + 1, n + 1))
    L2[:n, :n] = L
    L2[n, :n] = l
    L2[n, n] = d
    y2 = np.append(y, label)
    alpha = solve_triangular(L2.T, solve_triangular(L2, y2, lower=True), lower=False)
    return L2, alpha


def cpu_time(fn, min_time=0.5, max_reps=1000):
    reps, t0 = 0, time.process_time()
    while True:
        fn()
        reps += 1
        el = time.process_time() - t0
        if el >= min_time or reps >= max_reps:
            return el / reps


def find_bench():
    if len(sys.argv) > 1 and not sys.argv[1].startswith("--"):
        return sys.argv[1]
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(":") + ["install/gpis_explorer", "install"]:
        p = os.path.join(prefix, "lib", "gpis_explorer", "bench_gpis")
        if prefix and os.path.exists(p):
            return p
    sys.exit("bench_gpis not found: pass its path as the first argument")


def main():
    quick = "--quick" in sys.argv
    bench = find_bench()
    out = subprocess.run([bench, "--benchmark_format=json"], capture_output=True, text=True, check=True)
    cpp = {b["name"]: b["cpu_time"] * {"ms": 1e-3, "us": 1e-6, "ns": 1e-9}[b["time_unit"]]
           for b in json.loads(out.stdout)["benchmarks"]}
    rows = []
    for n, cells, gv in [(50, 10, 1), (2000, 200, 1), (2000, 200, 0)]:
        if quick and n > 50:
            continue
        X, y = room_points(n)
        t = cpu_time(lambda: update(X, y, cells, bool(gv)), min_time=0.5 if n < 100 else 0.0, max_reps=2000 if n < 100 else 1)
        rows.append((f"update {n} pts, {cells}x{cells} grid" + ("" if gv else ", mean only"),
                     cpp.get(f"BM_Update/{n}/{cells}/{gv}"), t))
    for n in (50, 2000):
        X, y = room_points(n)
        L = np.linalg.cholesky(kern(X[:-1], X[:-1]) + NOISE * np.eye(n - 1))
        t = cpu_time(lambda: incremental_add(L, X[:-1], y[:-1], X[-1], y[-1]))
        rows.append((f"incremental add, n = {n}", cpp.get(f"BM_IncrementalAdd/{n}"), t))
    print(f"{'step':42s} {'C++ [ms]':>12s} {'numpy [ms]':>12s} {'numpy / C++':>12s}")
    for name, c, p in rows:
        cs = f"{c * 1e3:12.3f}" if c else f"{'-':>12s}"
        ratio = f"{p / c:12.2f}" if c else f"{'-':>12s}"
        print(f"{name:42s} {cs} {p * 1e3:12.3f} {ratio}")
    print(f"onboard state (50 points, 10x10 grid, doubles): "
          f"{(50 * 5 + 50 * 50 + 2 * 100) * 8 / 1000:.1f} kB; paper 000 Fig. S6: 20.9 kB")


if __name__ == "__main__":
    main()
