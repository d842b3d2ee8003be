"""Recovery of a known truth: 30 stimuli, 2,000 simulated triplets (the issue's targets).

For each seed: 30 stimuli with ln(lambda) uniform over the standard scale's range (0.625 to
1.625 mm) are judged by the default simulated observer (Weber noise sigma = 0.18 on ln lambda) in a
balanced design; the pipeline (10-fold CV over lambda, embedding, 500 bootstrap resamples) runs,
and we record:
- Spearman (and Pearson) of the 1-D coordinate with the truth;
- the held-out triplet error at the lambda CV picks, against the noise floor: the fraction of the
  observer's answers that disagree with a noise-free observer (the best any embedding can do);
- the spectrum (share of the first eigenvalue, ratio of the first two);
- bootstrap coverage of the truth: the truth mapped onto the embedding's units by least squares
  (coordinate ~ a * truth + b), and the fraction of stimuli whose 5-95% interval contains it;
- bootstrap coverage of the estimand: what the same SDP gives with unlimited trials (approximated by
  ``--estimand-factor`` times as many trials from the same observer, at lambda times that factor,
  which leaves the minimiser of the expected objective unchanged). The bootstrap measures sampling
  variability around this, not the regulariser's shrinkage or the nonlinearity of a non-metric
  scale, so this is the coverage a 5-95% interval should have (about 90%);
- the same for the Thurstone scale (``embed --scale thurstone``, started from the SDP at the CV's
  lambda): coverage of the truth, and the slope of the scale against the truth in the observer's
  noise SDs (1 = the scale's unit is the noise SD, as the model says);
- the SDP's coverage of the truth with other kinds of interval from the same resamples (basic,
  bias-corrected, normal, each resample's scale fitted to the full embedding's);
- the SDP's bias: the largest deviation of the estimand from the line through the truth, as a
  fraction of the range (the part of the SDP's error no bootstrap interval can see).

``--scale thurstone`` skips cross-validation and the SDP's bootstrap and estimand: the SDP (at
lambda_max / 10) only gives the maximum-likelihood fit its start, which does not change its optimum.
A quick way to measure the Thurstone coverage over many seeds.

    PYTHONPATH=.:benchmarks OMP_NUM_THREADS=1 python benchmarks/perception_recovery.py --seeds 0 1 2 --workers 2
    PYTHONPATH=.:benchmarks OMP_NUM_THREADS=1 python benchmarks/perception_recovery.py --scale thurstone \
        --seeds 0 1 2 3 4 5 6 7 8 9 --out perception_recovery_thurstone
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from perception_speed import simulated  # benchmarks/ is on sys.path when run as a script
from scipy.stats import norm, spearmanr

from roughness.perception.analysis import analyse
from roughness.perception.embed import TripletSDP, aligned, lambda_max
from roughness.perception.observer import DEFAULT_SIGMA, noiseless_answer
from roughness.perception.parallel import stderr_progress

RESULTS = Path(__file__).resolve().parent / "results"


def estimand(n: int, trials_count: int, seed: int, lam: float, factor: int, ids: tuple[str, ...]) -> np.ndarray:
    """1-D embedding of ``factor`` times the trials (same truth, other trials) at ``factor`` * lam, in ``ids`` order."""
    big, _ = simulated(n, factor * trials_count, seed, trial_seed=seed + 1000)
    unique, inverse = big.unique()
    result = TripletSDP(len(big.stimuli), unique).solve(np.bincount(inverse, minlength=len(unique)), factor * lam)
    order = [big.stimuli.index(s) for s in ids]
    return result.coordinates(1)[order, 0]


def coverage(low: np.ndarray, high: np.ndarray, target: np.ndarray) -> float:
    return float(np.mean((low <= target) & (target <= high)))


def on_scale(truth: np.ndarray, coordinate: np.ndarray) -> np.ndarray:
    """The truth mapped onto the coordinate's units by least squares (coordinate ~ a * truth + b)."""
    return np.polyval(np.polyfit(truth, coordinate, 1), truth)


