"""Model file of the tactile-depth MLP (paper 000, "Whisker sensor model", eq. 12-14):
export from scikit-learn, load, and a pure-numpy forward pass that is the reference of
the C++ loader (src/tactile_depth).

File format (`tactile_depth_mlp`, version 1), per whisker:
    s_n    = (S - input_mean) / input_std                   000 eq. 12; S = S_p (input_signal
                                                             "compensated", the paper) or S_c
                                                             ("calibrated"), optional key
    h^k    = act_k(W^k h^(k-1) + b^k)                       000 eq. 13 (relu), eq. 14 (identity)
    depth  = output_scale * h^(L+1) + output_offset         [m]
`weights[k]` is out x in (scikit-learn `coefs_[k].T`).
"""
import json

import numpy as np

FORMAT = "tactile_depth_mlp"
VERSION = 1
ACTIVATIONS = ("relu", "identity")


def export_whisker(mlp, input_mean, input_std, output_scale=1.0, output_offset=0.0):
    """One whisker entry from a fitted sklearn MLPRegressor (activation relu)."""
    if mlp.activation != "relu":
        raise ValueError(f"only relu hidden layers are exported, got {mlp.activation}")
    n = len(mlp.coefs_)
    layers = []
    for k, (w, b) in enumerate(zip(mlp.coefs_, mlp.intercepts_)):
        layers.append({
            "weights": np.asarray(w, dtype=float).T.tolist(),
            "bias": np.asarray(b, dtype=float).ravel().tolist(),
            "activation": "relu" if k < n - 1 else "identity",
        })
    return {
        "input_mean": [float(v) for v in np.asarray(input_mean).ravel()],
        "input_std": [float(v) for v in np.asarray(input_std).ravel()],
        "layers": layers,
        "output_scale": float(output_scale),
        "output_offset": float(output_offset),
    }


INPUT_SIGNALS = {"compensated": "Pa (TDORC compensated S_p, 000 eq. 9-11)",
                 "calibrated": "Pa (TDORC calibrated S_c, 000 eq. 5)"}


def make_model(whiskers, provenance, input_signal="compensated"):
    if input_signal not in INPUT_SIGNALS:
        raise ValueError(f"input_signal: expected one of {sorted(INPUT_SIGNALS)}, got {input_signal!r}")
    return {
        "format": FORMAT,
        "version": VERSION,
        "whiskers": whiskers,
        "units": {"input": INPUT_SIGNALS[input_signal], "output": "m"},
        "input_signal": input_signal,
        "provenance": provenance,
    }


def save_model(model, path):
    # json writes floats with repr(): the shortest text that reads back to the same double.
    with open(path, "w") as f:
        json.dump(model, f, indent=1, allow_nan=False)
        f.write("\n")


def load_model(path):
    with open(path) as f:
        model = json.load(f)
    validate_model(model)
    return model


def validate_model(model):
    """Raise ValueError naming the key when the model does not follow the format."""
    if model.get("format") != FORMAT:
        raise ValueError(f"format: expected {FORMAT!r}, got {model.get('format')!r}")
    if model.get("version") != VERSION:
        raise ValueError(f"version: expected {VERSION}, got {model.get('version')!r}")
    if model.get("input_signal", "compensated") not in INPUT_SIGNALS:
        raise ValueError(f"input_signal: expected one of {sorted(INPUT_SIGNALS)}, got {model.get('input_signal')!r}")
    for side in ("left", "right"):
        w = model.get("whiskers", {}).get(side)
        if w is None:
            raise ValueError(f"whiskers.{side}: missing")
        n_in = len(w["input_mean"])
        if n_in != 3 or len(w["input_std"]) != 3:
            raise ValueError(f"whiskers.{side}.input_mean/input_std: expected 3 values")
        if not all(s > 0 for s in w["input_std"]):
            raise ValueError(f"whiskers.{side}.input_std: must be > 0")
        prev = n_in
        for k, layer in enumerate(w["layers"]):
            W = np.asarray(layer["weights"], dtype=float)
            b = np.asarray(layer["bias"], dtype=float)
            if W.ndim != 2 or W.shape[1] != prev or b.shape != (W.shape[0],):
                raise ValueError(f"whiskers.{side}.layers[{k}]: shape {W.shape} / bias {b.shape} "
                                 f"does not follow input size {prev}")
            if layer["activation"] not in ACTIVATIONS:
                raise ValueError(f"whiskers.{side}.layers[{k}].activation: {layer['activation']!r}")
            prev = W.shape[0]
        if prev != 1 or w["layers"][-1]["activation"] != "identity":
            raise ValueError(f"whiskers.{side}.layers: the last layer must have 1 output and identity activation")


def forward(whisker, sp):
    """Depth [m] of samples sp (N, 3) [Pa] through one whisker entry (pure numpy)."""
    x = (np.atleast_2d(np.asarray(sp, dtype=float)) - np.asarray(whisker["input_mean"])) / \
        np.asarray(whisker["input_std"])                                   # 000 eq. 12
    h = x.T
    for layer in whisker["layers"]:
        h = np.asarray(layer["weights"]) @ h + np.asarray(layer["bias"])[:, None]   # 000 eq. 13-14
        if layer["activation"] == "relu":
            h = np.maximum(h, 0.0)
    return whisker["output_scale"] * h[0] + whisker["output_offset"]
