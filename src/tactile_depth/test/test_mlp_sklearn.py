"""Independent check of the C++ MLP inference (000 eq. 12-14) against
scikit-learn: an MLPRegressor 3 -> 32 -> 32 -> 32 -> 1 (ReLU) is trained on
random data, exported to the tactile_depth model file format (weights[k] =
coefs_[k].T, out x in), and the C++ helper (path in $TACTILE_DEPTH_MLP_CSV)
must reproduce sklearn's predict() to 1e-5 on 1000 random inputs.
"""
import json
import os
import subprocess

import numpy as np
import pytest

sklearn = pytest.importorskip("sklearn")
from sklearn.neural_network import MLPRegressor  # noqa: E402


def train(seed):
    rng = np.random.default_rng(seed)
    x = rng.normal([40.0, -10.0, 25.0], [30.0, 20.0, 50.0], size=(400, 3))
    y = 80.0 + 0.3 * x[:, 0] - 0.1 * x[:, 1] + 0.05 * np.abs(x[:, 2]) + rng.normal(0, 1.0, 400)  # mm
    mean, std = x.mean(axis=0), x.std(axis=0)
    net = MLPRegressor(hidden_layer_sizes=(32, 32, 32), activation="relu", max_iter=200,
                       random_state=seed)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        net.fit((x - mean) / std, y)
    return net, mean, std


def whisker(net, mean, std, scale, offset):
    layers = []
    for k, (w, b) in enumerate(zip(net.coefs_, net.intercepts_)):
        last = k == len(net.coefs_) - 1
        layers.append({"weights": w.T.tolist(), "bias": b.tolist(),
                       "activation": "identity" if last else "relu"})
    return {"input_mean": mean.tolist(), "input_std": std.tolist(), "layers": layers,
            "output_scale": scale, "output_offset": offset}


def test_cpp_matches_sklearn(tmp_path):
    exe = os.environ.get("TACTILE_DEPTH_MLP_CSV")
    if not exe:
        pytest.skip("TACTILE_DEPTH_MLP_CSV not set (run through ctest)")
    left, ml, sl = train(1)
    right, mr, sr = train(2)
    model = {
        "format": "tactile_depth_mlp", "version": 1,
        "whiskers": {"left": whisker(left, ml, sl, 1.0, 0.0),
                     "right": whisker(right, mr, sr, 1e-3, 0.01)},  # mm -> m, plus an offset
        "units": {"input": "Pa (TDORC compensated S_p)", "output": "m"},
        "provenance": {"tool": "test_mlp_sklearn.py", "sklearn": sklearn.__version__, "seed": [1, 2]},
    }
    path = tmp_path / "model.json"
    path.write_text(json.dumps(model))
    rng = np.random.default_rng(3)
    x = rng.normal([40.0, -10.0, 25.0], [40.0, 30.0, 60.0], size=(1000, 3))
    sides = np.where(rng.random(1000) < 0.5, "left", "right")
    lines = "\n".join(f"{s},{a!r},{b!r},{c!r}" for s, (a, b, c) in zip(sides, x.tolist()))
    out = subprocess.run([exe, str(path)], input=lines, capture_output=True, text=True, check=True)
    got = np.array([float(v) for v in out.stdout.split()])
    assert got.shape == (1000,)
    expected = np.where(sides == "left",
                        left.predict((x - ml) / sl),
                        1e-3 * right.predict((x - mr) / sr) + 0.01)
    err = np.abs(got - expected)
    assert err.max() <= 1e-5, f"max |C++ - sklearn| = {err.max()}"
    # the check is not vacuous: outputs vary and ReLUs are active and inactive
    assert np.std(got[sides == "left"]) > 1.0
    h = np.maximum(0.0, ((x - ml) / sl) @ left.coefs_[0] + left.intercepts_[0])
    assert 0.05 < np.mean(h > 0) < 0.95


def test_cpp_rejects_broken_export(tmp_path):
    exe = os.environ.get("TACTILE_DEPTH_MLP_CSV")
    if not exe:
        pytest.skip("TACTILE_DEPTH_MLP_CSV not set (run through ctest)")
    net, m, s = train(1)
    w = whisker(net, m, s, 1.0, 0.0)
    w["layers"][1]["weights"] = np.asarray(w["layers"][1]["weights"]).T[:, :31].tolist()  # coefs_ not transposed
    model = {"format": "tactile_depth_mlp", "version": 1, "whiskers": {"left": w, "right": w},
             "units": {"input": "Pa", "output": "m"}, "provenance": {}}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(model))
    out = subprocess.run([exe, str(path)], input="", capture_output=True, text=True)
    assert out.returncode == 1
    assert "whiskers.left.layers[1].weights[0]" in out.stderr
