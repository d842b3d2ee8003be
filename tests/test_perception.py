"""Perception pipeline: trials files, the triplet SDP, cross-validation, bootstrap, observer, design, fit."""
from __future__ import annotations

import csv
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import norm, spearmanr

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.perception import values as values_module
from roughness.perception.bootstrap import bootstrap, thurstone_bootstrap
from roughness.perception.crossval import cross_validate
from roughness.perception.design import balanced_design
from roughness.perception.embed import SOLVER_EPS, TripletSDP, lambda_max, margin_matrix, triplet_error, triplet_margins
from roughness.perception.fit import correlate, sampling_fit
from roughness.perception.observer import DEFAULT_SIGMA, Observer, noiseless_answer
from roughness.perception.thurstone import PRIOR_SD, answer_probability, negative_log_likelihood, thurstone_scale
from roughness.perception.trials import parse_trials
from roughness.perception.values import StimulusValue, stimulus_values

HEADER = "subject,reference,left,right,answer"


def consistent_trials(p: np.ndarray, ids: list[str]) -> str:
    """Every triplet of points on a line with distinct distances, answered without noise."""
    lines = [HEADER]
    n = len(p)
    for r in range(n):
        for a in range(n):
            for b in range(a + 1, n):
                if len({r, a, b}) == 3 and abs(abs(p[a] - p[r]) - abs(p[b] - p[r])) > 1e-9:
                    answer = "left" if abs(p[a] - p[r]) < abs(p[b] - p[r]) else "right"
                    lines.append(f"s1,{ids[r]},{ids[a]},{ids[b]},{answer}")
    return "\n".join(lines) + "\n"


def simulated_text(p: np.ndarray, trials: int, seed: int, observer: Observer) -> str:
    ids = [f"x{i}" for i in range(len(p))]
    design = balanced_design(ids, trials, seed=seed)
    triplets = np.array([[ids.index(t.reference), ids.index(t.left), ids.index(t.right)] for t in design])
    left = observer.answer(p, triplets, np.random.default_rng(seed))
    return "\n".join([HEADER] + [f"s1,{t.reference},{t.left},{t.right},{'left' if a else 'right'}"
                                 for t, a in zip(design, left)]) + "\n"


# --- the solver on problems with known answers ---------------------------------------------------------

def test_five_stimuli_on_a_line_are_ordered_and_one_dimensional():
    p = np.array([0.0, 1.0, 3.0, 4.5, 7.0])  # unequal gaps: every consistent triplet is strict
    trials = parse_trials(consistent_trials(p, list("abcde")))
    unique, inverse = trials.unique()
    result = TripletSDP(5, unique).solve(np.bincount(inverse), lam=1e-3)
    assert result.success, result.message
    assert result.iterations > 0 and result.seconds > 0
    x = result.coordinates(1)[:, 0]
    assert abs(spearmanr(x, p)[0]) == pytest.approx(1.0)
    assert triplet_error(result.gram, trials.triplets) == 0.0
    spectrum = result.eigenvalues  # minimal trace is not exactly 1-D for ordinal data, but the line dominates
    assert spectrum[0] > 2 * spectrum[1]
    assert np.allclose(result.gram.sum(axis=0), 0.0, atol=1e-9 * np.trace(result.gram))  # centred


def test_margins_are_one_sparse_matrix_times_vec_k():
    rng = np.random.default_rng(3)
    x = rng.normal(size=(6, 2))
    gram = x @ x.T
    triplets = np.array([rng.choice(6, 3, replace=False) for _ in range(20)])
    via_matrix = margin_matrix(6, triplets) @ gram.ravel(order="F")
    dist = ((x[:, None] - x[None]) ** 2).sum(-1)
    r, c, f = triplets.T
    assert np.allclose(via_matrix, triplet_margins(gram, triplets))
    assert np.allclose(via_matrix, dist[r, f] - dist[r, c])


def test_lambda_max_is_where_the_embedding_collapses():
    p = np.array([0.0, 1.0, 3.0, 4.5, 7.0])
    trials = parse_trials(consistent_trials(p, list("abcde")))
    unique, inverse = trials.unique()
    w = np.bincount(inverse).astype(float)
    top = lambda_max(5, unique, w)
    sdp = TripletSDP(5, unique)
    above, below = sdp.solve(w, 1.05 * top), sdp.solve(w, 0.8 * top)
    # SCS stops at relative tolerance SOLVER_EPS: "zero" means zero up to that tolerance of the objective scale
    assert np.trace(above.gram) < 10 * SOLVER_EPS * w.sum() / top
    assert np.trace(below.gram) > 100 * SOLVER_EPS * w.sum() / top


