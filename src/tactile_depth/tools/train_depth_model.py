#!/usr/bin/env python3
"""Train and evaluate the tactile-depth sensor model (paper 000, "Whisker sensor model",
eq. 12-15; Table 1 and Table S1) on datasets written by make_dataset.py.

Per dataset, flights are split by flight id: the first `--train-flights` (9 of 12, 000
Methods) for training, the rest for testing. Of the training flights, the last
`--val-flights` are the validation split (early stopping of the MLP, hyperparameter
grid search of the baselines); every model is fitted on the remaining training flights.

Per whisker:
  MLP      z-scored S_p (000 eq. 12) -> 3-32-32-32-1 ReLU (eq. 13-14, the layout of the
           public onboard implementation), Adam on the MSE (eq. 15) of the z-scored
           depth, early stopping on the validation flights (best epoch kept)
  PolyFit  polynomial of the z-scored inputs, degree by grid search on validation
  GPR      GaussianProcessRegressor, ARD RBF + white noise, kernel hyperparameters by
           marginal likelihood on a subsample; kernel family chosen on validation
  RFR      RandomForestRegressor, grid search on validation

Metrics on the test flights (000 Table 1 / S1): MAE and RMSE of each whisker's depth [mm];
orientation theta = atan((d_l - d_r) / spacing) [deg] (spacing 0.05 m) against the same
formula on the true depths; reconstruction [mm]: distance of the contact point estimated
from the mean of both whiskers' depths (000 Supplementary: "we take the average of the
left and right whisker estimates") to the wall line, with the true pose.

The MLP model file (format of depth_model.py, the C++ loader's contract) is written from
the models trained on `--train-on` (default: all datasets, training flights pooled), and
the MLP metrics are computed through that file's numpy forward pass.

    train_depth_model.py --dataset whiteboard=out/wb/dataset.npz --dataset glass=out/gl/dataset.npz \
        --out out/model   # model.json, report.json, report.md
"""
import argparse
import datetime
import json
import math
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import depth_model  # noqa: E402

SIDES = ("left", "right")
MODELS = ("PolyFit", "GPR", "RFR", "MLP")
HIDDEN = (32, 32, 32)
CATEGORIES = ("whisker_left", "whisker_right", "orientation", "reconstruction")


# ---------------------------------------------------------------------------- data

def load_dataset(path):
    with np.load(path, allow_pickle=False) as z:
        d = {k: z[k] for k in z.files}
    return d


def split_flights(flight_ids, n_train=9, n_val=2):
    """By flight id (sorted): first n_train flights train, the rest test; the last n_val of
    the training flights are validation, the others 'fit'. Fewer than 12 flights: the
    same proportions (75 % train, at least one test and one validation flight)."""
    flights = sorted(int(f) for f in np.unique(flight_ids))
    n = len(flights)
    if n < 3:
        raise ValueError(f"need at least 3 flights to split, got {n}")
    if n_train >= n:
        n_train = max(2, int(round(0.75 * n)))
        n_train = min(n_train, n - 1)
    n_val = max(1, min(n_val, n_train - 1))
    train = flights[:n_train]
    return {"train": train, "fit": train[:n_train - n_val], "val": train[n_train - n_val:], "test": flights[n_train:]}


def whisker_samples(d, side, flights):
    j = SIDES.index(side)
    m = np.isin(d["flight"], flights) & d["contact"][:, j]
    return d["sp"][m, j, :], d["depth"][m, j]


# ---------------------------------------------------------------------------- models

class ZScore:
    """000 eq. 12: per-channel mean and (population) standard deviation of the fit data."""

    def __init__(self, x):
        self.mean = x.mean(axis=0)
        self.std = x.std(axis=0)
        self.std[self.std <= 0] = 1.0

    def __call__(self, x):
        return (x - self.mean) / self.std


