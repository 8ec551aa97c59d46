"""Independent check of the elastica solver with scipy's collocation BVP solver
(solve_bvp): a cantilever with a load F normal to the whisker at s_a
(frictionless contact, 002 Sec. VI-A), E I phi'' = -F cos(phi - phi_a),
phi(0) = 0, phi'(s_a) = 0, phi(s_a) = phi_a (unknown parameter), x' = cos phi,
y' = sin phi. Force mode and point mode of the C++ solver must agree."""
import os
import subprocess

import numpy as np
from scipy.integrate import solve_bvp

EXE = os.environ["ELASTICA_CSV"]
EI = 52e9 * 5.555e-15  # 002 Sec. V-A


def run(lines):
    out = subprocess.run([EXE], input="\n".join(lines) + "\n", capture_output=True, text=True, check=True).stdout
    return [list(map(float, row.split())) for row in out.strip().splitlines()]


def bvp(force, s_a):
    s = np.linspace(0.0, s_a, 200)

    def f(t, y, p):
        phi, dphi, x, yy = y
        return np.vstack([dphi, -force / EI * np.cos(phi - p[0]), np.cos(phi), np.sin(phi)])

    def bc(ya, yb, p):
        return np.array([ya[0], ya[2], ya[3], yb[1], yb[0] - p[0]])

    guess_phi = force * s_a ** 2 / (2 * EI)
    y0 = np.vstack([guess_phi * (s / s_a) * (2 - s / s_a), np.full_like(s, guess_phi * 2 / s_a), s, 0 * s])
    sol = solve_bvp(f, bc, s, y0, p=[guess_phi], tol=1e-10, max_nodes=100000)
    assert sol.success, sol.message
    phi_a = sol.p[0]
    x_a, y_a = sol.sol(s_a)[2], sol.sol(s_a)[3]
    m0 = EI * sol.sol(0.0)[1]
    return phi_a, x_a, y_a, m0


def test_force_mode_matches_scipy_bvp():
    cases = [(1e-4, 0.07), (0.02, 0.05), (0.08, 0.06), (0.3, 0.04)]
    rows = run([f"normal {F} {s}" for F, s in cases])
    for (F, s_a), r in zip(cases, rows):
        ok, _, _, phi_a, cx, cy, m0 = r
        assert ok == 1
        ref = bvp(F, s_a)
        assert abs(phi_a - ref[0]) < 1e-6
        assert abs(cx - ref[1]) < 1e-7 and abs(cy - ref[2]) < 1e-7
        assert abs(m0 - ref[3]) < 1e-6 * max(abs(ref[3]), 1e-9)


def test_point_mode_reproduces_the_contact_point():
    points = [(0.035, 0.001), (0.055, 0.008), (0.07, 0.012), (0.045, -0.01)]
    rows = run([f"point {px} {py}" for px, py in points])
    for (px, py), r in zip(points, rows):
        ok, F, s_a, _, _, _, m0 = r
        assert ok == 1
        phi_a, x_a, y_a, m_ref = bvp(F, s_a)  # scipy with the C++ force and arc length
        assert abs(x_a - px) < 1e-7 and abs(y_a - py) < 1e-7
        assert abs(m0 - m_ref) < 1e-6 * abs(m_ref)
        assert s_a >= np.hypot(px, py)  # arc at least the chord
