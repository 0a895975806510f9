"""The failure predictor (breccia.predict; docs/analysis.md §10): Garson and Olden against the hand
example and seed 000's tables S1/S2, the scalers and metrics against their worked examples, the
network's own forward pass against scikit-learn's, recovery of a planted relation under
leave-one-test-out with the planted input ranked first, the data set of a real run, and the
command's errors."""
import json
import os
import subprocess
import tempfile

import numpy as np
import pandas as pd
import pytest

from breccia import predict

CLI = os.environ["BRECCIA_CLI"]
SOURCE = os.environ["BRECCIA_SOURCE_DIR"]


def test_garson_and_olden_reproduce_the_worked_example():
    # docs/analysis.md §10.6: w[input, hidden], v[hidden].
    w = np.array([[1.0, 0.2], [-0.5, 0.8]])
    v = np.array([2.0, -1.0])
    assert predict.garson(w, v) == pytest.approx([0.43333, 0.56667], abs=1e-5)
    assert predict.olden(w, v) == pytest.approx([1.8, -1.8])


# Seed 000, tables S1 (stress to failure) and S2 (strain to failure): input-to-hidden weights,
# one row per hidden neuron, inputs CP, MCvar, SF, D2, AEvar, b; output weights; and the
# relative importances (%) the seed reports.
S1_W = [[-12.787, -5.3654, 3.3737, 5.197, 5.529, -4.4557],
        [-0.69941, 0.46166, 1.7681, -0.44316, -0.53642, 1.3435],
        [-1.3795, 0.62373, 1.8093, -0.96023, -2.5051, 2.0473],
        [-0.1906, -0.80925, -0.34267, 1.3237, -0.93371, -1.7405],
        [-0.00902, -0.07215, -0.00188, 0.78122, -0.84251, -0.45002],
        [-1.1023, -1.8656, 2.1003, 0.65579, 4.1812, 1.7924]]
S1_V = [0.068337, -1.127, 0.39871, -0.81965, 0.92711, 0.81099]
S1_RI = [12.726, 10.757, 14.453, 16.585, 24.072, 21.409]
S2_W = [[0.003748, 0.36396, 0.97119, -0.43355, 1.8287, 2.9244],
        [0.70824, -3.9489, -1.4084, -0.67197, -0.93546, -3.8996],
        [-0.29575, 1.9861, 0.17713, -0.03881, -0.01627, 0.12422],
        [-0.63046, 0.99101, 2.5128, -0.47049, 0.8302, 1.778],
        [-0.77788, -2.9333, -1.075, 0.71918, -0.96588, 2.2468],
        [-1.3277, -1.845, -0.68016, 1.1911, -0.97703, 1.8469]]
S2_V = [0.84593, 0.56068, 0.53844, -0.32142, 1.831, -3.3834]
S2_RI = [8.6543, 30.969, 14.93, 7.3054, 11.955, 26.186]


@pytest.mark.parametrize("w, v, ri", [(S1_W, S1_V, S1_RI), (S2_W, S2_V, S2_RI)])
def test_garson_reproduces_seed_000s_importances_from_its_weights(w, v, ri):
    # The seed's tables give weights to 3-5 significant figures: 0.01 percentage points.
    got = 100 * predict.garson(np.array(w).T, np.array(v))
    assert got == pytest.approx(ri, abs=0.01)


def test_min_max_scaling_and_metrics_match_the_worked_examples():
    s = predict.MinMax.fit(np.array([5.0, 10.0, 20.0]))
    assert s.scale([5.0, 10.0, 20.0]) == pytest.approx([-1.0, -1 / 3, 1.0])
    assert s.unscale(s.scale([7.0])) == pytest.approx([7.0])
    assert predict.MinMax.fit(np.array([3.0, 3.0])).scale([3.0]) == pytest.approx([0.0])
    y, p = [1, 2, 3, 4], [1.1, 1.9, 3.2, 3.8]
    assert predict.rmse(y, p) == pytest.approx(0.1581, abs=1e-4)
    assert predict.r2(y, p) == pytest.approx(0.98, abs=1e-12)


