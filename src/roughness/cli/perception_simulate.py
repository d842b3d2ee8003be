"""`roughness perception simulate --stimuli TABLE --trials N --out DIR`: a balanced trial list answered by a
simulated observer."""
from __future__ import annotations

import argparse
from pathlib import Path

from roughness.core.limits import MAX_TRIALS

from .common import add_overwrite, add_quiet, count, finish, json_text, log
from .perception_common import (
    add_observer_args,
    add_truth_args,
    check_trials,
    made,
    observer_run,
)


def add_parser(sub) -> None:
    sim = sub.add_parser("simulate", help="answer a balanced trial list with a simulated observer (Thurstone, "
                                         "Weber noise on ln V / 2), for testing and planning")
    add_truth_args(sim)
    sim.add_argument("--trials", required=True, type=count(MAX_TRIALS), help="trials per subject")
    sim.add_argument("--subjects", type=count(MAX_TRIALS), default=1, help="number of simulated subjects (default 1)")
    add_observer_args(sim, "the observer's noise", "trials.csv, truth.csv")
    add_overwrite(sim)
    add_quiet(sim)
    finish(sim, run_simulate)


def run_simulate(args: argparse.Namespace) -> int:
    import numpy as np

    from roughness.perception.design import FIELDNAMES, balanced_design
    from roughness.perception.observer import noiseless_answer, perceptual_coordinate
    from roughness.perception.trials import write_trials
    from roughness.perception.values import stimulus_values

    check_trials(args)
    run = observer_run(args, ("trials.csv", "truth.csv"))
    stimuli, ids, observer, v, files = run.stimuli, run.ids, run.observer, run.truth, run.files
    if v is not None:
        source = f"--truth {args.truth}"
    else:
        cache = Path(args.cache) if args.cache else Path(args.out) / "fem-cache"
        log(args, f"true V of {len(ids)} stimuli with {args.engine} ...")
        values = stimulus_values(ids, [s.heightmap() for s in stimuli], args.engine, cache, lambda m: log(args, m))
        v = np.array([x.roughness for x in values])
        source = args.engine
    truth = perceptual_coordinate(v, ids)
    subjects = [f"s{i}" for i in range(1, args.subjects + 1)]
    design = balanced_design(ids, args.trials, subjects, args.seed)
    index = {s: i for i, s in enumerate(ids)}
    triplets = np.array([[index[t.reference], index[t.left], index[t.right]] for t in design])
    left = observer.answer(truth, triplets, np.random.default_rng([args.seed, 1]))
    rows = [{**t.row(), "answer": "left" if a else "right"} for t, a in zip(design, left)]
    write_trials(made(files)["trials.csv"], rows, FIELDNAMES)
    _write_truth(files["truth.csv"], ids, v, truth)
    disagree = float(np.mean(left != noiseless_answer(truth, triplets)))
    roughest = ids[int(np.argmax(v))]
    print(json_text({"trials": len(rows), "stimuli": len(ids), "truth": source, "sigma": observer.sigma,
                      "lapse": observer.lapse, "noise_floor": disagree, "roughest": roughest}))
    log(args, f"the observer's answers disagree with the noise-free ones in {disagree:.1%} of trials (the best "
              f"achievable triplet error); embed with --roughest {roughest}")
    return 0


def _write_truth(path: Path, ids, v, coordinate) -> None:
    from roughness.core.files import write_csv

    write_csv(path, ["stimulus", "roughness", "coordinate"],
              ([s, f"{a:.6g}", f"{p:.6g}"] for s, a, p in zip(ids, v, coordinate)))
