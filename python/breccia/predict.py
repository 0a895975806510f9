"""Failure prediction from microcracking indicators (seed 000; docs/analysis.md §10).

The data set: one row per pre-peak trailing strain window of each test (indicators.csv), with
the seed's six inputs (confining pressure, MCvar, shear fraction, D2, AEvar, b-value; all causal)
and two targets: stress to failure q_peak - q(eps_k) (MPa) and strain to failure
eps_peak - eps_k. Windows with a missing input are dropped and counted per test.

The network is the seed's 6-6-1 (tanh hidden layer, linear output; one network per target) on
inputs and target scaled min-max to [-1, 1] with the training tests' ranges. scikit-learn's
MLPRegressor trains it with L-BFGS, full batch: scikit-learn has no Levenberg-Marquardt
(docs/analysis.md §10.3's default) and L-BFGS is its full-batch quasi-Newton method, the closest
in kind. Ten networks with different seeds are trained and the one with the lowest error on a
validation test is kept. Validation is leave-one-test-out (§10.4): each fold holds one test out
for testing and one other for validation. Input importance is Garson's (§10.6) with Olden's
signed connection weights beside it. A trained model is a JSON file of its weights and scalers.
Gradient-boosted trees, scored under the same folds, stand beside the network as a second
learner (what the seed did not have).

    breccia predict train SWEEP_OR_RUN... --output MODEL [--inputs ...] [--networks 10]
                          [--learners network,gradient_boosting]
    breccia predict apply RUN --model MODEL
    (or python3 -m breccia.predict train|apply ...)
"""
import argparse
import json
import os
import sys
import warnings

import numpy as np
import pandas as pd

from .folders import RunFolder, SweepFolder, read

# The seed's inputs, in its order (Tables S1 and S2), and the indicators.csv column of each.
INPUTS = ["confining_mpa", "mc_var", "shear_fraction", "d2", "ae_var", "b_value"]
COLUMNS = {"mc_var": "mc_var", "shear_fraction": "shear_fraction", "d2": "d2",
           "ae_var": "ae_var_j2", "b_value": "b_value"}
TARGETS = {"stress": "stress_to_failure_mpa", "strain": "strain_to_failure"}
# Heavy-tailed inputs taken as log10 before scaling (§10.2's option); zero variances are kept
# finite by a floor far below any nonzero value they take.
LOG_INPUTS = {"mc_var": 1e-6, "ae_var": 1e-40}


class PredictError(ValueError):
    """Bad input to the predictor: names what is wrong and what is allowed."""


# ---------------------------------------------------------------------------------------------
# Data set
# ---------------------------------------------------------------------------------------------

def peak_of(run):
    """(axial strain, deviatoric stress in Pa) at the run's peak, or None with the reason when
    the run did not finish or never reached a peak: without it there is no time to failure."""
    if not run.complete:
        return None, f"the run is {run.status}, not complete"
    s = run.summary
    if not s.get("peak_reached", True):
        return None, "the run never reached a peak (it stopped at its strain limit)"
    strain, stress = s.get("axial_strain_at_peak"), s.get("peak_deviatoric_stress_pa")
    if not isinstance(strain, (int, float)) or not isinstance(stress, (int, float)):
        return None, "its summary.json has no axial_strain_at_peak or peak_deviatoric_stress_pa"
    return (float(strain), float(stress)), ""


def run_folders(paths, log=print):
    """The run folders of the given sweep and run folders that reached a peak, in order; the
    others are left out with the reason."""
    runs = []
    for p in paths:
        f = read(p)
        if isinstance(f, SweepFolder):
            found = [r for r in f.runs if r.complete]
        elif isinstance(f, RunFolder):
            found = [f]
        else:
            raise PredictError(f"{p}: a calibration folder; give sweep or run folders")
        for r in found:
            peak, why = peak_of(r)
            if peak is None:
                log(f"predict: {r.path} left out: {why}")
            else:
                runs.append(r)
    if not runs:
        raise PredictError(f"{' '.join(map(str, paths))}: no complete run that reached a peak "
                           "(a predictor of the time to failure learns from tests that failed)")
    return runs