def planted(tests=6, per_test=60, seed=1):
    """Windows of synthetic tests whose target is a known function of D2 alone (plus weak
    noise); the other inputs are noise of their typical sizes."""
    rng = np.random.default_rng(seed)
    rows = []
    for t in range(tests):
        n = per_test
        d2 = rng.uniform(0.8, 2.2, n)
        rows.append(pd.DataFrame({
            "test": f"t{t}", "confining_mpa": 10.0 * t,
            "mc_var": 10 ** rng.uniform(-1, 2, n), "shear_fraction": rng.uniform(0, 0.3, n),
            "d2": d2, "ae_var": 10 ** rng.uniform(-16, -12, n), "b_value": rng.uniform(0.5, 2, n),
            "stress_to_failure_mpa": 40 * (d2 - 0.8) ** 2 + rng.normal(0, 0.5, n)}))
    return pd.concat(rows, ignore_index=True)


def test_the_network_recovers_a_planted_relation_and_ranks_its_input_first():
    data = planted()
    target = "stress_to_failure_mpa"
    folds, pooled = predict.leave_one_test_out(data, predict.INPUTS, target, networks=3)
    assert len(folds) == 6
    # The target spans 0-78 MPa with noise 0.5 MPa: held-out tests are predicted to R^2 > 0.95.
    assert predict.r2(pooled["y"], pooled["predicted"]) > 0.95
    net, nets = predict.best_of(data[predict.INPUTS], data[target], data[predict.INPUTS],
                                data[target], predict.INPUTS, target, networks=3)
    ri = np.mean([n.garson() for n in nets], axis=0)
    assert int(np.argmax(ri)) == predict.INPUTS.index("d2"), ri


def test_the_networks_forward_pass_is_scikit_learns_and_survives_saving():
    from sklearn.neural_network import MLPRegressor
    data = planted(tests=2, per_test=40)
    X, y = data[predict.INPUTS], data["stress_to_failure_mpa"]
    net = predict.fit_network(X, y, predict.INPUTS, "stress_to_failure_mpa", seed=4)
    # The same fit with scikit-learn's own predict on the scaled inputs.
    Xt = predict._transform(X, predict.INPUTS)
    mlp = MLPRegressor(hidden_layer_sizes=(6,), activation="tanh", solver="lbfgs", alpha=0.0,
                       max_iter=1000, random_state=4)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mlp.fit(net.x_scale.scale(Xt), net.y_scale.scale(y))
    expected = net.y_scale.unscale(mlp.predict(net.x_scale.scale(Xt)))
    assert net.predict(X) == pytest.approx(expected, rel=1e-10, abs=1e-9)
    again = predict.Network.from_dict(json.loads(json.dumps(net.to_dict())))
    assert again.predict(X) == pytest.approx(net.predict(X), rel=0, abs=0)