def interval_variants(samples: np.ndarray, estimate: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """5-95% intervals from bootstrap samples (resamples, n) around ``estimate``, built five ways."""
    low, high = np.percentile(samples, [5, 95], axis=0)
    z0 = norm.ppf(np.clip(np.mean(samples < estimate, axis=0), 1e-3, 1 - 1e-3))  # bias correction (BC)
    bc = [np.percentile(samples[:, i], 100 * norm.cdf(2 * z0[i] + norm.ppf(q)))
          for q in (0.05, 0.95) for i in range(len(estimate))]
    sd = samples.std(axis=0, ddof=1)
    scale = (samples @ estimate) / np.sum(samples * samples, axis=1)  # each resample's scale fitted to the estimate
    scaled_low, scaled_high = np.percentile(samples * scale[:, None], [5, 95], axis=0)
    n = len(estimate)
    return {"percentile": (low, high), "basic": (2 * estimate - high, 2 * estimate - low),
            "BC": (np.array(bc[:n]), np.array(bc[n:])), "normal": (estimate - 1.645 * sd, estimate + 1.645 * sd),
            "scale-aligned percentile": (scaled_low, scaled_high)}


def one(seed: int, n: int, trials_count: int, resamples: int, workers: int, factor: int, sdp: bool) -> dict:
    trials, truth_sorted = simulated(n, trials_count, seed)
    truth = truth_sorted[[int(s[1:]) for s in trials.stimuli]]
    roughest = trials.stimuli[int(np.argmax(truth))]
    start = time.perf_counter()
    unique, inverse = trials.unique()
    lam = None if sdp else 0.1 * lambda_max(n, unique, np.bincount(inverse, minlength=len(unique)))
    a = analyse(trials, lam=lam, resamples=resamples if sdp else 0, workers=workers, seed=seed, roughest=roughest,
                progress=lambda what: stderr_progress(f"seed {seed} {what}"))
    seconds = time.perf_counter() - start
    start = time.perf_counter()
    t = analyse(trials, lam=a.fit.lam, resamples=resamples, seed=seed, roughest=roughest, scale="thurstone")
    thurstone_seconds = time.perf_counter() - start
    # the rows' triplets are (reference, closer, farther): a noise-free observer calls "closer" closer
    floor = float(np.mean(~noiseless_answer(truth, trials.triplets)))
    spectrum = a.fit.eigenvalues
    run = {"seed": seed, "stimuli": n, "trials": len(trials),
           "spearman": float(spearmanr(a.coordinate, truth)[0]),
           "pearson": float(np.corrcoef(a.coordinate, truth)[0, 1]), "lambda": a.fit.lam, "noise_floor": floor,
           "first_dimension_share": float(spectrum[0] / spectrum.sum()),
           "first_to_second": float(spectrum[0] / spectrum[1]) if spectrum[1] > 0 else None,
           "thurstone_spearman": float(spearmanr(t.coordinate, truth)[0]),
           "thurstone_pearson": float(np.corrcoef(t.coordinate, truth)[0, 1]),
           "thurstone_coverage": coverage(t.low, t.high, on_scale(truth, t.coordinate)),
           "thurstone_slope_noise_units": float(np.polyfit(truth, t.coordinate, 1)[0] * DEFAULT_SIGMA),
           "thurstone_seconds": thurstone_seconds, "seconds": seconds, "stage_seconds": a.seconds}
    if sdp:
        cv = a.cv
        best = int(np.flatnonzero(cv.lambdas == cv.best_lambda)[0])
        target = aligned(estimand(n, trials_count, seed, cv.best_lambda, factor, trials.stimuli), a.coordinate)
        run.update({"lambda_one_se": cv.one_se_lambda, "lambda_grid": [float(cv.lambdas[0]), float(cv.lambdas[-1])],
                    "heldout_error_at_lambda": float(cv.test_error[best].mean()),"coverage": coverage(a.low, a.high, on_scale(truth, a.coordinate)),
                    "coverage_estimand": coverage(a.low, a.high, target), "estimand_factor": factor,
                    "estimand_bias": float(np.max(np.abs(target - on_scale(truth, target))) / np.ptp(target)),
                    "coverage_by_interval": {name: coverage(lo, hi, on_scale(truth, a.coordinate)) for name, (lo, hi)
                                             in interval_variants(a.boot.samples, a.coordinate).items()}})
    return run


def table(runs: list[dict], sdp: bool) -> list[str]:
    head = ["seed", "SDP Spearman", "SDP Pearson", "CV lambda (1-SE)" if sdp else "lambda (start only)"]
    head += ["held-out error"] if sdp else []
    head += ["noise floor", "1st dim share", "eig1/eig2"]
    head += ["SDP coverage of truth", "SDP coverage of estimand", "SDP estimand bias"] if sdp else []
    head += ["Thurstone Spearman", "Thurstone coverage of truth", "Thurstone slope (noise SDs)", "Thurstone Pearson",
             "seconds"]
    lines = ["| " + " | ".join(head) + " |", "| --- " * len(head) + "|"]
    for r in runs:
        cells = [f"{r['seed']}", f"{r['spearman']:.3f}", f"{r['pearson']:.3f}"]
        cells += [f"{r['lambda']:.3g} ({r['lambda_one_se']:.3g})", f"{r['heldout_error_at_lambda']:.3f}"] if sdp else [
            f"{r['lambda']:.3g}"]
        cells += [f"{r['noise_floor']:.3f}", f"{r['first_dimension_share']:.2f}",
                  f"{r['first_to_second'] or float('inf'):.1f}"]
        if sdp:
            cells += [f"{r['coverage']:.2f}", f"{r['coverage_estimand']:.2f}", f"{r['estimand_bias']:.3f}"]
        cells += [f"{r['thurstone_spearman']:.3f}", f"{r['thurstone_coverage']:.2f}", f"{r['thurstone_slope_noise_units']:.3f}",
                  f"{r['thurstone_pearson']:.3f}", f"{r['seconds'] + r['thurstone_seconds']:.0f}"]
        lines.append("| " + " | ".join(cells) + " |")
    mean = {k: np.mean([r[k] for r in runs]) for k in (["coverage", "coverage_estimand"] if sdp else [])
            + ["thurstone_coverage"]}
    lines.append("\nMean over seeds: " + ", ".join(f"{k} {v:.3f}" for k, v in mean.items())
                 + f" ({len(runs)} x {runs[0]['stimuli']} stimuli)")
    if sdp:
        lines.append("\nSDP coverage of the truth by kind of interval (mean over seeds): " + ", ".join(
            f"{name} {np.mean([r['coverage_by_interval'][name] for r in runs]):.3f}"
            for name in runs[0]["coverage_by_interval"]))
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--stimuli", type=int, default=30)
    parser.add_argument("--trials", type=int, default=2000)
    parser.add_argument("--resamples", type=int, default=500)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--estimand-factor", type=int, default=20)
    parser.add_argument("--scale", choices=("both", "thurstone"), default="both",
                        help="both: SDP and Thurstone intervals; thurstone: skip the SDP's bootstrap and estimand")
    parser.add_argument("--out", default="perception_recovery", help="results/<OUT>.json and .md")
    args = parser.parse_args()
    sdp = args.scale == "both"
    runs = [one(s, args.stimuli, args.trials, args.resamples, args.workers, args.estimand_factor, sdp)
            for s in args.seeds]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{args.out}.json").write_text(json.dumps(runs, indent=2) + "\n")
    command = (f"PYTHONPATH=.:benchmarks OMP_NUM_THREADS=1 python benchmarks/perception_recovery.py --seeds "
               f"{' '.join(map(str, args.seeds))} --workers {args.workers} --scale {args.scale} --out {args.out}")
    lines = [f"# Recovery: {args.stimuli} stimuli, {args.trials} simulated triplets, {args.resamples} resamples\n",
             f"Regenerate: `{command}`\n", *table(runs, sdp)]
    md = "\n".join(lines) + "\n"
    (RESULTS / f"{args.out}.md").write_text(md)
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
