"""Speed of the perception pipeline at the paper's size: 46 stimuli, 3,000 triplets.

Measures (wall clock, this machine): compiling the SDP, one embedding solve with SCS (the solver
used) and with Clarabel (the alternative), 10-fold cross-validation over the default lambda grid,
and 500 bootstrap resamples, with ``--workers`` processes (one BLAS thread each).

    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/perception_speed.py --workers 2

Writes benchmarks/results/perception_speed.json and .md. The answers come from the simulated
observer (default Weber noise) on 46 stimuli spread over the standard scale's range of lambda.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from roughness.perception.analysis import analyse
from roughness.perception.design import balanced_design
from roughness.perception.embed import SOLVER, TripletSDP
from roughness.perception.observer import Observer
from roughness.perception.parallel import stderr_progress
from roughness.perception.trials import parse_trials

RESULTS = Path(__file__).resolve().parent / "results"
HEADER = "subject,reference,left,right,answer"


def simulated(n: int, trials: int, seed: int, trial_seed: int | None = None):
    """Trials of the default observer on n stimuli with ln(lambda) uniform over the standard scale.

    ``seed`` draws the truth (and, unless ``trial_seed`` is given, the design and the answers).
    """
    rng = np.random.default_rng(seed)
    truth = np.log(np.sort(rng.uniform(0.625, 1.625, n)))
    if trial_seed is not None:
        rng = np.random.default_rng(trial_seed)
    ids = [f"s{i:02d}" for i in range(n)]
    design = balanced_design(ids, trials, seed=seed if trial_seed is None else trial_seed)
    index = {s: i for i, s in enumerate(ids)}
    triplets = np.array([[index[t.reference], index[t.left], index[t.right]] for t in design])
    left = Observer().answer(truth, triplets, rng)
    text = "\n".join([HEADER] + [f"s1,{t.reference},{t.left},{t.right},{'left' if a else 'right'}"
                                 for t, a in zip(design, left)])
    return parse_trials(text, repeats="keep"), truth


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--stimuli", type=int, default=46)
    parser.add_argument("--trials", type=int, default=3000)
    parser.add_argument("--resamples", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    trials, _ = simulated(args.stimuli, args.trials, args.seed)
    unique, inverse = trials.unique()
    weights = np.bincount(inverse, minlength=len(unique)).astype(float)

    start = time.perf_counter()
    sdp = TripletSDP(len(trials.stimuli), unique)
    compile_s = time.perf_counter() - start
    analysis = analyse(trials, resamples=args.resamples, workers=args.workers, seed=args.seed,
                       progress=lambda what: stderr_progress(what))
    lam = analysis.fit.lam
    scs = sdp.solve(weights, lam)
    sdp.weights.value, sdp.lam.value = weights, lam
    start = time.perf_counter()
    sdp.problem.solve(solver="CLARABEL", warm_start=False)
    clarabel_s = time.perf_counter() - start
    clarabel_status = str(sdp.problem.status)
    clarabel_objective = float(sdp.problem.value)
    result = {
        "stimuli": len(trials.stimuli), "trials": len(trials), "distinct_triplets": len(unique),
        "workers": args.workers, "resamples": args.resamples, "lambda": lam,
        "compile_seconds": compile_s,
        "embedding_seconds": {"compile_plus_solve": compile_s + scs.seconds, "scs_solve": scs.seconds,
                              "scs_iterations": scs.iterations, "scs_objective": scs.objective,
                              "clarabel_solve": clarabel_s, "clarabel_status": clarabel_status,
                              "clarabel_objective": clarabel_objective, "solver_used": SOLVER},
        "pipeline_seconds": analysis.seconds,
        "load_average_at_end": os.getloadavg(), "cpu_count": os.cpu_count(), "python": sys.version.split()[0],
        "machine": platform.machine(),
        "note": "measured on a 2-core machine shared with other jobs (load average above): wall times are upper "
                "bounds of what an idle machine gives",
    }
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "perception_speed.json").write_text(json.dumps(result, indent=2) + "\n")
    e, p = result["embedding_seconds"], result["pipeline_seconds"]
    md = (f"# Perception pipeline speed ({result['stimuli']} stimuli, {result['trials']} triplets)\n\n"
          f"Regenerate: `PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/perception_speed.py --workers "
          f"{args.workers}`\n\n"
          "| stage | seconds |\n| --- | --- |\n"
          f"| compile the SDP (cvxpy) | {compile_s:.1f} |\n"
          f"| one embedding, SCS ({e['scs_iterations']} iterations) | {e['scs_solve']:.1f} |\n"
          f"| one embedding, Clarabel ({clarabel_status}) | {clarabel_s:.1f} |\n"
          f"| embedding from trials (compile + SCS solve) | {e['compile_plus_solve']:.1f} |\n"
          f"| 10-fold cross-validation, 13 lambdas ({args.workers} workers) | {p.get('cross_validation', 0):.0f} |\n"
          f"| {args.resamples} bootstrap resamples ({args.workers} workers) | {p.get('bootstrap', 0):.0f} |\n\n"
          f"Objective: SCS {e['scs_objective']:.6g}, Clarabel {clarabel_objective:.6g} (lambda {lam:.4g}). "
          f"Load average at the end {result['load_average_at_end'][0]:.1f} on {os.cpu_count()} cores: "
          "the machine was shared, so these are upper bounds.\n")
    (RESULTS / "perception_speed.md").write_text(md)
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