def test_gradient_boosting_recovers_the_planted_relation_under_the_same_folds():
    data = planted()
    target = "stress_to_failure_mpa"
    folds, pooled = predict.leave_one_test_out(data, predict.INPUTS, target,
                                               learner="gradient_boosting")
    net_folds, _ = predict.leave_one_test_out(data, predict.INPUTS, target, networks=1)
    assert (folds["learner"] == "gradient_boosting").all()
    assert folds[["held_out", "validation"]].equals(net_folds[["held_out", "validation"]])
    # Trees approximate the smooth 40 (d2 - 0.8)^2 by steps; the noise is 0.5 MPa on a target
    # spanning 0-78 MPa, so held-out R^2 > 0.95 as for the network.
    assert predict.r2(pooled["y"], pooled["predicted"]) > 0.95
    train, val = data[data["test"] != "t2"], data[data["test"] == "t2"]
    trees = predict.Boosting.fit(train[predict.INPUTS], train[target], val[predict.INPUTS],
                                 val[target], predict.INPUTS, target)
    # The planted input carries nearly all the squared-error reduction.
    assert int(np.argmax(trees.importance())) == predict.INPUTS.index("d2")
    assert trees.importance()[predict.INPUTS.index("d2")] > 0.9
    # The number of trees is the validation test's best over a full fit's stages.
    from sklearn.ensemble import GradientBoostingRegressor
    full = GradientBoostingRegressor(n_estimators=300, learning_rate=0.05, max_depth=3,
                                     random_state=0).fit(train[predict.INPUTS], train[target])
    errors = [predict.rmse(val[target], p) for p in full.staged_predict(val[predict.INPUTS])]
    chosen = predict.Boosting.fit(train[predict.INPUTS], train[target], val[predict.INPUTS],
                                  val[target], predict.INPUTS, target, max_trees=300)
    assert chosen.trees == int(np.argmin(errors)) + 1 < 300
    assert chosen.predict(val[predict.INPUTS]) == pytest.approx(
        list(full.staged_predict(val[predict.INPUTS]))[chosen.trees - 1], rel=1e-12)


def test_training_scores_both_learners_and_refuses_an_unknown_one(monkeypatch):
    data = planted(tests=4, per_test=40)
    per_test = data.groupby("test").agg(confining_mpa=("confining_mpa", "first"),
                                        windows=("d2", "size")).reset_index()
    per_test["dropped_missing_input"] = 0
    monkeypatch.setattr(predict, "dataset", lambda paths, inputs, log: (data, per_test))
    target_only = planted(tests=4, per_test=40)  # the strain target: planted on D2 as well
    data["strain_to_failure"] = target_only["stress_to_failure_mpa"] / 1000.0
    with tempfile.TemporaryDirectory() as out:
        model = predict.train(["x"], os.path.join(out, "m"), predict.INPUTS, networks=1,
                              log=lambda *a: None)
        for name in ("stress", "strain"):
            gb = model["targets"][name]["gradient_boosting"]
            assert gb["loto_r2_pooled"] > 0.9 and gb["trees_final"] >= 1
            assert max(gb["importance"], key=gb["importance"].get) == "d2"
        folds = pd.read_csv(os.path.join(out, "m", "validation.csv"))
        assert sorted(folds["learner"].unique()) == ["gradient_boosting", "network"]
        assert len(folds) == 2 * 2 * 4  # two learners, two targets, four folds
        imp = pd.read_csv(os.path.join(out, "m", "importance.csv"))
        assert imp["gradient_boosting"].notna().all()
        with pytest.raises(predict.PredictError, match="learners = trees"):
            predict.train(["x"], os.path.join(out, "n"), predict.INPUTS, learners=["trees"])


def small_run(out, extra=()):
    cmd = [CLI, "run", "--quiet", "--output", out, "--set", 'sample.source="file"',
           "--set", f'sample.file="{SOURCE}/tests/data/ucs-small.geom"',
           "--set", "engine.density_scaling=100", "--set", "loading.platen_speed=0.2",
           "--set", "loading.max_strain=0.008", "--set", "output.snapshot_strain_interval=0",
           "--set", "output.plot=false", "--set", 'material.preset="custom"',
           "--set", 'contact.law="hertz_mindlin"', "--set", "contact.shear_modulus=29e9",
           "--set", "contact.poisson_ratio=0.33", "--set", "contact.friction=0.4",
           "--set", "bond.modulus=8e9", "--set", "bond.tensile_strength=30e6",
           "--set", "bond.cohesion=300e6", *extra]
    return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.split()[-1]


