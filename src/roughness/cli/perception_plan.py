"""`roughness perception plan --stimuli TABLE --trials N,N --out DIR`: how many trials bring R within a tolerance."""
from __future__ import annotations

import argparse
from pathlib import Path

from roughness.core.limits import MAX_TRIALS

from .common import add_overwrite, add_quiet, count, finish, log, positive
from .perception_common import (
    PROBABILITY,
    add_observer_args,
    add_truth_args,
    made,
    number_list,
    observer_run,
)

count_list = number_list(count(MAX_TRIALS), "numbers of trials")  # 500,1000,2000
MAX_EXPERIMENTS = 1000  # --experiments: each a simulated experiment and fit; 1,000 pin a share to about 1.5%

def add_parser(sub) -> None:
    pla = sub.add_parser("plan", help="how many trials for R within a tolerance? simulated experiments at several "
                                     "numbers of trials")
    add_truth_args(pla)
    pla.add_argument("--trials", required=True, type=count_list, metavar="N,N",
                     help="numbers of trials to try, e.g. 500,1000,2000,4000")
    pla.add_argument("--experiments", type=count(MAX_EXPERIMENTS, low=2), default=20,
                     help="simulated experiments per number of trials (default 20)")
    pla.add_argument("--tolerance", type=positive(2.0), default=0.05,
                     help="|R - R_inf| wanted (default 0.05; R_inf = R with unlimited trials)")
    pla.add_argument("--share", type=PROBABILITY, default=0.9,
                     help="share of experiments that must reach the tolerance (default 0.9)")
    add_observer_args(pla, "the simulated experiments", "plan.csv, plan.json")
    add_overwrite(pla)
    add_quiet(pla)
    finish(pla, run_plan)


def run_plan(args: argparse.Namespace) -> int:
    import numpy as np

    from roughness.core.files import write_csv
    from roughness.core.limits import MAX_TRIALS, check_size
    from roughness.perception.analysis import write_json
    from roughness.perception.embed import require_cvxpy
    from roughness.perception.parallel import stderr_progress
    from roughness.perception.plan import plan_trials
    from roughness.perception.values import stimulus_values

    check_size("trials of one simulated experiment", max(args.trials), MAX_TRIALS, "trials")
    require_cvxpy()
    run = observer_run(args, ("plan.csv", "plan.json"))
    stimuli, ids, observer, v, files = run.stimuli, run.ids, run.observer, run.truth, run.files
    if v is None:
        cache = Path(args.cache) if args.cache else Path(args.out) / "fem-cache"
        log(args, f"true V of {len(ids)} stimuli with {args.engine} ...")
        values = stimulus_values(ids, [s.heightmap() for s in stimuli], args.engine, cache, lambda m: log(args, m))
        v = np.array([x.roughness for x in values])
    plan = plan_trials(ids, v, args.trials, args.experiments, observer, args.tolerance, args.share, args.seed,
                       stderr_progress("simulated experiments", args.quiet))
    summary = {"stimuli_table": str(args.stimuli), "truth": args.truth or args.engine, "sigma": observer.sigma,
               "lapse": observer.lapse, "seed": args.seed, **plan.summary()}
    made(files)
    write_csv(files["plan.csv"], ("trials", "experiments", "pearson_mean", "pearson_5", "pearson_95",
                                  "within_tolerance", "spearman_truth_mean"),
              ([s["trials"], s["experiments"], *(f"{s[k]:.4f}" for k in ("pearson_mean", "pearson_5", "pearson_95",
                                                                         "within_tolerance", "spearman_truth_mean"))]
               for s in summary["steps"]))
    write_json(files["plan.json"], summary)
    needed = plan.needed
    print(f"R with unlimited trials {plan.limit:.3f}; " + (
        f"{needed} trials bring R within {args.tolerance:g} of it in {args.share:.0%} of simulated experiments"
        if needed else f"none of {','.join(map(str, args.trials))} trials brings R within {args.tolerance:g} of it "
                       f"in {args.share:.0%} of simulated experiments: try more"))
    log(args, f"wrote {files['plan.csv']}, {files['plan.json']}")
    return 0
