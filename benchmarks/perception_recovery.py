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
  scale, so this is the coverage a 5-95% interval should have (about 90%).

    PYTHONPATH=.:benchmarks OMP_NUM_THREADS=1 python benchmarks/perception_recovery.py --seeds 0 1 2 --workers 2
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from perception_speed import simulated  # benchmarks/ is on sys.path when run as a script
from scipy.stats import spearmanr

from roughness.perception.analysis import analyse
from roughness.perception.embed import TripletSDP, aligned
from roughness.perception.observer import noiseless_answer
from roughness.perception.parallel import stderr_progress

RESULTS = Path(__file__).resolve().parent / "results"


def estimand(n: int, trials_count: int, seed: int, lam: float, factor: int, ids: tuple[str, ...]) -> np.ndarray:
    """1-D embedding of ``factor`` times the trials (same truth, other trials) at ``factor`` * lam, in ``ids`` order."""
    big, _ = simulated(n, factor * trials_count, seed, trial_seed=seed + 1000)
    unique, inverse = big.unique()
    result = TripletSDP(len(big.stimuli), unique).solve(np.bincount(inverse, minlength=len(unique)), factor * lam)
    order = [big.stimuli.index(s) for s in ids]
    return result.coordinates(1)[order, 0]


def one(seed: int, n: int, trials_count: int, resamples: int, workers: int, factor: int) -> dict:
    trials, truth_sorted = simulated(n, trials_count, seed)
    truth = truth_sorted[[int(s[1:]) for s in trials.stimuli]]
    roughest = trials.stimuli[int(np.argmax(truth))]
    start = time.perf_counter()
    a = analyse(trials, resamples=resamples, workers=workers, seed=seed, roughest=roughest,
                progress=lambda what: stderr_progress(f"seed {seed} {what}"))
    seconds = time.perf_counter() - start
    # the rows' triplets are (reference, closer, farther): a noise-free observer calls "closer" closer
    floor = float(np.mean(~noiseless_answer(truth, trials.triplets)))
    cv = a.cv
    best = int(np.flatnonzero(cv.lambdas == cv.best_lambda)[0])
    spectrum = a.fit.eigenvalues
    slope, intercept = np.polyfit(truth, a.coordinate, 1)
    mapped = slope * truth + intercept
    covered = (a.low <= mapped) & (mapped <= a.high)
    target = aligned(estimand(n, trials_count, seed, cv.best_lambda, factor, trials.stimuli), a.coordinate)
    covered_estimand = (a.low <= target) & (target <= a.high)
    return {"seed": seed, "stimuli": n, "trials": len(trials),
            "spearman": float(spearmanr(a.coordinate, truth)[0]),
            "pearson": float(np.corrcoef(a.coordinate, truth)[0, 1]),
            "lambda": cv.best_lambda, "lambda_one_se": cv.one_se_lambda,
            "lambda_grid": [float(cv.lambdas[0]), float(cv.lambdas[-1])],
            "heldout_error_at_lambda": float(cv.test_error[best].mean()), "noise_floor": floor,
            "first_dimension_share": float(spectrum[0] / spectrum.sum()),
            "first_to_second": float(spectrum[0] / spectrum[1]) if spectrum[1] > 0 else None,
            "coverage": float(covered.mean()), "coverage_estimand": float(covered_estimand.mean()),
            "estimand_factor": factor, "seconds": seconds, "stage_seconds": a.seconds}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--stimuli", type=int, default=30)
    parser.add_argument("--trials", type=int, default=2000)
    parser.add_argument("--resamples", type=int, default=500)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--estimand-factor", type=int, default=20)
    args = parser.parse_args()
    runs = [one(s, args.stimuli, args.trials, args.resamples, args.workers, args.estimand_factor)
            for s in args.seeds]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "perception_recovery.json").write_text(json.dumps(runs, indent=2) + "\n")
    lines = [f"# Recovery: {args.stimuli} stimuli, {args.trials} simulated triplets, {args.resamples} resamples\n",
             ("Regenerate: `PYTHONPATH=.:benchmarks OMP_NUM_THREADS=1 python benchmarks/perception_recovery.py "
              f"--seeds {' '.join(map(str, args.seeds))} --workers {args.workers}`\n"),
             ("| seed | Spearman | Pearson | CV lambda (1-SE) | held-out error | noise floor | 1st dim share | "
              "eig1/eig2 | coverage of truth | coverage of estimand | seconds |"), "| --- " * 11 + "|"]
    for r in runs:
        lines.append(f"| {r['seed']} | {r['spearman']:.3f} | {r['pearson']:.3f} | {r['lambda']:.3g} "
                     f"({r['lambda_one_se']:.3g}) | {r['heldout_error_at_lambda']:.3f} | {r['noise_floor']:.3f} | "
                     f"{r['first_dimension_share']:.2f} | {r['first_to_second'] or float('inf'):.1f} | "
                     f"{r['coverage']:.2f} | {r['coverage_estimand']:.2f} | {r['seconds']:.0f} |")
    md = "\n".join(lines) + "\n"
    (RESULTS / "perception_recovery.md").write_text(md)
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
