"""`roughness perception embed TRIALS --out DIR`: a 1-D perceptual scale from triplet answers."""
from __future__ import annotations

import argparse
import os
import sys

from roughness.core.limits import MAX_TRIALS

from .common import PARALLEL, SEED, Number, add_overwrite, add_quiet, count, finish, log
from .perception_common import made, output_files

# --lambda: above lambda_max of any experiment within MAX_TRIALS trials (the largest eigenvalue of their summed
# margins, a few per trial) the embedding is 0
REGULARISER = Number(float, low=0, high=10.0 * MAX_TRIALS)
MAX_RESAMPLES = 10_000  # --resamples: enough to pin the 5-95% interval's ends to a percent (default 500)


def add_parser(sub) -> None:
    emb = sub.add_parser("embed", help="1-D perceptual scale from triplet answers (Wills et al. 2009 SDP), with "
                                      "cross-validated lambda, spectrum and bootstrap intervals")
    emb.add_argument("trials", metavar="TRIALS", help="trials CSV: subject,reference,left,right,answer (answer = "
                                                      "left|right, the one closer in roughness to the reference)")
    emb.add_argument("--out", required=True, metavar="DIR", help="output folder (created if missing)")
    emb.add_argument("--stimuli", metavar="TABLE", help="stimuli table: every id in TRIALS must be listed in it")
    emb.add_argument("--roughest", metavar="ID", help="a stimulus known to be rough: orients the scale so that it "
                                                      "is positive (default: arbitrary sign, said in the summary)")
    emb.add_argument("--lambda", dest="lam", type=REGULARISER, metavar="L",
                     help="fixed regulariser (skips cross-validation)")
    emb.add_argument("--folds", type=count(MAX_TRIALS, low=2), default=10, help="cross-validation folds (default 10)")
    emb.add_argument("--resamples", type=count(MAX_RESAMPLES, low=0), default=500,
                     help="bootstrap resamples for the 5-95%% intervals (default 500; 0: none)")
    emb.add_argument("--workers", type=PARALLEL, default=min(os.cpu_count() or 1, PARALLEL.high),
                     help="processes for cross-validation and bootstrap (default: all cores)")
    emb.add_argument("--repeats", choices=("keep", "error"), default="keep",
                     help="one subject's different answers to a repeated trial: keep both (default: normal in "
                          "psychophysics) or error (refuse them: data that should hold no repeats)")
    emb.add_argument("--scale", choices=("sdp", "thurstone"), default="sdp",
                     help="the 1-D coordinate: sdp (the SDP's principal coordinate, the paper's; default) or thurstone "
                          "(maximum likelihood under the Thurstone observer, started from the SDP: metric, in noise "
                          "SDs, its bootstrap intervals contain a simulated truth about 90%% of the time)")
    emb.add_argument("--lapse", type=Number(float, low=0, high=0.5), default=0.01,
                     help="lapse rate (random answers) of the Thurstone model (--scale thurstone; default 0.01)")
    emb.add_argument("--seed", type=SEED, default=0, help="seed of the folds and resamples")
    add_overwrite(emb)
    add_quiet(emb)
    finish(emb, run_embed)


def run_embed(args: argparse.Namespace) -> int:
    from roughness.perception.analysis import analyse, write_embedding_csv, write_json
    from roughness.perception.embed import require_cvxpy
    from roughness.perception.parallel import stderr_progress
    from roughness.perception.plots import plot_cross_validation, plot_embedding
    from roughness.perception.stimuli import read_stimuli
    from roughness.perception.trials import disconnection_warning, read_trials

    require_cvxpy()
    ids = [s.stimulus for s in read_stimuli(args.stimuli)] if args.stimuli else None
    trials = read_trials(args.trials, ids, args.repeats)
    disconnected = disconnection_warning(trials.groups())
    if disconnected:
        print(f"roughness: warning: {args.trials}: {disconnected}", file=sys.stderr, flush=True)
    files = output_files(args.out, ("embedding.csv", "embedding.json", "embedding.png", "cross_validation.png"),
                         args.overwrite, {"TRIALS": args.trials, "--stimuli": args.stimuli})
    log(args, f"{args.trials}: {len(trials)} trials, {len(trials.stimuli)} stimuli, "
              f"{len(set(trials.subjects))} subject(s); {args.workers} worker(s)")
    analysis = analyse(trials, lam=args.lam, folds=args.folds, resamples=args.resamples, seed=args.seed,
                       workers=args.workers, roughest=args.roughest,
                       progress=lambda what: stderr_progress(what, args.quiet), scale=args.scale, lapse=args.lapse)
    summary = {"trials_file": str(args.trials), **analysis.summary(trials), "seed": args.seed}
    made(files)
    write_embedding_csv(files["embedding.csv"], analysis)
    write_json(files["embedding.json"], summary)
    plot_embedding(analysis, files["embedding.png"])
    plot_cross_validation(analysis, files["cross_validation.png"])
    share = summary["first_dimension_share"]
    print(f"lambda {analysis.fit.lam:.4g} ({summary['lambda_source']}); first dimension "
          f"{share:.1%} of the spectrum; training triplet error {summary['training_error']:.3f} "
          f"(1-D: {summary['training_error_1d']:.3f})" if share is not None else
          f"lambda {analysis.fit.lam:.4g}: the embedding collapsed to a point (lambda too large)")
    log(args, f"wrote {', '.join(str(p) for p in files.values())}")
    return 0