def windows(run, inputs=INPUTS, pre_peak_only=True):
    """One row per trailing window of a run: its inputs and, where the peak is known, its
    targets. Returns (all windows with every input present, number dropped for a missing one)."""
    ind = run.indicators
    s = run.summary
    peak, _ = peak_of(run)
    # Without a known peak (an unfinished run being forecast) the targets stay empty.
    peak_strain, peak_q_mpa = (peak[0], peak[1] / 1e6) if peak else (np.nan, np.nan)
    h = run.history
    rows = pd.DataFrame({"test": os.path.basename(run.path),
                         "axial_strain": ind["axial_strain"].to_numpy()})
    rows["confining_mpa"] = s.get("confining_stress_pa", 0.0) / 1e6
    for name in inputs:
        if name != "confining_mpa":
            rows[name] = ind[COLUMNS[name]].to_numpy()
    # q at the end of each window, from the history rows (linear between rows).
    q_mpa = np.interp(rows["axial_strain"], h["axial_strain"], h["deviatoric_stress_pa"]) / 1e6
    rows["deviatoric_mpa"] = q_mpa
    rows["stress_to_failure_mpa"] = peak_q_mpa - q_mpa
    rows["strain_to_failure"] = peak_strain - rows["axial_strain"]
    if pre_peak_only:
        rows = rows[rows["axial_strain"] <= peak_strain]
    complete = rows[list(inputs)].notna().all(axis=1) & np.isfinite(rows[list(inputs)]).all(axis=1)
    return rows[complete].reset_index(drop=True), int((~complete).sum())


def dataset(paths, inputs=INPUTS, log=print):
    """The windows of every complete run in `paths` (sweep or run folders), and a per-test table
    of windows kept and dropped."""
    unknown = [i for i in inputs if i not in INPUTS]
    if unknown or not inputs:
        raise PredictError(f"inputs = {','.join(inputs)}: allowed: any of {', '.join(INPUTS)}")
    parts, report = [], []
    for run in run_folders(paths, log):
        rows, dropped = windows(run, inputs)
        parts.append(rows)
        report.append({"test": os.path.basename(run.path),
                       "confining_mpa": run.summary.get("confining_stress_pa", 0.0) / 1e6,
                       "windows": len(rows), "dropped_missing_input": dropped})
    data = pd.concat(parts, ignore_index=True)
    return data, pd.DataFrame(report)


# ---------------------------------------------------------------------------------------------
# The network
# ---------------------------------------------------------------------------------------------

def _transform(X, inputs):
    X = np.array(X, dtype=float, copy=True)
    for k, name in enumerate(inputs):
        if name in LOG_INPUTS:
            X[:, k] = np.log10(np.maximum(X[:, k], LOG_INPUTS[name]))
    return X


class MinMax:
    """Min-max scaling to [-1, 1] (docs/analysis.md §10.2); a constant column maps to 0."""

    def __init__(self, low, high):
        self.low, self.high = np.asarray(low, float), np.asarray(high, float)

    @classmethod
    def fit(cls, values):
        v = np.asarray(values, float)
        return cls(v.min(axis=0), v.max(axis=0))

    def _span(self):
        return np.where(self.high > self.low, self.high - self.low, 1.0)

    def scale(self, v):
        s = 2.0 * (np.asarray(v, float) - self.low) / self._span() - 1.0
        return np.where(self.high > self.low, s, 0.0)

    def unscale(self, s):
        return self.low + (np.asarray(s, float) + 1.0) * self._span() / 2.0