def train_mlp(x_fit, y_fit, x_val, y_val, seed, max_epochs=400, patience=40, log=None):
    """MLP on z-scored inputs and target; Adam one epoch at a time, the weights of the
    epoch with the lowest validation MSE are kept. Returns the whisker entry of the model
    file and the training record."""
    from sklearn.neural_network import MLPRegressor

    zx = ZScore(x_fit)
    y_mean, y_std = float(y_fit.mean()), float(y_fit.std()) or 1.0
    xf, xv = zx(x_fit), zx(x_val)
    yf = (y_fit - y_mean) / y_std
    mlp = MLPRegressor(hidden_layer_sizes=HIDDEN, activation="relu", solver="adam", learning_rate_init=1e-3,
                       batch_size=min(64, len(xf)), alpha=1e-4, shuffle=True, random_state=seed)
    best = (math.inf, None, 0)
    history = []
    for epoch in range(1, max_epochs + 1):
        mlp.partial_fit(xf, yf)  # one epoch of Adam minibatches on the MSE (000 eq. 15)
        val_mse = float(np.mean((mlp.predict(xv) * y_std + y_mean - y_val) ** 2))
        history.append(val_mse)
        if val_mse < best[0]:
            best = (val_mse, ([c.copy() for c in mlp.coefs_], [b.copy() for b in mlp.intercepts_]), epoch)
        elif epoch - best[2] >= patience:
            break
    mlp.coefs_, mlp.intercepts_ = best[1]
    entry = depth_model.export_whisker(mlp, zx.mean, zx.std, output_scale=y_std, output_offset=y_mean)
    record = {"best_epoch": best[2], "epochs_run": len(history), "val_rmse_mm": 1e3 * math.sqrt(best[0])}
    if log:
        log(f"    MLP: best epoch {best[2]} of {len(history)}, validation RMSE {record['val_rmse_mm']:.2f} mm")
    return entry, mlp, record


def _val_rmse(model, x, y):
    return float(np.sqrt(np.mean((model.predict(x) - y) ** 2)))


def _grid(make, grid, x_fit, y_fit, x_val, y_val):
    """Fit make(**g) for every g in grid, keep the best on validation RMSE."""
    best = None
    for g in grid:
        m = make(**g).fit(x_fit, y_fit)
        r = _val_rmse(m, x_val, y_val)
        if best is None or r < best[0]:
            best = (r, g, m)
    return best[2], {"params": best[1], "val_rmse_mm": 1e3 * best[0]}


def train_polyfit(x_fit, y_fit, x_val, y_val, degrees=(1, 2, 3, 4, 5)):
    from sklearn.linear_model import LinearRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import PolynomialFeatures, StandardScaler

    def make(degree):
        return make_pipeline(StandardScaler(), PolynomialFeatures(degree), LinearRegression())
    return _grid(make, [{"degree": d} for d in degrees], x_fit, y_fit, x_val, y_val)