def test_solver_rejects_bad_weights_and_indices():
    with pytest.raises(InputError, match="indices"):
        TripletSDP(3, np.array([[0, 1, 3]]))
    sdp = TripletSDP(3, np.array([[0, 1, 2]]))
    with pytest.raises(InputError, match="weights"):
        sdp.solve(np.array([-1.0]), 1.0)
    with pytest.raises(InputError, match="lam"):
        sdp.solve(np.array([1.0]), float("nan"))


def test_noisy_recovery_small():
    """12 stimuli, 600 noisy triplets at the default Weber noise: the order comes back."""
    p = np.log(np.linspace(0.625, 1.625, 12))
    trials = parse_trials(simulated_text(p, 600, 1, Observer()), repeats="keep")
    unique, inverse = trials.unique()
    w = np.bincount(inverse).astype(float)
    result = TripletSDP(len(p), unique).solve(w, 0.1 * lambda_max(len(p), unique, w))
    order = [int(s[1:]) for s in trials.stimuli]
    assert abs(spearmanr(result.coordinates(1)[:, 0], p[order])[0]) > 0.9


# --- the Thurstone scale ------------------------------------------------------------------------------

def test_thurstone_gradient_matches_finite_differences():
    rng = np.random.default_rng(3)
    triplets = np.array([rng.permutation(6)[:3] for _ in range(40)])
    weights = rng.integers(1, 4, 40).astype(float)
    p = rng.normal(0, 1.5, 6)
    value, grad = negative_log_likelihood(p, triplets, weights, lapse=0.02)
    h = 1e-6
    numeric = [(negative_log_likelihood(p + h * e, triplets, weights, 0.02)[0]
                - negative_log_likelihood(p - h * e, triplets, weights, 0.02)[0]) / (2 * h) for e in np.eye(6)]
    assert np.allclose(grad, numeric, rtol=1e-6, atol=1e-6 * abs(value))


def test_thurstone_probability_matches_the_simulated_observer():
    """The closed form P(c closer) against 200,000 answers of the observer (noise SD 1)."""
    p = np.array([0.0, 0.7, -0.4, 1.5])
    triplets = np.array([[0, 1, 2], [0, 2, 3], [1, 0, 3], [3, 1, 2]])
    prob = answer_probability(p, triplets, lapse=0.0)[0]
    draws = 200_000
    said = np.array([Observer(sigma=1.0).answer(p, np.repeat(t[None], draws, 0), np.random.default_rng(i)).mean()
                     for i, t in enumerate(triplets)])
    assert np.all(np.abs(said - prob) < 5 * np.sqrt(prob * (1 - prob) / draws))  # Monte Carlo, 5 SE


def test_thurstone_recovers_the_scale_in_noise_units():
    """10 stimuli 4 noise SDs apart end to end, 3,000 answers: the metric scale comes back in its units."""
    p = np.linspace(-2.0, 2.0, 10)
    trials = parse_trials(simulated_text(p, 3000, 4, Observer(sigma=1.0)), repeats="keep")
    unique, inverse = trials.unique()
    w = np.bincount(inverse).astype(float)
    order = [int(s[1:]) for s in trials.stimuli]
    start = TripletSDP(len(p), unique).solve(w, 0.1 * lambda_max(len(p), unique, w)).coordinates(1)[:, 0]
    fit = thurstone_scale(unique, w, start, lapse=0.0)
    assert fit.success and abs(np.sum(fit.coordinate)) < 1e-6
    slope = np.polyfit(p[order], fit.coordinate, 1)[0]
    assert 0.9 < abs(slope) < 1.1  # the unit is the noise SD (Monte Carlo: slope SE about 0.02 here)
    assert np.corrcoef(p[order], fit.coordinate)[0, 1] ** 2 > 0.99


def test_thurstone_scale_is_finite_on_noise_free_answers():
    p = np.array([0.0, 1.0, 3.0, 4.5, 7.0])
    trials = parse_trials(consistent_trials(p, list("abcde")))
    unique, inverse = trials.unique()
    fit = thurstone_scale(unique, np.bincount(inverse).astype(float), p - 3, lapse=0.0)
    assert np.all(np.isfinite(fit.coordinate)) and np.all(np.abs(fit.coordinate) < 5 * PRIOR_SD)
    assert np.all(np.diff(fit.coordinate) > 0)


# --- cross-validation and bootstrap ------------------------------------------------------------------

@pytest.fixture(scope="module")
def noisy_trials():
    p = np.log(np.linspace(0.625, 1.625, 8))
    return parse_trials(simulated_text(p, 240, 2, Observer()), repeats="keep")


