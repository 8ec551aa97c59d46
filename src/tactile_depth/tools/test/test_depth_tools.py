"""Tests of the tactile-depth tools (make_dataset.py, depth_model.py, train_depth_model.py)
on tiny synthetic datasets; no simulator needed (the SITL extractor test is
test_depth_dataset_sitl.py)."""
import json
import math
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

TOOLS = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(TOOLS))
import depth_model  # noqa: E402
import make_dataset  # noqa: E402
import train_depth_model as tdm  # noqa: E402


def synthetic_dataset(n_flights=6, per_flight=60, seed=3):
    """Dataset dict in make_dataset's layout: S_p a smooth function of depth plus noise."""
    rng = np.random.default_rng(seed)
    n = n_flights * per_flight
    depth = rng.uniform(0.07, 0.14, size=(n, 2))
    gain = np.array([900.0, 500.0, 250.0])
    sp = (0.142 - depth)[:, :, None] * gain + rng.normal(0, 2.0, size=(n, 2, 3))
    flights = np.repeat(np.arange(1, n_flights + 1), per_flight)
    pose = np.zeros((n, 3))
    pose[:, 0] = rng.uniform(0.7, 0.8, n)
    contact = np.ones((n, 2), bool)
    contact[::7, 1] = False  # some samples with only one whisker touching
    depth[~contact] = np.nan
    return {
        "flight": flights, "t": np.tile(np.arange(per_flight) * 0.02, n_flights), "sp": sp, "depth": depth,
        "contact": contact, "ready": np.ones((n, 2), bool), "detected": contact.copy(), "pose": pose,
        "z": np.full(n, 0.4),
        "wall": np.array([[f, 1.0, 0.0, math.pi / 2] for f in range(1, n_flights + 1)]),
        "wall_fit_residual": np.zeros(n_flights), "base_x": np.float64(0.05), "spacing": np.float64(0.05),
        "scenario": np.str_("synthetic.yaml"), "seeds": np.arange(1, n_flights + 1),
        "arena_yaw_deg": np.zeros(n_flights),
    }


# ---------------------------------------------------------------------------- model file

def test_exported_file_forward_pass_reproduces_sklearn_predict(tmp_path):
    from sklearn.neural_network import MLPRegressor

    rng = np.random.default_rng(0)
    x = rng.normal(size=(300, 3)) * [50.0, 30.0, 10.0] + [20.0, -5.0, 3.0]
    y = 0.1 + 0.01 * np.tanh(x[:, 0] / 40) - 0.003 * x[:, 1] / 30
    mean, std = x.mean(axis=0), x.std(axis=0)
    y_off, y_scale = y.mean(), y.std()
    mlp = MLPRegressor(hidden_layer_sizes=(32, 32, 32), activation="relu", max_iter=60, random_state=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # convergence within 60 iterations is irrelevant here
        mlp.fit((x - mean) / std, (y - y_off) / y_scale)
    entry = depth_model.export_whisker(mlp, mean, std, output_scale=y_scale, output_offset=y_off)
    model = depth_model.make_model({"left": entry, "right": entry}, {"tool": "test"})
    path = tmp_path / "model.json"
    depth_model.save_model(model, path)
    loaded = depth_model.load_model(path)

    w = loaded["whiskers"]["left"]
    assert [len(layer["weights"]) for layer in w["layers"]] == [32, 32, 32, 1]
    assert [len(layer["weights"][0]) for layer in w["layers"]] == [3, 32, 32, 32]
    assert [layer["activation"] for layer in w["layers"]] == ["relu"] * 3 + ["identity"]
    # weights[k] = coefs_[k].T exactly (json keeps every double)
    for layer, c, b in zip(w["layers"], mlp.coefs_, mlp.intercepts_):
        np.testing.assert_array_equal(np.array(layer["weights"]), c.T)
        np.testing.assert_array_equal(np.array(layer["bias"]), b)
    x_test = rng.normal(size=(200, 3)) * [60.0, 40.0, 15.0]
    expected = mlp.predict((x_test - mean) / std) * y_scale + y_off
    got = depth_model.forward(w, x_test)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)
    # the forward pass is not vacuous: outputs vary over the inputs
    assert np.ptp(got) > 1e-3


def test_forward_pass_by_hand():
    # 3 -> 2 (relu) -> 1: s_n = (S_p - mu) / sigma, h = relu(W s_n + b), m = w h + c, depth = s m + o
    w = {"input_mean": [1.0, 2.0, 3.0], "input_std": [1.0, 2.0, 4.0], "output_scale": 0.5, "output_offset": 0.1,
         "layers": [{"weights": [[1.0, 0.0, 0.0], [0.0, 1.0, -1.0]], "bias": [0.0, -0.5], "activation": "relu"},
                    {"weights": [[2.0, 3.0]], "bias": [1.0], "activation": "identity"}]}
    # S_p = (3, 6, 3): s_n = (2, 2, 0); h = (2, 1.5); m = 4 + 4.5 + 1 = 9.5; depth = 4.85
    # S_p = (0, 2, 7): s_n = (-1, 0, 1); h = relu(-1, -1.5) = 0; m = 1; depth = 0.6
    np.testing.assert_allclose(depth_model.forward(w, [[3.0, 6.0, 3.0], [0.0, 2.0, 7.0]]), [4.85, 0.6], atol=1e-15)