class Network:
    """A trained 6-6-1 network with its scalers: y = w2 . tanh(W1 x + b1) + b2 on scaled x."""

    def __init__(self, inputs, target, W1, b1, w2, b2, x_scale, y_scale):
        self.inputs, self.target = list(inputs), target
        self.W1, self.b1 = np.asarray(W1, float), np.asarray(b1, float)  # (hidden, inputs)
        self.w2, self.b2 = np.asarray(w2, float), float(b2)
        self.x_scale, self.y_scale = x_scale, y_scale

    @classmethod
    def from_sklearn(cls, mlp, inputs, target, x_scale, y_scale):
        return cls(inputs, target, mlp.coefs_[0].T, mlp.intercepts_[0], mlp.coefs_[1][:, 0],
                   mlp.intercepts_[1][0], x_scale, y_scale)

    def predict(self, X):
        x = self.x_scale.scale(_transform(X, self.inputs))
        h = np.tanh(x @ self.W1.T + self.b1)
        return self.y_scale.unscale(h @ self.w2 + self.b2)

    def garson(self):
        return garson(self.W1.T, self.w2)

    def olden(self):
        return olden(self.W1.T, self.w2)

    def to_dict(self):
        return {"inputs": self.inputs, "target": self.target, "activation": "tanh",
                "log10_inputs": [i for i in self.inputs if i in LOG_INPUTS],
                "W1": self.W1.tolist(), "b1": self.b1.tolist(), "w2": self.w2.tolist(),
                "b2": self.b2,
                "x_min": self.x_scale.low.tolist(), "x_max": self.x_scale.high.tolist(),
                "y_min": float(self.y_scale.low), "y_max": float(self.y_scale.high)}

    @classmethod
    def from_dict(cls, d):
        return cls(d["inputs"], d["target"], d["W1"], d["b1"], d["w2"], d["b2"],
                   MinMax(d["x_min"], d["x_max"]), MinMax(d["y_min"], d["y_max"]))


def garson(w_input_hidden, v_hidden_output):
    """Garson's relative importance (docs/analysis.md §10.6): w[i, h] input-to-hidden weights,
    v[h] hidden-to-output weights; returns RI[i], summing to 1."""
    c = np.abs(np.asarray(w_input_hidden, float) * np.asarray(v_hidden_output, float)[None, :])
    r = c / c.sum(axis=0, keepdims=True)
    s = r.sum(axis=1)
    return s / s.sum()


def olden(w_input_hidden, v_hidden_output):
    """Olden's signed connection weights CW[i] = sum_h w[i, h] v[h]."""
    return np.asarray(w_input_hidden, float) @ np.asarray(v_hidden_output, float)


def rmse(y, p):
    return float(np.sqrt(np.mean((np.asarray(y) - np.asarray(p)) ** 2)))


def r2(y, p):
    y, p = np.asarray(y, float), np.asarray(p, float)
    total = np.sum((y - y.mean()) ** 2)
    return float(1.0 - np.sum((y - p) ** 2) / total) if total > 0 else float("nan")