def test_cross_validation_is_deterministic_and_shaped(noisy_trials):
    a = cross_validate(noisy_trials, folds=3, seed=5)
    b = cross_validate(noisy_trials, folds=3, seed=5)
    assert a.test_error.shape == (13, 3) and a.failed_solves == 0
    assert np.array_equal(a.test_error, b.test_error) and a.best_lambda == b.best_lambda
    assert a.best_lambda in a.lambdas
    assert np.isclose(a.lambdas[-1] / a.lambdas[0], 1e3)
    # far above lambda_max the embedding is a point: every triplet is a tie (error 1/2)
    unique, inverse = noisy_trials.unique()
    top = lambda_max(len(noisy_trials.stimuli), unique, np.bincount(inverse))
    c = cross_validate(noisy_trials, [0.01 * top, 2 * top], folds=3, seed=5)
    assert np.all(c.test_error[-1] == 0.5) and np.all(c.train_error[-1] == 0.5)
    assert a.train_error.mean(axis=1)[0] <= a.train_error.mean(axis=1)[-1]


def test_bootstrap_is_deterministic_for_a_seed_and_across_workers(noisy_trials):
    unique, inverse = noisy_trials.unique()
    w = np.bincount(inverse).astype(float)
    lam = 0.1 * lambda_max(len(noisy_trials.stimuli), unique, w)
    coordinate = TripletSDP(len(noisy_trials.stimuli), unique).solve(w, lam).coordinates(1)[:, 0]
    one = bootstrap(noisy_trials, lam, coordinate, resamples=4, seed=9, workers=1)
    again = bootstrap(noisy_trials, lam, coordinate, resamples=4, seed=9, workers=1)
    two = bootstrap(noisy_trials, lam, coordinate, resamples=4, seed=9, workers=2)
    other = bootstrap(noisy_trials, lam, coordinate, resamples=4, seed=10, workers=1)
    assert np.array_equal(one.samples, again.samples)
    assert np.array_equal(one.samples, two.samples)
    assert not np.array_equal(one.samples, other.samples)
    assert np.all(one.samples @ coordinate > 0)  # sign-aligned to the full-data embedding
    assert np.all(one.low <= one.high)
    scale = thurstone_scale(unique, w, coordinate).coordinate
    first = thurstone_bootstrap(noisy_trials, scale, resamples=20, seed=9)
    assert np.array_equal(first.samples, thurstone_bootstrap(noisy_trials, scale, resamples=20, seed=9).samples)
    assert first.failed_solves == 0 and np.all(first.samples @ scale > 0) and np.all(first.low < first.high)


# --- trials files ----------------------------------------------------------------------------------

@pytest.mark.parametrize("text, message", [
    ("subject,reference,left,answer\ns1,a,b,left\n", "missing column"),
    (HEADER + "\ns1,a,b,c,left,extra\n", "line 2: 6 fields"),
    (HEADER + "\ns1,a,b,c\n", "line 2: fewer fields"),
    (HEADER + "\ns1,a,b,c,up\n", "answer must be 'left' or 'right'"),
    (HEADER + "\ns1,a,a,c,left\n", "three different stimuli"),
    (HEADER + "\ns1,,b,c,left\n", "empty reference"),
    (HEADER + "\n", "no trials"),
    ("", "empty file"),
    (HEADER + "\ns1,a,b,c,left\ns1,a,c,b,left\n", "contradictory duplicates.*line 3 contradicts line 2"),
])
def test_bad_trials_are_refused_with_the_line(text, message):
    with pytest.raises(InputError, match=message):
        parse_trials(text, "t.csv", repeats="error")  # refuses contradictory duplicates too


def test_trials_against_a_stimuli_table_and_repeats():
    text = HEADER + ",rt_ms\ns1,a,b,c,left,812\ns1,a,c,b,left,640\ns2,a,b,c,right,700\n"
    with pytest.raises(InputError, match="not in the stimuli table: c"):
        parse_trials(text, "t.csv", stimuli=["a", "b", "z"], repeats="keep")
    trials = parse_trials(text, "t.csv", stimuli=["z", "c", "b", "a"], repeats="keep")
    assert trials.stimuli == ("c", "b", "a")  # table order, stimuli without trials dropped
    assert trials.rows[0]["rt_ms"] == "812" and trials.fieldnames[-1] == "rt_ms"
    a, b, c = 2, 1, 0
    assert trials.triplets.tolist() == [[a, b, c], [a, c, b], [a, c, b]]
    # different subjects may disagree; the same subject twice is a contradiction if asked to refuse those
    with pytest.raises(InputError, match="contradictory"):
        parse_trials(text, "t.csv", repeats="error")


# --- observer and design -----------------------------------------------------------------------------