def test_the_data_set_of_a_run_holds_its_pre_peak_windows_and_their_targets():
    import breccia
    with tempfile.TemporaryDirectory() as out:
        # Loaded past its peak (the stress falls below 0.6 of it at about 1.8 % strain).
        run = breccia.read(small_run(out, extra=["--set", "loading.max_strain=0.03"]))
        assert run.summary["peak_reached"]
        inputs = ["confining_mpa", "mc_var", "ae_var"]
        rows, dropped = predict.windows(run, inputs)
        s = run.summary
        ind = run.indicators
        pre = ind[ind["axial_strain"] <= s["axial_strain_at_peak"]]
        assert len(rows) + dropped == len(pre) and len(rows) > 0
        assert (rows["strain_to_failure"] >= 0).all()
        assert rows["strain_to_failure"].to_numpy() == pytest.approx(
            s["axial_strain_at_peak"] - rows["axial_strain"].to_numpy())
        # q at a window end never exceeds the peak: stress to failure >= 0 (to rounding of
        # the interpolation between history rows).
        assert (rows["stress_to_failure_mpa"] >= -1e-9).all()
        assert rows["mc_var"].to_numpy() == pytest.approx(
            pre.loc[pre[["mc_var", "ae_var_j2"]].notna().all(axis=1), "mc_var"].to_numpy())
        # Three runs of one sample are one test each; fewer than 3 tests are refused.
        with pytest.raises(predict.PredictError, match="at least 3"):
            predict.leave_one_test_out(rows.assign(stress=0.0), inputs, "stress", networks=1)


def test_the_command_refuses_bad_input_with_a_message():
    r = subprocess.run([CLI, "predict", "train", SOURCE, "--output", "/tmp/x"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "not a Breccia run" in r.stderr
    with tempfile.TemporaryDirectory() as out:
        r = subprocess.run([CLI, "predict", "train", out, "--output", out, "--inputs", "foo"],
                           capture_output=True, text=True)
        assert r.returncode == 2 and "allowed: any of confining_mpa" in r.stderr
        r = subprocess.run([CLI, "predict", "apply", out, "--model", out],
                           capture_output=True, text=True)
        assert r.returncode == 2 and "no model.json" in r.stderr


def _predict(*args):
    return subprocess.run([CLI, "predict", *args], capture_output=True, text=True)


def _model(inputs, hidden=2):
    net = {"inputs": inputs, "activation": "tanh", "W1": [[0.1] * len(inputs)] * hidden,
           "b1": [0.0] * hidden, "w2": [0.5] * hidden, "b2": 0.0,
           "x_min": [0.0] * len(inputs), "x_max": [1.0] * len(inputs), "y_min": 0.0, "y_max": 1.0}
    return {"targets": {"stress": {"network": {**net, "target": "stress_to_failure_mpa"}},
                        "strain": {"network": {**net, "target": "strain_to_failure"}}}}


@pytest.mark.parametrize("text, needle", [
    ("", "not valid JSON"),
    ("{{{", "not valid JSON"),
    ("[1, 2]", "'targets'"),
    ('{"targets": {}}', "'targets'"),
    ('{"targets": {"stress": {"network": {}}}}', "targets.stress.network.inputs: missing"),
    (json.dumps({"targets": {"stress": {"network": {**_model(["mc_var"])["targets"]["stress"]["network"],
                                                    "W1": [[1, 2, 3]]}}}}), "W1: shape"),
    (json.dumps({"targets": {"stress": {"network": {**_model(["mc_var"])["targets"]["stress"]["network"],
                                                    "b2": "x"}}}}), "must be numbers"),
])
def test_a_damaged_model_is_named_not_a_traceback(text, needle):
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, "model.json"), "w") as f:
            f.write(text)
        r = _predict("apply", d, "--model", d)
        assert r.returncode == 2, r.stderr
        assert needle in r.stderr and "model.json" in r.stderr, r.stderr
        assert "Traceback" not in r.stderr


def test_training_onto_a_file_or_a_foreign_folder_is_refused_before_anything_runs():
    with tempfile.TemporaryDirectory() as d:
        target = os.path.join(d, "model")
        open(target, "w").close()
        r = _predict("train", d, "--output", target)
        assert r.returncode == 2 and "is a file" in r.stderr and "Traceback" not in r.stderr
        os.remove(target)
        os.makedirs(target)
        open(os.path.join(target, "notes.txt"), "w").close()
        r = _predict("train", d, "--output", target)
        assert r.returncode == 2 and "other files" in r.stderr, r.stderr