def fit_network(X, y, inputs, target, seed, hidden=6, max_iter=1000):
    """One network on (X, y), scaled with their own ranges."""
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.neural_network import MLPRegressor
    Xt = _transform(X, inputs)
    x_scale, y_scale = MinMax.fit(Xt), MinMax.fit(np.asarray(y, float))
    mlp = MLPRegressor(hidden_layer_sizes=(hidden,), activation="tanh", solver="lbfgs",
                       alpha=0.0, max_iter=max_iter, random_state=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # max_iter is the epoch limit
        mlp.fit(x_scale.scale(Xt), y_scale.scale(y))
    return Network.from_sklearn(mlp, inputs, target, x_scale, y_scale)


def best_of(X, y, Xv, yv, inputs, target, networks, seed0=0):
    """`networks` networks from different seeds; the one with the lowest validation RMSE, and
    all of them (for the spread of their importances)."""
    nets = [fit_network(X, y, inputs, target, seed0 + k) for k in range(networks)]
    errors = [rmse(yv, n.predict(Xv)) for n in nets]
    return nets[int(np.argmin(errors))], nets


class Boosting:
    """Gradient-boosted regression trees (scikit-learn's GradientBoostingRegressor: squared
    error, depth-3 trees, learning rate 0.05) on the raw inputs (trees need no scaling and are
    blind to the log of MCvar and AEvar). The number of trees is the one with the lowest RMSE on
    the validation test, the role the validation test plays in choosing among the networks."""

    LEARNING_RATE, DEPTH, MAX_TREES = 0.05, 3, 1000

    def __init__(self, inputs, target, model):
        self.inputs, self.target, self.model = list(inputs), target, model

    @classmethod
    def fit(cls, X, y, Xv, yv, inputs, target, seed=0, max_trees=MAX_TREES):
        from sklearn.ensemble import GradientBoostingRegressor

        def regressor(trees):
            return GradientBoostingRegressor(
                n_estimators=trees, learning_rate=cls.LEARNING_RATE, max_depth=cls.DEPTH,
                subsample=1.0, random_state=seed)
        X, y = np.asarray(X, float), np.asarray(y, float)
        full = regressor(max_trees).fit(X, y)
        errors = [rmse(yv, p) for p in full.staged_predict(np.asarray(Xv, float))]
        trees = int(np.argmin(errors)) + 1
        # A refit to that many trees repeats the first trees of the full fit (no subsampling).
        return cls(inputs, target, full if trees == max_trees else regressor(trees).fit(X, y))

    @property
    def trees(self):
        return int(self.model.n_estimators)

    def predict(self, X):
        return self.model.predict(np.asarray(X, float))

    def importance(self):
        """Impurity-based importances (each input's share of the squared-error reduction)."""
        return np.asarray(self.model.feature_importances_, float)


LEARNERS = ("network", "gradient_boosting")


def fit_learner(learner, train_rows, val_rows, inputs, target, networks):
    """The chosen learner fitted on the training tests, with the validation test choosing among
    networks or the number of trees."""
    X, y = train_rows[inputs], train_rows[target]
    Xv, yv = val_rows[inputs], val_rows[target]
    if learner == "gradient_boosting":
        return Boosting.fit(X, y, Xv, yv, inputs, target)
    return best_of(X, y, Xv, yv, inputs, target, networks)[0]


def validation_test(tests_by_pc, held_out):
    """The validation test of a fold: the remaining test nearest in confining pressure to the
    held-out one (so the training tests keep the ends of the range whenever they can)."""
    pc = dict(tests_by_pc)
    others = [t for t in pc if t != held_out]
    return min(others, key=lambda t: (abs(pc[t] - pc[held_out]), t))


def leave_one_test_out(data, inputs, target, networks=10, learner="network"):
    """Per-fold metrics and the pooled held-out predictions (docs/analysis.md §10.4), for the
    seed's network or gradient boosting, under the same folds."""
    tests = data.groupby("test")["confining_mpa"].first().sort_values()
    if len(tests) < 3:
        raise PredictError(f"{len(tests)} tests with usable windows: leave-one-test-out needs "
                           "at least 3 (one to test, one to validate, one to train)")
    folds, pooled = [], []
    for held in tests.index:
        val = validation_test(tests.items(), held)
        train = data[~data["test"].isin([held, val])]
        v, t = data[data["test"] == val], data[data["test"] == held]
        p = fit_learner(learner, train, v, inputs, target, networks).predict(t[inputs])
        folds.append({"learner": learner, "target": target, "held_out": held,
                      "confining_mpa": tests[held],
                      "validation": val, "train_windows": len(train), "test_windows": len(t),
                      "rmse": rmse(t[target], p), "r2": r2(t[target], p)})
        pooled.append(pd.DataFrame({"test": held, "y": t[target].to_numpy(), "predicted": p}))
    return pd.DataFrame(folds), pd.concat(pooled, ignore_index=True)


# ---------------------------------------------------------------------------------------------
# train / apply
# ---------------------------------------------------------------------------------------------

def train(paths, output, inputs=INPUTS, networks=10, log=print, learners=LEARNERS):
    """Builds the data set, validates leave-one-test-out, trains the final networks (all tests
    but one kept for validation), and writes model.json, dataset.csv, windows.csv,
    validation.csv and importance.csv to `output`. With gradient boosting among `learners` its
    leave-one-test-out scores and importances stand beside the network's (the network is the
    model `apply` uses). Returns the model dict."""
    check_output(output)
    unknown = [x for x in learners if x not in LEARNERS]
    if unknown or "network" not in learners:
        raise PredictError(f"learners = {','.join(learners)}: allowed: network, or "
                           "network,gradient_boosting (the network is the model applied)")
    data, per_test = dataset(paths, inputs, log)
    if len(data) == 0:
        raise PredictError("no pre-peak window has every input "
                           f"({', '.join(inputs)}); dropped per test:\n"
                           + per_test.to_string(index=False)
                           + "\nsmall samples have too few events for b-values before the peak: "
                           "choose --inputs without b_value, or larger samples")
    os.makedirs(output, exist_ok=True)
    log(f"predict: {len(data)} windows from {per_test['windows'].gt(0).sum()} tests "
        f"({per_test['dropped_missing_input'].sum()} dropped for a missing input)")
    model = {"program": "breccia.predict", "inputs": list(inputs), "networks_per_fit": networks,
             "training": "scikit-learn MLPRegressor, 6 tanh hidden units, L-BFGS, "
                         "min-max [-1, 1], log10 of MCvar and AEvar",
             "learners": list(learners),
             "sources": [os.path.abspath(os.fspath(p)) for p in paths],
             "windows": len(data), "tests": per_test.to_dict("records"), "targets": {}}
    folds, importance = [], []
    tests = data.groupby("test")["confining_mpa"].first().sort_values()
    for name, column in TARGETS.items():
        fold_table, pooled = leave_one_test_out(data, list(inputs), column, networks)
        folds.append(fold_table)
        boosting = None
        if "gradient_boosting" in learners:
            boosting = leave_one_test_out(data, list(inputs), column, networks,
                                          "gradient_boosting")
            folds.append(boosting[0])
        # The final model: every test but the one nearest the median confining pressure.
        val = tests.index[len(tests) // 2]
        train_rows, v = data[data["test"] != val], data[data["test"] == val]
        net, nets = best_of(train_rows[inputs], train_rows[column], v[inputs], v[column],
                            list(inputs), column, networks)
        ri = np.array([n.garson() for n in nets])
        table = pd.DataFrame({
            "target": column, "input": list(inputs), "garson": net.garson(),
            "garson_mean_of_networks": ri.mean(axis=0), "garson_sd_of_networks": ri.std(axis=0),
            "olden": net.olden()})
        if boosting is not None:
            trees = Boosting.fit(train_rows[inputs], train_rows[column], v[inputs], v[column],
                                 list(inputs), column)
            table["gradient_boosting"] = trees.importance()
        importance.append(table)
        model["targets"][name] = {
            "network": net.to_dict(), "validation_test": val,
            "loto_rmse_pooled": rmse(pooled["y"], pooled["predicted"]),
            "loto_r2_pooled": r2(pooled["y"], pooled["predicted"]),
            "loto_rmse_mean_of_folds": float(fold_table["rmse"].mean()),
            "garson": dict(zip(inputs, net.garson().tolist()))}
        if boosting is not None:
            folds_gb, pooled_gb = boosting
            model["targets"][name]["gradient_boosting"] = {
                "loto_rmse_pooled": rmse(pooled_gb["y"], pooled_gb["predicted"]),
                "loto_r2_pooled": r2(pooled_gb["y"], pooled_gb["predicted"]),
                "loto_rmse_mean_of_folds": float(folds_gb["rmse"].mean()),
                "trees_final": trees.trees,
                "importance": dict(zip(inputs, trees.importance().tolist()))}
            log(f"predict: {column}: gradient boosting: leave-one-test-out R^2 "
                f"{model['targets'][name]['gradient_boosting']['loto_r2_pooled']:.3f}")
        log(f"predict: {column}: leave-one-test-out RMSE {model['targets'][name]['loto_rmse_pooled']:.4g}, "
            f"R^2 {model['targets'][name]['loto_r2_pooled']:.3f} over {len(tests)} folds")
    data.to_csv(os.path.join(output, "windows.csv"), index=False)
    per_test.to_csv(os.path.join(output, "dataset.csv"), index=False)
    pd.concat(folds).to_csv(os.path.join(output, "validation.csv"), index=False)
    pd.concat(importance).to_csv(os.path.join(output, "importance.csv"), index=False)
    with open(os.path.join(output, "model.json"), "w") as f:
        json.dump(model, f, indent=1)
    return model


def check_output(output):
    """A model folder: a new one, or one that holds a model already (it is replaced)."""
    output = os.fspath(output)
    if os.path.exists(output) and not os.path.isdir(output):
        raise PredictError(f"--output {output}: is a file; the model is a folder (model.json and "
                           "its tables): give a new folder's name")
    if os.path.isdir(output) and os.listdir(output) and \
            not os.path.exists(os.path.join(output, "model.json")):
        raise PredictError(f"--output {output}: a folder that holds other files and no model; "
                           "give a new folder's name (or an earlier model's, to replace it)")


def _checked_network(d, path, name):
    """A network of model.json, every field checked (shapes included)."""
    where = f"{path}: targets.{name}.network"
    if not isinstance(d, dict):
        raise PredictError(f"{where}: expected an object")
    for key in ("inputs", "target", "W1", "b1", "w2", "b2", "x_min", "x_max", "y_min", "y_max"):
        if key not in d:
            raise PredictError(f"{where}.{key}: missing")
    inputs = d["inputs"]
    if not isinstance(inputs, list) or not inputs or any(i not in INPUTS for i in inputs):
        raise PredictError(f"{where}.inputs = {inputs!r}: expected a list of {', '.join(INPUTS)}")
    try:
        W1 = np.asarray(d["W1"], float)
        vectors = {k: np.asarray(d[k], float) for k in ("b1", "w2", "x_min", "x_max")}
        scalars = {k: float(d[k]) for k in ("b2", "y_min", "y_max")}
    except (TypeError, ValueError) as e:
        raise PredictError(f"{where}: weights and scalers must be numbers ({e})") from None
    n, h = len(inputs), W1.shape[0] if W1.ndim == 2 else -1
    if W1.ndim != 2 or W1.shape[1] != n or h < 1:
        raise PredictError(f"{where}.W1: shape {W1.shape}: expected (hidden, {n})")
    want = {"b1": h, "w2": h, "x_min": n, "x_max": n}
    for k, size in want.items():
        if vectors[k].shape != (size,):
            raise PredictError(f"{where}.{k}: {vectors[k].shape[0] if vectors[k].ndim == 1 else vectors[k].shape} "
                               f"values: expected {size}")
    if not all(np.isfinite(v).all() for v in [W1, *vectors.values()]) or \
            not all(np.isfinite(list(scalars.values()))):
        raise PredictError(f"{where}: weights and scalers must be finite")
    if d["target"] not in TARGETS.values():
        raise PredictError(f"{where}.target = {d['target']!r}: expected one of "
                           f"{', '.join(TARGETS.values())}")
    return Network.from_dict(d)


def load(model_dir):
    path = os.path.join(os.fspath(model_dir), "model.json")
    if not os.path.exists(path):
        raise PredictError(f"{model_dir}: no model.json (train one with `breccia predict train`)")
    if not os.path.isfile(path):
        raise PredictError(f"{path}: not a file")
    try:
        with open(path) as f:
            model = json.load(f)
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise PredictError(f"{path}: not valid JSON ({e}); train the model again") from None
    if not isinstance(model, dict) or not isinstance(model.get("targets"), dict) \
            or not model["targets"]:
        raise PredictError(f"{path}: 'targets': missing or empty; not a model written by "
                           "`breccia predict train`")
    nets = {name: _checked_network(t.get("network") if isinstance(t, dict) else t, path, name)
            for name, t in model["targets"].items()}
    if len({tuple(n.inputs) for n in nets.values()}) != 1:
        raise PredictError(f"{path}: the targets' networks have different inputs")
    return nets


def apply(run_path, model_dir, log=print):
    """Predicts stress and strain to failure at every window of a run with every input present
    (the peak is not used), writes failure_predictions.csv in the run folder, and, where the
    run's peak is known, the actual values beside them."""
    networks = load(model_dir)
    run = read(run_path)
    if not isinstance(run, RunFolder):
        raise PredictError(f"{run_path}: not a run folder")
    inputs = next(iter(networks.values())).inputs
    rows, dropped = windows(run, inputs, pre_peak_only=False)
    peak, why = peak_of(run)
    out = rows[["axial_strain", "deviatoric_mpa", *inputs]].copy()
    for name, net in networks.items():
        out[f"predicted_{net.target}"] = net.predict(rows[inputs]) if len(rows) else []
        # Without a known peak the actual values are unknown: the column stays empty.
        out[f"actual_{net.target}"] = rows[net.target] if peak else np.nan
    path = run.file("failure_predictions.csv")
    out.to_csv(path, index=False)
    if not peak:
        log(f"predict: no actual stress or strain to failure beside the forecast: {why}")
    pre = out[out["axial_strain"] <= peak[0]] if peak else out.iloc[0:0]
    for name, net in networks.items():
        if len(pre):
            log(f"predict: {net.target}: RMSE {rmse(pre[f'actual_{net.target}'], pre[f'predicted_{net.target}']):.4g} "
                f"over {len(pre)} pre-peak windows")
    log(f"predict: {len(out)} windows ({dropped} without every input) -> {path}")
    return out


def redraw_report(run_path, log=print):
    """A run that has a report gets it redrawn with the forecast figure and row; one without
    (output.plot = false) is left so, with the command that draws it."""
    if os.path.exists(os.path.join(run_path, "report.html")):
        import matplotlib  # only where a report is drawn
        matplotlib.use("Agg")  # files only
        from . import report
        report.run_report(run_path)
        log(f"predict: the report shows the forecast: {os.path.join(run_path, 'report.html')}")
    else:
        log(f"predict: `breccia report {run_path}` draws the forecast in the run's report")


def main(argv=None):
    parser = argparse.ArgumentParser(prog="breccia predict", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    t = sub.add_parser("train", help="train on sweep or run folders")
    t.add_argument("folders", nargs="+")
    t.add_argument("--output", required=True, help="model folder")
    t.add_argument("--inputs", default=",".join(INPUTS),
                   help=f"comma-separated inputs (default: the seed's: {','.join(INPUTS)})")
    t.add_argument("--networks", type=int, default=10, help="networks per fit (best kept)")
    t.add_argument("--learners", default=",".join(LEARNERS),
                   help="network, or network,gradient_boosting (default): gradient boosting's "
                        "leave-one-test-out scores beside the network's")
    a = sub.add_parser("apply", help="predict failure along a run")
    a.add_argument("run")
    a.add_argument("--model", required=True)
    args = parser.parse_args(argv)
    try:
        if args.command == "train":
            if args.networks < 1:
                raise PredictError(f"--networks = {args.networks}: allowed: >= 1")
            train(args.folders, args.output, [i for i in args.inputs.split(",") if i],
                  args.networks, learners=[x for x in args.learners.split(",") if x])
        else:
            apply(args.run, args.model)
            redraw_report(args.run)
    except (PredictError, FileNotFoundError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted; the model folder may be incomplete", file=sys.stderr)
        return 130
    except OSError as e:
        print(f"error: {e.filename or ''}: {e.strerror or e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