def test_observer_noise_model_matches_its_weber_fraction():
    """Reference far below both comparisons: the task is a 2AFC on p, P(left) = Phi(dp / (sigma sqrt 2))."""
    n = 20000
    p = np.array([-100.0, 0.0, math.log(1.19)])
    triplets = np.tile([0, 1, 2], (n, 1))
    left = Observer().answer(p, triplets, np.random.default_rng(0))
    expected = norm.cdf(math.log(1.19) / (DEFAULT_SIGMA * math.sqrt(2)))
    assert expected == pytest.approx(0.75, abs=1e-6)  # the default sigma is the 75% Weber threshold
    assert abs(left.mean() - expected) < 4 * math.sqrt(expected * (1 - expected) / n)
    lapsed = Observer(lapse=1.0).answer(p, triplets, np.random.default_rng(1))
    assert abs(lapsed.mean() - 0.5) < 4 * math.sqrt(0.25 / n)
    exact = Observer(sigma=0.0).answer(p, triplets[:10], np.random.default_rng(2))
    assert np.array_equal(exact, noiseless_answer(p, triplets[:10]))
    with pytest.raises(InputError, match="lapse"):
        Observer(lapse=1.5)


def test_design_is_balanced_randomised_and_seeded():
    ids = [f"t{i}" for i in range(12)]
    design = balanced_design(ids, 100, subjects=("s1", "s2"), seed=4)
    assert design == balanced_design(ids, 100, subjects=("s1", "s2"), seed=4)
    assert design != balanced_design(ids, 100, subjects=("s1", "s2"), seed=5)
    for subject in ("s1", "s2"):
        trials = [t for t in design if t.subject == subject]
        assert [t.trial for t in trials] == list(range(1, 101))
        assert all(len({t.reference, t.left, t.right}) == 3 for t in trials)
        assert len({(t.reference, frozenset((t.left, t.right))) for t in trials}) == 100  # no trial twice
        refs = np.array([sum(t.reference == s for t in trials) for s in ids])
        comps = np.array([sum(s in (t.left, t.right) for t in trials) for s in ids])
        sides = np.array([sum(t.left == s for t in trials) - sum(t.right == s for t in trials) for s in ids])
        assert refs.max() - refs.min() <= 1
        assert comps.max() - comps.min() <= 2
        assert np.abs(sides).max() <= 1
    first = [ids.index(t.reference) for t in design[:12]]
    assert first != sorted(first)  # shuffled order


# --- fit ---------------------------------------------------------------------------------------------

def test_refit_over_sampling_uses_the_fields():
    """Fields whose amplitude is the truth: every (d, r) that fits the window gives R = 1."""
    axis = np.arange(-4.0, 4.0001, 0.1)
    rng = np.random.default_rng(0)
    base = rng.normal(size=(len(axis), len(axis)))
    amplitude = np.array([1.0, 2.0, 3.5, 5.0])
    values = [StimulusValue(f"s{i}", 0.0, 0.0, "fem:coarse", a * base, axis) for i, a in enumerate(amplitude)]
    fit = sampling_fit(values, amplitude, [0.8, 3.0], [0.4, 3.0], 8.0, 500, 0)
    assert np.allclose(fit.pearson[[0, 0, 1], [0, 1, 0]], 1.0)
    assert math.isnan(fit.pearson[1, 1])  # d/2 + r = 4.5 mm: the pair does not fit in the 8 mm window
    summary = fit.as_dict()
    assert summary["best"]["pearson"] == pytest.approx(1.0)
    with pytest.raises(InputError, match="FEM"):
        sampling_fit([StimulusValue("a", 1.0, 0.0, "surrogate")], amplitude[:1], [0.8], [0.8], 8.0, 10, 0)


def test_correlate():
    c = correlate(np.array([1.0, 2.0, 3.0, 4.0]), np.array([1.0, 4.0, 9.0, 16.0]))
    assert c.spearman == pytest.approx(1.0) and 0.9 < c.pearson < 1.0
    assert math.isnan(correlate(np.ones(4), np.arange(4.0)).pearson)


class _FakeResult:
    def __init__(self, heights: np.ndarray, force: float) -> None:
        self.roughness = float(heights.std() * force)
        self.roughness_stderr = 0.001
        self.seconds = 0.0
        self.grid_axis_mm = np.linspace(-4, 4, 9)
        self.fluctuation = np.full((9, 9), self.roughness)

        class _Config:
            def as_dict(self):
                return {"force_n": force}

        self.config = _Config()