@pytest.mark.parametrize("mutate, message", [
    (lambda m: m.update(format="other"), "format"),
    (lambda m: m.update(version=2), "version"),
    (lambda m: m["whiskers"].pop("right"), "whiskers.right"),
    (lambda m: m["whiskers"]["left"].update(input_std=[1.0, 0.0, 1.0]), "input_std"),
    (lambda m: m["whiskers"]["left"].update(input_mean=[1.0, 2.0]), "input_mean"),
    (lambda m: m["whiskers"]["left"]["layers"][0].update(weights=[[1.0, 2.0]]), "layers[0]"),
    (lambda m: m["whiskers"]["left"]["layers"][0].update(activation="tanh"), "activation"),
    (lambda m: m["whiskers"]["left"]["layers"].pop(), "last layer"),
])
def test_validate_rejects_malformed_models(mutate, message):
    w = {"input_mean": [0.0] * 3, "input_std": [1.0] * 3, "output_scale": 1.0, "output_offset": 0.0,
         "layers": [{"weights": [[1.0, 1.0, 1.0]] * 2, "bias": [0.0, 0.0], "activation": "relu"},
                    {"weights": [[1.0, 1.0]], "bias": [0.0], "activation": "identity"}]}
    model = depth_model.make_model({"left": json.loads(json.dumps(w)), "right": w}, {})
    depth_model.validate_model(model)
    mutate(model)
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("]", r"\]")):
        depth_model.validate_model(model)


def test_load_rejects_truncated_file(tmp_path):
    path = tmp_path / "m.json"
    path.write_text('{"format": "tactile_depth_mlp", "version": 1, "whiskers": {"left": {"input_mean": [1')
    with pytest.raises(json.JSONDecodeError):
        depth_model.load_model(path)


# ---------------------------------------------------------------------------- split and metrics

def test_split_is_by_flight():
    ids = np.repeat([12, 3, 7, 1, 2, 4, 5, 6, 8, 9, 10, 11], 5)  # unsorted, as read from disk
    sp = tdm.split_flights(ids)
    assert sp["train"] == [1, 2, 3, 4, 5, 6, 7, 8, 9]
    assert sp["test"] == [10, 11, 12]
    assert sp["fit"] == [1, 2, 3, 4, 5, 6, 7] and sp["val"] == [8, 9]
    d = synthetic_dataset(n_flights=12, per_flight=10)
    for part in ("fit", "val", "test"):
        x, y = tdm.whisker_samples(d, "right", sp[part])
        m = np.isin(d["flight"], sp[part]) & d["contact"][:, 1]
        np.testing.assert_array_equal(x, d["sp"][m, 1])
        np.testing.assert_array_equal(y, d["depth"][m, 1])
        assert set(np.unique(d["flight"][m])) == set(sp[part])
    # a small dataset keeps the proportions and never shares a flight between parts
    sp6 = tdm.split_flights(np.arange(1, 7))
    assert sp6["test"] == [5, 6] and sp6["val"] == [3, 4] and sp6["fit"] == [1, 2]
    with pytest.raises(ValueError):
        tdm.split_flights([1, 2])


def test_orientation_and_reconstruction_by_hand():
    # d_l - d_r = spacing -> 45 deg; equal depths -> 0 deg
    np.testing.assert_allclose(tdm.orientation_deg([0.10, 0.08], [0.05, 0.08], 0.05), [45.0, 0.0])
    # drone at the origin facing +x, wall x = 0.2 (point (0.2, 0), direction 90 deg), base 5 cm ahead
    pose = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.3, 0.0]])
    wall = np.array([[0.2, 0.0, math.pi / 2]] * 3)
    err = tdm.reconstruction_error(pose, [0.15, 0.17, 0.14], [0.15, 0.15, 0.14], wall, 0.05)
    np.testing.assert_allclose(err, [0.0, 0.01, 0.01], atol=1e-12)


