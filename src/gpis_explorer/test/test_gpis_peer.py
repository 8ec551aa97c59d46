"""Agreement of one GPIS explorer update (C++, through the gpis_update_json
helper in $GPIS_UPDATE_JSON) with numpy/scipy and scikit-learn's
GaussianProcessRegressor on the same kernel and data (issue 18): grid mean,
variance at the contour points, variance map, the chosen target. Small sizes,
no timing. The peers are scripts/gpis_peer.py (written from 000 eq. 33-46).
Tolerance: 1e-6 of the value's scale (mean: max |mean|; variance: k(x, x) = 1).
"""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "scripts"))
import gpis_peer as gp  # noqa: E402

HELPER = os.environ.get("GPIS_UPDATE_JSON")
needs_helper = pytest.mark.skipif(HELPER is None, reason="GPIS_UPDATE_JSON not set (run through ctest)")


def run_cpp(X, y, cells, vcells, size=4.0):
    lines = [f"{cells},{size!r},{vcells}"] + [f"{a!r},{b!r},{l!r}" for (a, b), l in zip(X.tolist(), y.tolist())]
    out = subprocess.run([HELPER], input="\n".join(lines) + "\n", capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def test_rational_quadratic_is_the_imq_kernel():
    rng = np.random.default_rng(3)
    A, B = rng.uniform(-2, 2, (30, 2)), rng.uniform(-2, 2, (20, 2))
    np.testing.assert_allclose(gp.sklearn_gpr().kernel(A, B), gp.kern(A, B), rtol=1e-14, atol=0)


@needs_helper
@pytest.mark.parametrize("n,cells,vcells,seed", [(150, 41, 0, 1), (300, 60, 15, 2), (50, 10, 0, 3)])
def test_update_agrees_with_numpy_and_sklearn(n, cells, vcells, seed):
    X, y = gp.room_points(n, seed=seed)
    got = run_cpp(X, y, cells, vcells)
    assert got["status"] == "ok"
    ref = gp.NumpyGpis(cells, vcells, capacity=n)
    ref.fit(X, y)
    _, mean, var = ref.update()
    gpr = gp.sklearn_gpr().fit(X, y)
    # grid mean (000 eq. 34), numpy and scikit-learn
    m = np.array(got["grid_mean"])
    scale = np.max(np.abs(mean))
    np.testing.assert_allclose(m, mean, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(m, gpr.predict(ref.G), rtol=0, atol=1e-6 * scale)
    # variance map (eq. 35; interpolated from vcells^2 nodes when vcells > 0)
    np.testing.assert_allclose(np.array(got["grid_variance"]), var, rtol=0, atol=1e-6)
    if vcells == 0:
        np.testing.assert_allclose(np.array(got["grid_variance"]), gpr.predict(ref.G, return_std=True)[1] ** 2,
                                   rtol=0, atol=1e-6)
    # contours: the C++ marching squares gives the vertices contourpy gives
    lines = gp.contour_lines(ref.gx, ref.gy, mean, cells)
    cpp_pts = np.vstack([np.array(c["points"]) for c in got["contours"]])
    peer_pts = np.vstack([P for P, _ in lines])
    assert len(cpp_pts) == len(peer_pts)
    d = np.min(np.linalg.norm(cpp_pts[:, None, :] - peer_pts[None, :, :], axis=2), axis=1)
    assert d.max() < 1e-6
    # variance at the C++ contour points (eq. 35, 44), numpy and scikit-learn
    contours = [np.array(c["points"]) for c in got["contours"]]
    variances = []
    for c, P in zip(got["contours"], contours):
        v_np = ref.variance_at(P)
        v_sk = gpr.predict(P, return_std=True)[1] ** 2
        np.testing.assert_allclose(np.array(c["variance"]), v_np, rtol=0, atol=1e-6)
        np.testing.assert_allclose(np.array(c["variance"]), v_sk, rtol=0, atol=1e-6)
        variances.append(v_np)
    # the target: curvature, corners, penalty, exclusion and argmax by the peer
    corners = []
    for c, P in zip(got["contours"], contours):
        corners += gp.corners_of(P, gp.derivatives(P, X, ref.alpha), c["closed"])
    np.testing.assert_allclose(np.array(got["corners"]).reshape(-1, 2), np.array(corners).reshape(-1, 2), atol=1e-9)
    target = gp.select_target(contours, variances, corners, -2.0, 2.0)
    assert target is not None and got["target"] is not None
    np.testing.assert_allclose(got["target"], target, atol=1e-9)


@needs_helper
def test_incremental_variance_map_equals_from_scratch():
    """The variance map extended by the rows of added points equals the map of
    a fit from scratch (numpy peer: the same incremental rows)."""
    X, y = gp.room_points(200, seed=5)
    ref = gp.NumpyGpis(40, 12, capacity=200)
    ref.fit(X[:150], y[:150])
    ref.update()
    ref.add(X[150:], y[150:])
    _, _, var_inc = ref.update()
    got = run_cpp(X, y, 40, 12)
    np.testing.assert_allclose(np.array(got["grid_variance"]), var_inc, rtol=0, atol=1e-6)