def test_runs_without_a_peak_train_nothing_and_get_no_actual_values():
    import breccia
    with tempfile.TemporaryDirectory() as out:
        # A test stopped long before its peak: bonds 100 times stronger than the small run's.
        folder = small_run(out, extra=["--set", "bond.tensile_strength=3e9", "--set",
                                       "bond.cohesion=30e9", "--set", "loading.max_strain=0.002"])
        run = breccia.read(folder)
        assert run.complete and not run.summary["peak_reached"]
        r = _predict("train", folder, "--output", os.path.join(out, "m"))
        assert r.returncode == 2 and "reached a peak" in r.stderr, r.stderr
        assert "never reached a peak" in r.stdout + r.stderr
        assert not os.path.exists(os.path.join(out, "m", "model.json"))
        model = os.path.join(out, "model")
        os.makedirs(model)
        with open(os.path.join(model, "model.json"), "w") as f:
            json.dump(_model(["confining_mpa"]), f)
        r = _predict("apply", folder, "--model", model)
        assert r.returncode == 0, r.stderr
        assert "never reached a peak" in r.stdout
        table = breccia.read(folder).table("failure_predictions")
        assert len(table) > 0
        assert table["actual_stress_to_failure_mpa"].isna().all()
        assert table["actual_strain_to_failure"].isna().all()
        assert table["predicted_stress_to_failure_mpa"].notna().all()
        # Without a report (output.plot = false) the command says how to draw one; with one,
        # it redraws it with the forecast figure and row.
        assert "draws the forecast" in r.stdout
        subprocess.run([CLI, "report", folder], check=True, capture_output=True)
        r = _predict("apply", folder, "--model", model)
        assert r.returncode == 0 and "the report shows the forecast" in r.stdout, r.stderr
        assert os.path.exists(os.path.join(folder, "report", "failure_forecast.png"))
        with open(os.path.join(folder, "report.html")) as f:
            assert "no actual values beside it" in f.read()


def test_the_report_scores_the_forecast_on_the_windows_before_the_peak_only():
    from breccia import report
    from breccia.report_kit import Table
    strain = np.array([0.001, 0.002, 0.003, 0.004, 0.005])
    # Before the peak (0.004) the hand example of docs/analysis.md §10.5: R^2 0.98, RMSE 0.1581;
    # the row after it, far off, must not count.
    preds = Table({"axial_strain": strain,
                   "actual_stress_to_failure_mpa": np.array([1.0, 2.0, 3.0, 4.0, -9.0]),
                   "predicted_stress_to_failure_mpa": np.array([1.1, 1.9, 3.2, 3.8, 7.0]),
                   "actual_strain_to_failure": 0.004 - strain,
                   "predicted_strain_to_failure": 0.004 - strain}, 5)
    summary = {"peak_reached": True, "axial_strain_at_peak": 0.004}
    scores = report.forecast_scores(preds, summary)
    r2, err, n = scores["stress_to_failure_mpa"]
    assert (r2, err, n) == (pytest.approx(0.98), pytest.approx(0.1581, abs=1e-4), 4)
    assert scores["strain_to_failure"][:2] == (pytest.approx(1.0), pytest.approx(0.0))
    (name, text), = report.forecast_rows(preds, summary)
    assert name == "failure forecast" and "stress to failure R^2 0.98 (RMSE 0.158 MPa)" in text
    assert report.forecast_scores(preds, {"peak_reached": False}) == {}
    assert "no actual values" in report.forecast_rows(preds, {"peak_reached": False})[0][1]
    assert report.forecast_rows(Table({}, 0), summary) == []
    with tempfile.TemporaryDirectory() as out:
        figures = []
        report.failure_forecast(summary, preds, out, figures)
        assert os.path.exists(os.path.join(out, "failure_forecast.png")), figures