def test_fem_values_are_cached_by_content_and_configuration(tmp_path, monkeypatch):
    from roughness.engines import FemEngine
    from roughness.surface.heightmap import Heightmap

    calls = []

    def fake(engine, hm):
        calls.append(engine.config)
        return _FakeResult(hm.heights, engine.config.force_n)

    monkeypatch.setattr(FemEngine, "simulate", fake)
    h = np.random.default_rng(0).uniform(0, 1, (20, 20))
    a, same, other = Heightmap(h, 0.5), Heightmap(h.copy(), 0.5), Heightmap(h + 0.1 * h ** 2, 0.5)
    first = stimulus_values(["a"], [a], "fem:coarse", tmp_path)
    assert len(calls) == 1 and len(list(tmp_path.glob("arrays/*.npz"))) == 1
    renamed = stimulus_values(["renamed"], [same], "fem:coarse", tmp_path)
    assert len(calls) == 1  # same heights and configuration under another name: from the cache
    assert renamed[0].roughness == first[0].roughness and renamed[0].fluctuation.shape == (9, 9)
    stimulus_values(["a"], [a], "fem:coarse", tmp_path, force_n=5.0)
    stimulus_values(["a"], [Heightmap(h, 0.25)], "fem:coarse", tmp_path)
    stimulus_values(["b"], [other], "fem:coarse", tmp_path)
    assert len(calls) == 4 and len(list(tmp_path.glob("arrays/*.npz"))) == 4
    assert [c.fidelity for c in calls] == ["coarse"] * 4 and calls[1].force_n == 5.0
    with pytest.raises(InputError, match="engine"):
        values_module.check_engine("fem:ultra")


# --- command line ------------------------------------------------------------------------------------