def train_gpr(x_fit, y_fit, x_val, y_val, seed, max_samples=600):
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, Matern, WhiteKernel
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    rng = np.random.default_rng(seed)
    if len(x_fit) > max_samples:  # exact GP is O(n^3): fit on a seeded subsample
        idx = np.sort(rng.choice(len(x_fit), max_samples, replace=False))
        x_fit, y_fit = x_fit[idx], y_fit[idx]
    kernels = {
        "rbf": lambda: ConstantKernel(1.0) * RBF(length_scale=np.ones(3), length_scale_bounds=(1e-2, 1e3))
        + WhiteKernel(1e-2, (1e-6, 1e1)),
        "matern52": lambda: ConstantKernel(1.0) * Matern(length_scale=np.ones(3), length_scale_bounds=(1e-2, 1e3), nu=2.5)
        + WhiteKernel(1e-2, (1e-6, 1e1)),
    }

    def make(kernel):
        return make_pipeline(StandardScaler(), GaussianProcessRegressor(kernel=kernels[kernel](), normalize_y=True,
                                                                        n_restarts_optimizer=1, random_state=seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # bound warnings of the kernel optimiser
        model, rec = _grid(make, [{"kernel": k} for k in kernels], x_fit, y_fit, x_val, y_val)
    rec["fitted_kernel"] = str(model[-1].kernel_)
    rec["fit_samples"] = int(len(x_fit))
    return model, rec


def train_rfr(x_fit, y_fit, x_val, y_val, seed, fast=False):
    from sklearn.ensemble import RandomForestRegressor

    grid = [{"max_depth": md, "min_samples_leaf": leaf} for md in ((None, 8) if fast else (None, 6, 12))
            for leaf in ((1, 10) if fast else (1, 5, 20))]

    def make(max_depth, min_samples_leaf):
        return RandomForestRegressor(n_estimators=50 if fast else 100, max_depth=max_depth,
                                     min_samples_leaf=min_samples_leaf, random_state=seed, n_jobs=1)
    return _grid(make, grid, x_fit, y_fit, x_val, y_val)


# ---------------------------------------------------------------------------- metrics

def _mae_rmse(err):
    err = np.asarray(err, dtype=float)
    if err.size == 0:
        return {"mae": None, "rmse": None, "n": 0}
    return {"mae": float(np.mean(np.abs(err))), "rmse": float(np.sqrt(np.mean(err ** 2))), "n": int(err.size)}


def orientation_deg(d_left, d_right, spacing):
    """theta = atan((d_l - d_r) / spacing) [deg] (000, wall angle from the two depths)."""
    return np.degrees(np.arctan((np.asarray(d_left) - np.asarray(d_right)) / spacing))


def reconstruction_error(pose, d_left, d_right, wall, base_x):
    """Distance [m] of the contact point base_mid + mean(d_l, d_r) * body x (true pose) to
    the wall line (px, py, direction angle)."""
    px, py, ang = wall[..., 0], wall[..., 1], wall[..., 2]
    reach = base_x + 0.5 * (np.asarray(d_left) + np.asarray(d_right))
    cx = pose[:, 0] + np.cos(pose[:, 2]) * reach
    cy = pose[:, 1] + np.sin(pose[:, 2]) * reach
    # normal of the line: (-sin(ang), cos(ang))
    return np.abs(-(cx - px) * np.sin(ang) + (cy - py) * np.cos(ang))


def evaluate(d, flights, predict):
    """Table 1 / S1 metrics of predict(side, sp) on the given flights, overall and per flight."""
    spacing, base_x = float(d["spacing"]), float(d["base_x"])
    walls = {int(w[0]): w[1:] for w in d["wall"]}

    def metrics(fl):
        m = np.isin(d["flight"], fl)
        pred = np.full((int(m.sum()), 2), np.nan)
        for j, side in enumerate(SIDES):
            c = d["contact"][m, j]
            if c.any():
                pred[c, j] = predict(side, d["sp"][m, j][c])
        truth = d["depth"][m]
        out = {}
        for j, side in enumerate(SIDES):
            c = d["contact"][m, j]
            out[f"whisker_{side}"] = _mae_rmse(1e3 * (pred[c, j] - truth[c, j]))
        both = d["contact"][m].all(axis=1)
        out["orientation"] = _mae_rmse(orientation_deg(pred[both, 0], pred[both, 1], spacing)
                                       - orientation_deg(truth[both, 0], truth[both, 1], spacing))
        wall = np.array([walls[int(f)] for f in d["flight"][m][both]]).reshape(-1, 3)
        out["reconstruction"] = _mae_rmse(1e3 * reconstruction_error(d["pose"][m][both], pred[both, 0],
                                                                     pred[both, 1], wall, base_x))
        return out

    res = metrics(flights)
    res["per_flight"] = {str(f): metrics([f]) for f in flights}
    return res


# ---------------------------------------------------------------------------- training runs

def train_all(datasets, names, seed, fast=False, log=print, gp_max=600):
    """Train every model per whisker on the 'fit' flights of the named datasets (pooled),
    with validation on their 'val' flights. Returns {model: {side: predictor}}, MLP model
    entries and records."""
    predictors = {m: {} for m in MODELS}
    entries, records = {}, {m: {} for m in MODELS}
    for side in SIDES:
        xf, yf, xv, yv = [], [], [], []
        for n in names:
            d, sp = datasets[n]
            a, b = whisker_samples(d, side, sp["fit"])
            xf.append(a), yf.append(b)
            a, b = whisker_samples(d, side, sp["val"])
            xv.append(a), yv.append(b)
        xf, yf, xv, yv = map(np.concatenate, (xf, yf, xv, yv))
        if len(xf) < 10 or len(xv) < 2:
            raise ValueError(f"{side}: too few samples (fit {len(xf)}, validation {len(xv)})")
        log(f"  {side}: fit {len(xf)} samples, validation {len(xv)}")
        t0 = time.time()
        entry, _, rec = train_mlp(xf, yf, xv, yv, seed, max_epochs=150 if fast else 600,
                                  patience=20 if fast else 100, log=log)
        rec["seconds"] = round(time.time() - t0, 2)
        entries[side], records["MLP"][side] = entry, rec
        predictors["MLP"][side] = (lambda e: (lambda x: depth_model.forward(e, x)))(entry)
        for name, fn in (("PolyFit", lambda: train_polyfit(xf, yf, xv, yv, (1, 2, 3) if fast else (1, 2, 3, 4, 5))),
                         ("GPR", lambda: train_gpr(xf, yf, xv, yv, seed, max_samples=150 if fast else gp_max)),
                         ("RFR", lambda: train_rfr(xf, yf, xv, yv, seed, fast))):
            t0 = time.time()
            model, rec = fn()
            rec["seconds"] = round(time.time() - t0, 2)
            records[name][side] = rec
            predictors[name][side] = model.predict
            log(f"    {name}: {rec['params'] if 'params' in rec else ''} validation RMSE {rec['val_rmse_mm']:.2f} mm")
    return predictors, entries, records


def _fmt(v):
    return "—" if v is None else f"{v:.2f}"


def markdown_report(report):
    lines = []
    for ds, r in report["datasets"].items():
        lines.append(f"### {ds} (test flights {', '.join(map(str, r['split']['test']))})")
        lines.append("")
        lines.append("| model | trained on | left MAE [mm] | left RMSE [mm] | right MAE [mm] | right RMSE [mm] | "
                     "orientation MAE [deg] | orientation RMSE [deg] | reconstruction MAE [mm] | reconstruction RMSE [mm] |")
        lines.append("| --- | --- | " + " | ".join(["---:"] * 8) + " |")
        for key, res in r["results"].items():
            cells = []
            for c in CATEGORIES:
                cells += [_fmt(res[c]["mae"]), _fmt(res[c]["rmse"])]
            lines.append(f"| {res['model']} | {res['trained_on']} | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", action="append", required=True, metavar="NAME=PATH",
                    help="dataset.npz of make_dataset.py (repeat for several)")
    ap.add_argument("--train-on", default="all", help="comma-separated dataset names for the model file, or 'all'")
    ap.add_argument("--out", required=True, help="directory for report.json, report.md (and model.json)")
    ap.add_argument("--model-out", default=None, help="model file path (default OUT/model.json)")
    ap.add_argument("--train-flights", type=int, default=9)
    ap.add_argument("--val-flights", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--input", choices=("compensated", "calibrated"), default="compensated",
                    help="MLP input: the band-passed S_p of 000 eq. 12 (compensated) or the drift-"
                         "corrected S_c before the band-pass (calibrated; the model file says which)")
    ap.add_argument("--gp-max-samples", type=int, default=600)
    ap.add_argument("--no-per-dataset", action="store_true", help="skip the models trained on each dataset alone")
    ap.add_argument("--fast", action="store_true", help="small grids and few epochs (tests)")
    args = ap.parse_args(argv)

    import scipy
    import sklearn

    datasets = {}
    for spec in args.dataset:
        if "=" not in spec:
            ap.error(f"--dataset {spec}: expected NAME=PATH")
        name, path = spec.split("=", 1)
        d = load_dataset(path)
        if args.input == "calibrated":
            if "sc" not in d:
                ap.error(f"--dataset {spec}: no calibrated signals ('sc'); rebuild it with make_dataset.py")
            d["sp"] = d["sc"]  # every model below reads its input from 'sp'
        datasets[name] = (d, split_flights(d["flight"], args.train_flights, args.val_flights))
    train_on = list(datasets) if args.train_on == "all" else args.train_on.split(",")
    for n in train_on:
        if n not in datasets:
            ap.error(f"--train-on: unknown dataset {n!r}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    runs = {"+".join(train_on): train_on}
    if not args.no_per_dataset and len(train_on) > 1:
        runs.update({n: [n] for n in datasets})
    report = {"datasets": {}, "training": {}, "models": list(MODELS), "categories": list(CATEGORIES),
              "units": {"whisker_left": "mm", "whisker_right": "mm", "orientation": "deg", "reconstruction": "mm"}}
    for n, (d, sp) in datasets.items():
        report["datasets"][n] = {"scenario": str(d["scenario"]), "split": sp, "results": {},
                                 "samples": {s: int(d["contact"][:, j].sum()) for j, s in enumerate(SIDES)}}
    default_entries = default_records = None
    for run_name, names in runs.items():
        print(f"training on {run_name} (seed {args.seed})")
        preds, entries, records = train_all(datasets, names, args.seed, args.fast, gp_max=args.gp_max_samples)
        report["training"][run_name] = records
        if run_name == "+".join(train_on):
            default_entries, default_records = entries, records
        for n, (d, sp) in datasets.items():
            for m in MODELS:
                res = evaluate(d, sp["test"], lambda side, x, m=m: preds[m][side](x))
                res["model"], res["trained_on"] = m, run_name
                report["datasets"][n]["results"][f"{m}@{run_name}"] = res

    provenance = {
        "datasets": [{"name": n, "scenario": str(d["scenario"]), "flights": [int(s) for s in d["seeds"]]}
                     for n, (d, _) in datasets.items() if n in train_on],
        "train_flights": [{"dataset": n, "flights": datasets[n][1]["fit"]} for n in train_on],
        "validation_flights": [{"dataset": n, "flights": datasets[n][1]["val"]} for n in train_on],
        "test_flights": [{"dataset": n, "flights": datasets[n][1]["test"]} for n in train_on],
        "tool": "tools/train_depth_model.py",
        "python": platform.python_version(),
        "sklearn": sklearn.__version__,
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "seed": args.seed,
        "input_signal": args.input,
        "date": datetime.date.today().isoformat(),
        "hidden_layers": list(HIDDEN),
        "training": {side: {k: v for k, v in rec.items() if k != "seconds"}  # no timing: reproducible file
                     for side, rec in default_records["MLP"].items()},
        "metrics": {n: {c: report["datasets"][n]["results"][f"MLP@{'+'.join(train_on)}"][c] for c in CATEGORIES}
                    for n in datasets},
    }
    model = depth_model.make_model(default_entries, provenance, input_signal=args.input)
    depth_model.validate_model(model)
    model_path = Path(args.model_out) if args.model_out else out / "model.json"
    model_path.parent.mkdir(parents=True, exist_ok=True)
    depth_model.save_model(model, model_path)
    report["model_file"] = model_path.name
    report["provenance"] = {k: v for k, v in provenance.items() if k not in ("metrics", "training")}
    (out / "report.json").write_text(json.dumps(report, indent=1) + "\n")
    md = markdown_report(report)
    (out / "report.md").write_text(md + "\n")
    print(md)
    print(f"wrote {model_path}, {out / 'report.json'}, {out / 'report.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