def test_train_writes_model_and_report_with_every_key(tmp_path):
    a, b = tmp_path / "a.npz", tmp_path / "b.npz"
    np.savez(a, **synthetic_dataset(seed=3))
    np.savez(b, **synthetic_dataset(seed=4))
    out = tmp_path / "out"
    assert tdm.main(["--dataset", f"wb={a}", "--dataset", f"gl={b}", "--out", str(out), "--fast", "--seed", "7"]) == 0
    report = json.loads((out / "report.json").read_text())
    model = depth_model.load_model(out / "model.json")
    assert set(model) == {"format", "version", "whiskers", "units", "input_signal", "provenance"}
    assert model["input_signal"] == "compensated"  # the default: the paper's S_p (000 eq. 12)
    assert model["units"] == {"input": "Pa (TDORC compensated S_p, 000 eq. 9-11)", "output": "m"}
    for key in ("datasets", "train_flights", "test_flights", "tool", "python", "sklearn", "numpy", "seed", "date",
                "metrics"):
        assert key in model["provenance"], key
    assert model["provenance"]["seed"] == 7
    prov = model["provenance"]
    assert prov["train_flights"] == [{"dataset": "wb", "flights": [1, 2]}, {"dataset": "gl", "flights": [1, 2]}]
    assert prov["validation_flights"] == [{"dataset": "wb", "flights": [3, 4]}, {"dataset": "gl", "flights": [3, 4]}]
    assert prov["test_flights"] == [{"dataset": "wb", "flights": [5, 6]}, {"dataset": "gl", "flights": [5, 6]}]
    for side in ("left", "right"):
        assert set(model["whiskers"][side]) == {"input_mean", "input_std", "layers", "output_scale", "output_offset"}
    for ds in ("wb", "gl"):
        r = report["datasets"][ds]
        assert r["split"]["test"] == [5, 6]
        keys = {f"{m}@{run}" for m in ("MLP", "PolyFit", "GPR", "RFR") for run in ("wb+gl", "wb", "gl")}
        assert set(r["results"]) == keys
        for res in r["results"].values():
            for cat in ("whisker_left", "whisker_right", "orientation", "reconstruction"):
                assert set(res[cat]) == {"mae", "rmse", "n"}
                assert res[cat]["n"] > 0 and 0 <= res[cat]["mae"] <= res[cat]["rmse"]
            assert set(res["per_flight"]) == {"5", "6"}
        # The MLP metrics in the report are those of the written file: recompute one.
        d = dict(np.load(a if ds == "wb" else b))
        m = np.isin(d["flight"], [5, 6]) & d["contact"][:, 0]
        err = 1e3 * (depth_model.forward(model["whiskers"]["left"], d["sp"][m, 0]) - d["depth"][m, 0])
        assert r["results"]["MLP@wb+gl"]["whisker_left"]["mae"] == pytest.approx(np.mean(np.abs(err)), rel=1e-12)
        # a learnable synthetic relation: every model beats predicting the mean depth (~17.5 mm MAE)
        for res in r["results"].values():
            assert res["whisker_left"]["mae"] < 10.0
    md = (out / "report.md").read_text()
    assert "| MLP | wb+gl |" in md and "### gl" in md


def test_calibrated_input_trains_on_sc_and_says_so(tmp_path):
    # --input calibrated: every model reads S_c ('sc') instead of S_p; the file records it.
    d = synthetic_dataset(seed=3)
    d["sc"] = d["sp"] * 2.0 + 5.0  # a different, equally learnable input
    a = tmp_path / "a.npz"
    np.savez(a, **d)
    out = tmp_path / "out"
    assert tdm.main(["--dataset", f"wb={a}", "--out", str(out), "--fast", "--no-per-dataset",
                     "--input", "calibrated"]) == 0
    model = depth_model.load_model(out / "model.json")
    assert model["input_signal"] == "calibrated"
    assert model["provenance"]["input_signal"] == "calibrated"
    assert model["units"]["input"] == "Pa (TDORC calibrated S_c, 000 eq. 5)"
    # The standardisation is that of S_c on the fit flights, not of S_p.
    m = np.isin(d["flight"], model["provenance"]["train_flights"][0]["flights"]) & d["contact"][:, 0]
    np.testing.assert_allclose(model["whiskers"]["left"]["input_mean"], d["sc"][m, 0].mean(axis=0), rtol=1e-12)
    # A dataset without 'sc' is refused by name.
    del d["sc"]
    b = tmp_path / "b.npz"
    np.savez(b, **d)
    with pytest.raises(SystemExit):
        tdm.main(["--dataset", f"wb={b}", "--out", str(tmp_path / "o2"), "--fast", "--input", "calibrated"])
    bad = dict(model, input_signal="raw")
    with pytest.raises(ValueError, match="input_signal"):
        depth_model.validate_model(bad)


def test_training_is_deterministic(tmp_path):
    a = tmp_path / "a.npz"
    np.savez(a, **synthetic_dataset(seed=5))
    models = []
    for k in range(2):
        out = tmp_path / f"o{k}"
        tdm.main(["--dataset", f"wb={a}", "--out", str(out), "--fast", "--no-per-dataset"])
        m = json.loads((out / "model.json").read_text())
        models.append(m["whiskers"])
    assert models[0] == models[1]


def test_extractor_reports_a_failing_simulator(tmp_path):
    scen = tmp_path / "bad.yaml"
    scen.write_text("name: x\n")
    fake = tmp_path / "fake_tactile"
    fake.write_text("#!/bin/sh\necho 'bad.yaml: duration_s: required' >&2\nexit 1\n")
    fake.chmod(0o755)
    with pytest.raises(RuntimeError, match="duration_s: required"):
        make_dataset.main(["--scenario", str(scen), "--flights", "1", "--out", str(tmp_path / "o"),
                           "--tactile", str(fake), "--config", str(tmp_path)])