def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def test_cli_embed_writes_embedding_and_refuses_to_overwrite(tmp_path, capsys):
    p = np.array([0.0, 1.0, 3.0, 4.5, 7.0])
    trials = _write(tmp_path / "trials.csv", consistent_trials(p, ["a", "b", "c", "d", "e"]))
    out = tmp_path / "emb"
    args = ["perception", "embed", str(trials), "--out", str(out), "--folds", "2", "--resamples", "3",
            "--workers", "1", "--roughest", "e", "--quiet"]
    assert main(args) == 0
    with open(out / "embedding.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["stimulus"] for r in rows] == list("abcde")
    x = np.array([float(r["coordinate"]) for r in rows])
    assert np.all(np.diff(x) > 0)  # oriented: e (the roughest) positive, and in order
    assert all(float(r["low"]) <= float(r["high"]) for r in rows)
    summary = json.loads((out / "embedding.json").read_text())
    assert summary["spectrum"][0] > 2 * summary["spectrum"][1] and summary["cross_validation"]["folds"] == 2
    assert (out / "embedding.png").stat().st_size > 0 and (out / "cross_validation.png").stat().st_size > 0
    capsys.readouterr()
    assert main(args) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert main(args + ["--overwrite", "--scale", "thurstone"]) == 0
    summary = json.loads((out / "embedding.json").read_text())
    assert summary["scale"] == "thurstone" and summary["thurstone"]["success"]
    with open(out / "embedding.csv") as f:
        x = np.array([float(r["coordinate"]) for r in csv.DictReader(f)])
    assert np.all(np.diff(x) > 0)


@pytest.mark.parametrize("text, message", [
    (HEADER + "\ns1,a,b,c,maybe\n", "answer must be"),
    (HEADER + "\ns1,a,b,c,left\ns1,a,b,c,right\n", "contradictory duplicates"),
    ("subject,reference,left,right\ns1,a,b,c\n", "missing column"),
])
def test_cli_bad_trials_exit_2(tmp_path, capsys, text, message):
    trials = _write(tmp_path / "t.csv", text)
    argv = ["perception", "embed", str(trials), "--out", str(tmp_path / "o"), "--quiet", "--repeats", "error"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_cli_missing_stimuli_exit_2(tmp_path, capsys):
    trials = _write(tmp_path / "t.csv", HEADER + "\ns1,a,b,c,left\n")
    table = _write(tmp_path / "stimuli.csv", "stimulus,texture\na,standard-1.0\nb,standard-1.25\nd,flat\n")
    assert main(["perception", "embed", str(trials), "--stimuli", str(table), "--out", str(tmp_path / "o")]) == 2
    assert "not in the stimuli table: c" in capsys.readouterr().err


def test_cli_without_cvxpy_exits_2_with_the_install_hint(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "cvxpy", None)  # import cvxpy raises ImportError
    trials = _write(tmp_path / "t.csv", HEADER + "\ns1,a,b,c,left\n")
    assert main(["perception", "embed", str(trials), "--out", str(tmp_path / "o")]) == 2
    assert "pip install 'roughness[perception]'" in capsys.readouterr().err


def test_cli_design_simulate_embed_fit(tmp_path, capsys, monkeypatch):
    """The experiment kit end to end on the surrogate: a design, a simulated experiment, embed, fit."""
    names = ["standard-0.625", "standard-1.0", "standard-1.625", "flattop-0.1", "flattop-0.5"]
    table = _write(tmp_path / "stimuli.csv", "stimulus,texture,seed\n" + "".join(f"{n},{n},0\n" for n in names))
    design = tmp_path / "design.csv"
    assert main(["perception", "design", "--stimuli", str(table), "--trials", "20", "--out", str(design)]) == 0
    assert "fill the answer column" in capsys.readouterr().out
    assert main(["perception", "design", "--stimuli", str(table), "--trials", "20", "--out", str(design)]) == 2
    truth = _write(tmp_path / "truth_in.csv", "stimulus,roughness\n" + "".join(
        f"{n},{v}\n" for n, v in zip(names, [0.03, 0.06, 0.11, 0.09, 0.07])))
    sim = tmp_path / "sim"
    assert main(["perception", "simulate", "--stimuli", str(table), "--truth", str(truth), "--trials", "150",
                 "--sigma", "0.05", "--out", str(sim), "--quiet"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["roughest"] == "standard-1.625" and report["trials"] == 150
    emb = tmp_path / "emb"
    assert main(["perception", "embed", str(sim / "trials.csv"), "--stimuli", str(table), "--out", str(emb),
                 "--folds", "2", "--resamples", "2", "--workers", "1", "--roughest", "standard-1.625",
                 "--repeats", "keep", "--quiet"]) == 0  # 150 trials over 30 distinct ones: repeats
    fitted = tmp_path / "fit"
    assert main(["perception", "fit", str(emb / "embedding.csv"), "--stimuli", str(table), "--out", str(fitted),
                 "--engine", "surrogate", "--exclude", "flattop-0.1", "--quiet"]) == 0
    assert "Pearson R" in capsys.readouterr().out
    summary = json.loads((fitted / "fit.json").read_text())
    assert summary["correlations"]["V"]["all"]["n"] == 5 and summary["correlations"]["V"]["included"]["n"] == 4
    assert set(summary["correlations"]) >= {"V", "ra", "p90"}
    assert summary["sampling"] is None  # the surrogate has no fields to re-sample
    with open(fitted / "fit.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["included"] for r in rows].count("0") == 1 and rows[0]["engine"] == "surrogate"
    assert main(["perception", "fit", str(emb / "embedding.csv"), "--stimuli", str(table), "--out",
                 str(tmp_path / "f2"), "--engine", "surrogate", "--exclude", "nope"]) == 2
    assert "excluded stimuli not in the embedding: nope" in capsys.readouterr().err
    # the paper's homogeneity exclusion, from the table's spreads (JND): the two largest go, with --exclude's
    spread = {"standard-0.625": 0.1, "standard-1.0": 0.9, "standard-1.625": 0.2, "flattop-0.1": 0.5, "flattop-0.5": 0.9}
    rated = _write(tmp_path / "rated.csv", "stimulus,texture,seed,homogeneity\n" + "".join(
        f"{n},{n},0,{spread[n]}\n" for n in names))
    assert main(["perception", "fit", str(emb / "embedding.csv"), "--stimuli", str(rated), "--out",
                 str(tmp_path / "f3"), "--engine", "surrogate", "--exclude", "flattop-0.5",
                 "--exclude-least-homogeneous", "2", "--quiet"]) == 0
    assert "without 2 excluded" in capsys.readouterr().out
    summary = json.loads((tmp_path / "f3" / "fit.json").read_text())
    assert summary["least_homogeneous"] == ["standard-1.0", "flattop-0.5"]  # tie at 0.9: table order
    assert summary["excluded"] == ["flattop-0.5", "standard-1.0"] and summary["homogeneity_spread_jnd"] == spread
    assert summary["correlations"]["V"]["included"]["n"] == 3
    assert main(["perception", "fit", str(emb / "embedding.csv"), "--stimuli", str(rated), "--out",
                 str(tmp_path / "f4"), "--engine", "surrogate", "--exclude", "standard-0.625",
                 "--exclude-least-homogeneous", "2"]) == 2  # 3 of 5 excluded
    assert "the fit needs at least 3" in capsys.readouterr().err


def test_plan_finds_the_trials_needed_and_is_deterministic():
    from roughness.perception.plan import Plan, PlanStep, plan_trials

    v = 0.05 * np.linspace(0.625, 1.625, 6) ** 2
    ids = [f"x{i}" for i in range(6)]
    plan = plan_trials(ids, v, [15, 1500], experiments=3, seed=2)
    again = plan_trials(ids, v, [1500, 15], experiments=3, seed=2)
    assert [s.trials for s in plan.steps] == [15, 1500]
    assert all(np.array_equal(a.pearson, b.pearson) for a, b in zip(plan.steps, again.steps))
    assert np.isclose(plan.limit, np.corrcoef(v, np.log(v))[0, 1])
    few, many = (np.abs(s.pearson - plan.limit) for s in plan.steps)
    assert many.max() < few.mean()  # 1,500 answers about 6 stimuli pin the scale down; 15 do not
    assert np.all(plan.steps[1].spearman_truth > 0.9)
    fake = Plan(tuple(ids), v, 0.9, 0.05, 0.5, [PlanStep(10, np.array([0.5, 0.88]), np.ones(2)),
                                                 PlanStep(20, np.array([0.86, 0.8]), np.ones(2)),
                                                 PlanStep(40, np.array([0.9, 0.9]), np.ones(2))])
    assert fake.needed == 10 and [fake.within(s) for s in fake.steps] == [0.5, 0.5, 1.0]
    assert Plan(tuple(ids), v, 0.9, 0.05, 0.9, fake.steps).needed == 40
    assert Plan(tuple(ids), v, 0.2, 0.05, 0.9, fake.steps).needed is None
    with pytest.raises(InputError, match="same V"):
        plan_trials(ids, np.full(6, 0.1), [10], experiments=2)


def test_cli_plan(tmp_path, capsys):
    names = ["a", "b", "c", "d", "e"]
    table = _write(tmp_path / "s.csv", "stimulus,texture\n" + "".join(f"{n},flat\n" for n in names))
    truth = _write(tmp_path / "t.csv", "stimulus,roughness\n" + "".join(
        f"{n},{v}\n" for n, v in zip(names, [0.03, 0.05, 0.07, 0.1, 0.14])))
    out = tmp_path / "plan"
    args = ["perception", "plan", "--stimuli", str(table), "--truth", str(truth), "--trials", "400,20",
            "--experiments", "2", "--out", str(out), "--quiet"]
    assert main(args) == 0
    assert "R with unlimited trials" in capsys.readouterr().out
    with open(out / "plan.csv") as f:
        assert [r["trials"] for r in csv.DictReader(f)] == ["20", "400"]
    summary = json.loads((out / "plan.json").read_text())
    assert summary["steps"][0]["experiments"] == 2 and summary["tolerance"] == 0.05
    assert main(args) == 2 and "--overwrite" in capsys.readouterr().err
    assert main(args[:7] + ["0,10"] + args[8:]) == 2


def test_stimuli_table_files_textures_and_errors(tmp_path):
    from roughness.perception.stimuli import read_stimuli

    (tmp_path / "maps").mkdir()
    np.save(tmp_path / "maps" / "a.npy", np.zeros((40, 40)))
    table = _write(tmp_path / "s.csv", "stimulus,file,pixel_mm,texture,seed,params,note\n"
                   "a,maps/a.npy,0.3,,,,a scan\nb,,,standard-1.0,2,,\nc,,,knit,0,wale_mm=1.2;height_mm=0.5,\n")
    a, b, c = read_stimuli(table)
    assert a.file == tmp_path / "maps" / "a.npy" and a.heightmap().pixel_mm == 0.3
    assert (b.texture, b.seed) == ("standard-1.0", 2)
    assert c.params == {"wale_mm": 1.2, "height_mm": 0.5}
    for rows, message in [("a,maps/a.npy,0.3,flat,,,\n", "exactly one of file or texture"),
                          ("a,maps/none.npy,0.3,,,,\n", "not found"),
                          ("a,,,flat,x,,\n", "seed must be"),
                          ("a,,,flat,,,\na,,,flat,,,\n", "repeated stimulus ids: a"),
                          ("a,,,flat,,w,\n", "key=value")]:
        bad = _write(tmp_path / "bad.csv", "stimulus,file,pixel_mm,texture,seed,params,note\n" + rows
                     + "y,,,flat,,,\nz,,,flat,,,\n")
        with pytest.raises(InputError, match=message):
            read_stimuli(bad)


def test_stimuli_table_homogeneity_column(tmp_path):
    from roughness.perception.stimuli import read_stimuli

    good = _write(tmp_path / "h.csv", "stimulus,texture,homogeneity\na,flat,0.4\nb,flat,\nc,flat,0\n")
    assert [s.homogeneity for s in read_stimuli(good)] == [0.4, None, 0.0]
    for value in ("-1", "nan", "inf", "x"):
        bad = _write(tmp_path / "hb.csv", f"stimulus,texture,homogeneity\na,flat,{value}\nb,flat,\nc,flat,\n")
        with pytest.raises(InputError, match="homogeneity|must be a number"):
            read_stimuli(bad)


def test_design_writes_printable_plates_of_every_stimulus(tmp_path):
    import trimesh

    table = tmp_path / "stimuli.csv"
    np.save(tmp_path / "scan.npy", np.random.default_rng(0).random((120, 130)) * 0.3)
    table.write_text("stimulus,texture,file,pixel_mm\nbumps 1.0,standard-1.0,,\nknit,knit,,\nscan,,scan.npy,0.05\n")
    plates = tmp_path / "plates"
    args = ["perception", "design", "--stimuli", str(table), "--trials", "4", "--out", str(tmp_path / "d.csv"),
            "--plates", str(plates), "--plate-mm", "5", "--base-mm", "1"]
    assert main(args) == 0
    assert sorted(p.name for p in plates.iterdir()) == ["bumps_1.0.stl", "knit.stl", "scan.stl"]
    for p in plates.iterdir():
        mesh = trimesh.load(p)
        assert mesh.is_watertight and mesh.extents[0] == pytest.approx(5 - 0.05, abs=1e-4)
    assert main(args) == 2  # outputs exist: refused without --overwrite
    small = [*args[:-6], "--out", str(tmp_path / "e.csv"), "--plates", str(tmp_path / "p2"), "--plate-mm", "25"]
    assert main(small) == 2 and not (tmp_path / "p2").exists()  # the 6 mm scan cannot make a 25 mm plate


@pytest.mark.parametrize("coordinates", ["equal", "excluded equal"])
def test_fit_with_undefined_correlations_says_undefined(tmp_path, capsys, coordinates):
    """An embedding whose coordinates are all equal (or equal among the included stimuli) has no Pearson R: the
    text, the JSON and the plot's title say "undefined" / null (the plot raised on a None R)."""
    names = ["standard-0.625", "standard-1.0", "standard-1.625", "flattop-0.5"]
    table = _write(tmp_path / "stimuli.csv", "stimulus,texture,seed\n" + "".join(f"{n},{n},0\n" for n in names))
    values = [0.0, 0.0, 0.0, 0.0] if coordinates == "equal" else [0.0, 0.0, 0.0, 1.0]
    embedding = _write(tmp_path / "embedding.csv", "stimulus,coordinate,low,high\n" + "".join(
        f"{n},{c},{c - 0.1},{c + 0.1}\n" for n, c in zip(names, values)))
    exclude = [] if coordinates == "equal" else ["--exclude", "flattop-0.5"]
    assert main(["perception", "fit", str(embedding), "--stimuli", str(table), "--out", str(tmp_path / "fit"),
                 "--engine", "surrogate", *exclude]) == 0
    out = capsys.readouterr().out
    summary = json.loads((tmp_path / "fit" / "fit.json").read_text())
    part = "all" if coordinates == "equal" else "included"
    assert summary["correlations"]["V"][part]["pearson"] is None and "R undefined" in out
    assert (tmp_path / "fit" / "fit.png").stat().st_size > 1000


@pytest.mark.parametrize("after_lines", [0, 1, 3])
def test_ctrl_c_with_two_workers_stops_cleanly(tmp_path, after_lines):
    """Ctrl-C reaches every process of the terminal's group: the workers ignore it, the parent stops them and says
    "interrupted" (exit 130); no process prints a traceback (1 run in 6 did), whenever it comes."""
    import os
    import signal
    import subprocess

    rng = np.random.default_rng(0)
    truth = np.linspace(0, 1, 14)
    rows = []
    for _ in range(3000):
        r, a, b = rng.choice(14, 3, replace=False)
        rows.append(f"p1,s{r},s{a},s{b},{'left' if abs(truth[r] - truth[a]) < abs(truth[r] - truth[b]) else 'right'}")
    trials = _write(tmp_path / "trials.csv", "subject,reference,left,right,answer\n" + "\n".join(rows) + "\n")
    proc = subprocess.Popen([sys.executable, "-m", "roughness.cli", "perception", "embed", str(trials), "--out",
                             str(tmp_path / "emb"), "--folds", "2", "--resamples", "40", "--workers", "2"],
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    seen = []
    for line in proc.stderr:  # progress lines: interrupt once the solves are under way
        seen.append(line)
        if "solves" in line and sum("solves" in s for s in seen) > after_lines:
            break
    os.killpg(proc.pid, signal.SIGINT)
    rest = proc.stderr.read()
    assert proc.wait(timeout=60) == 130, "".join(seen) + rest
    assert "Traceback" not in rest and "interrupted" in rest, rest
