"""`roughness perception embed|fit|design|simulate`: triplet experiments and the fit of V to them."""
from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

from .common import COUNT, PARALLEL, POSITIVE, SEED, Number, add_overwrite, add_quiet, finish, json_text, log

NON_NEGATIVE = Number(float, low=0)
PROBABILITY = Number(float, low=0, high=1)


def number_list(kind, what: str):
    """An argparse type for ``a,b,c``: each parsed by ``kind`` (a common.Number), sorted, duplicates dropped."""
    def parse(text: str) -> list:
        try:
            return sorted({kind(v) for v in text.split(",")})
        except argparse.ArgumentTypeError:
            raise argparse.ArgumentTypeError(f"expected comma-separated {what}, got {text!r}") from None
    return parse


positive_list = number_list(POSITIVE, "positive numbers")  # 0.4,0.8,1.2 (mm or N)
count_list = number_list(COUNT, "whole numbers >= 1")  # 500,1000,2000


def id_list(text: str) -> list[str]:
    return [v.strip() for v in text.split(",") if v.strip()]


def add_parser(sub) -> None:
    per = sub.add_parser("perception", help="triplet experiments: design trials, simulate an observer, embed the "
                                            "answers, fit V to the embedding")
    ps = per.add_subparsers(dest="perception_command", required=True)

    emb = ps.add_parser("embed", help="1-D perceptual scale from triplet answers (Wills et al. 2009 SDP), with "
                                      "cross-validated lambda, spectrum and bootstrap intervals")
    emb.add_argument("trials", metavar="TRIALS", help="trials CSV: subject,reference,left,right,answer (answer = "
                                                      "left|right, the one closer in roughness to the reference)")
    emb.add_argument("--out", required=True, metavar="DIR", help="output folder (created if missing)")
    emb.add_argument("--stimuli", metavar="TABLE", help="stimuli table: every id in TRIALS must be listed in it")
    emb.add_argument("--roughest", metavar="ID", help="a stimulus known to be rough: orients the scale so that it "
                                                      "is positive (default: arbitrary sign, said in the summary)")
    emb.add_argument("--lambda", dest="lam", type=NON_NEGATIVE, metavar="L",
                     help="fixed regulariser (skips cross-validation)")
    emb.add_argument("--folds", type=Number(int, low=2), default=10, help="cross-validation folds (default 10)")
    emb.add_argument("--resamples", type=Number(int, low=0), default=500,
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

    fit = ps.add_parser("fit", help="V of the stimuli against the embedding: Pearson/Spearman, classical measures, "
                                    "re-fit over the pair sampling (d, r) and force")
    fit.add_argument("embedding", metavar="EMBEDDING", help="embedding.csv from `roughness perception embed`")
    fit.add_argument("--stimuli", required=True, metavar="TABLE", help="stimuli table (ids -> heightmaps)")
    fit.add_argument("--out", required=True, metavar="DIR", help="output folder (created if missing)")
    fit.add_argument("--engine", choices=("fem:coarse", "fem:default", "fem:fine", "surrogate", "auto"),
                     default="fem:default", help="engine for V (default fem:default; the (d, r) and force re-fits "
                                                 "need a FEM engine)")
    fit.add_argument("--cache", metavar="DIR", help="FEM result cache (default: DIR/fem-cache); keyed by heights and "
                                                    "configuration, shareable between runs")
    fit.add_argument("--exclude", type=id_list, default=[], metavar="ID,ID",
                     help="stimuli left out of the 'included' fit (e.g. the least homogeneous ones)")
    fit.add_argument("--exclude-least-homogeneous", type=Number(int, low=0), default=0, metavar="N",
                     help="also leave out the N least homogeneous stimuli, as the paper did (N = 5): largest spread "
                          "in JNDs from the stimuli table's 'homogeneity' column, else computed with the "
                          "surrogate (roughness homogeneity); default 0")
    fit.add_argument("--distances", type=positive_list, default=[0.4, 0.6, 0.8, 1.0, 1.2, 1.6], metavar="MM,MM",
                     help="pair distances d of the re-fit (mm)")
    fit.add_argument("--radii", type=positive_list, default=[0.2, 0.4, 0.6, 0.8, 1.0, 1.2], metavar="MM,MM",
                     help="disk radii r of the re-fit (mm)")
    fit.add_argument("--forces", type=positive_list, default=[], metavar="N,N",
                     help="forces (N) of a re-fit over force (new FEM runs, cached; default: none)")
    add_overwrite(fit)
    add_quiet(fit)
    finish(fit, run_fit, force_n="--forces")

    des = ps.add_parser("design", help="a balanced, randomised triplet trial list for an experiment")
    des.add_argument("--stimuli", required=True, metavar="TABLE", help="stimuli table (its ids are used)")
    des.add_argument("--trials", required=True, type=COUNT, help="trials per subject")
    des.add_argument("--subjects", type=COUNT, default=1, help="number of subjects s1..sN (default 1)")
    des.add_argument("--seed", type=SEED, default=0, help="seed of the trial order (default: %(default)s)")
    des.add_argument("--out", required=True, metavar="CSV", help="trial list (answer column left blank)")
    des.add_argument("--plates", metavar="DIR", help="also write every stimulus as a printable plate DIR/<id>.stl "
                                                     "(default: none)")
    des.add_argument("--plate-mm", type=POSITIVE, default=25.0, help="side of the plates in mm (default: %(default)s, "
                                                                     "as in the paper)")
    des.add_argument("--base-mm", type=POSITIVE, default=2.0, help="plate thickness below the texture in mm "
                                                                   "(default: %(default)s)")
    add_overwrite(des)
    finish(des, run_design)

    sim = ps.add_parser("simulate", help="answer a balanced trial list with a simulated observer (Thurstone, "
                                         "Weber noise on ln V / 2), for testing and planning")
    _add_truth_args(sim)
    sim.add_argument("--trials", required=True, type=COUNT, help="trials per subject")
    sim.add_argument("--subjects", type=COUNT, default=1, help="number of simulated subjects (default 1)")
    sim.add_argument("--sigma", type=NON_NEGATIVE, default=None,
                     help="noise SD on the coordinate ln(V)/2 (default 0.18, from the Weber fraction 0.19)")
    sim.add_argument("--lapse", type=PROBABILITY, default=0.0, help="probability of a random answer (default 0)")
    sim.add_argument("--seed", type=SEED, default=0, help="seed of the observer's noise (default: %(default)s)")
    sim.add_argument("--out", required=True, metavar="DIR", help="output folder: trials.csv, truth.csv")
    add_overwrite(sim)
    add_quiet(sim)
    finish(sim, run_simulate)

    pla = ps.add_parser("plan", help="how many trials for R within a tolerance? simulated experiments at several "
                                     "numbers of trials")
    _add_truth_args(pla)
    pla.add_argument("--trials", required=True, type=count_list, metavar="N,N",
                     help="numbers of trials to try, e.g. 500,1000,2000,4000")
    pla.add_argument("--experiments", type=Number(int, low=2), default=20,
                     help="simulated experiments per number of trials (default 20)")
    pla.add_argument("--tolerance", type=POSITIVE, default=0.05,
                     help="|R - R_inf| wanted (default 0.05; R_inf = R with unlimited trials)")
    pla.add_argument("--share", type=PROBABILITY, default=0.9,
                     help="share of experiments that must reach the tolerance (default 0.9)")
    pla.add_argument("--sigma", type=NON_NEGATIVE, default=None,
                     help="the observer's noise SD on ln(V)/2 (default 0.18, from the Weber fraction 0.19)")
    pla.add_argument("--lapse", type=PROBABILITY, default=0.0, help="the observer's lapse rate (default 0)")
    pla.add_argument("--seed", type=SEED, default=0, help="seed of the simulated experiments (default: %(default)s)")
    pla.add_argument("--out", required=True, metavar="DIR", help="output folder: plan.csv, plan.json")
    add_overwrite(pla)
    add_quiet(pla)
    finish(pla, run_plan)



def _add_truth_args(p: argparse.ArgumentParser) -> None:
    """The stimuli and where their true V comes from (simulate and plan)."""
    p.add_argument("--stimuli", required=True, metavar="TABLE", help="stimuli table (ids -> heightmaps)")
    p.add_argument("--truth", metavar="CSV", help="known V per stimulus (columns stimulus,roughness) instead of "
                                                  "computing it with --engine")
    p.add_argument("--engine", choices=("fem:coarse", "fem:default", "fem:fine", "surrogate", "auto"),
                   default="surrogate", help="engine for the true V (default surrogate)")
    p.add_argument("--cache", metavar="DIR", help="FEM result cache (default: DIR/fem-cache)")

def _outputs(folder: str, names: tuple[str, ...], overwrite: bool, inputs: dict) -> dict[str, Path]:
    """The output files in ``folder``, checked before any computation (the folder is made by ``_made``);
    none of them may be one of ``inputs`` (label -> path)."""
    from roughness.core.files import check_distinct, check_output, check_output_folder

    out = Path(folder)
    check_distinct({"--out": [out, *(out / name for name in names)]}, inputs)
    if not out.is_dir():  # a new folder (its parent must be writable), or a file in the way: refused
        check_output_folder(out, name="out")
        return {name: out / name for name in names}
    return {name: check_output(out / name, overwrite, "out") for name in names}


def _made(files: dict[str, Path]) -> dict[str, Path]:
    """``files`` after creating their folder (once the inputs have been read and the work is done)."""
    next(iter(files.values())).parent.mkdir(exist_ok=True)
    return files


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
    files = _outputs(args.out, ("embedding.csv", "embedding.json", "embedding.png", "cross_validation.png"),
                     args.overwrite, {"TRIALS": args.trials, "--stimuli": args.stimuli})
    log(args, f"{args.trials}: {len(trials)} trials, {len(trials.stimuli)} stimuli, "
              f"{len(set(trials.subjects))} subject(s); {args.workers} worker(s)")
    analysis = analyse(trials, lam=args.lam, folds=args.folds, resamples=args.resamples, seed=args.seed,
                       workers=args.workers, roughest=args.roughest,
                       progress=lambda what: stderr_progress(what, args.quiet), scale=args.scale, lapse=args.lapse)
    summary = {"trials_file": str(args.trials), **analysis.summary(trials), "seed": args.seed}
    _made(files)
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


def _table_subset(table, ids):
    from roughness.core.errors import InputError
    from roughness.perception.trials import listed

    by_id = {s.stimulus: s for s in table}
    missing = [i for i in ids if i not in by_id]
    if missing:
        raise InputError(listed("stimuli not in the stimuli table", missing), parameter="stimuli")
    return [by_id[i] for i in ids]


def run_fit(args: argparse.Namespace) -> int:
    import numpy as np

    from roughness.core.errors import InputError
    from roughness.perception.analysis import read_embedding_csv, write_json
    from roughness.perception.fit import Fit, classical_measures, homogeneity_spreads, least_homogeneous, sampling_fit
    from roughness.perception.plots import plot_fit, plot_sampling
    from roughness.perception.stimuli import read_stimuli
    from roughness.perception.trials import listed
    from roughness.perception.values import stimulus_values

    embedding = read_embedding_csv(args.embedding)
    stimuli = _table_subset(read_stimuli(args.stimuli), embedding.stimuli)
    unknown = [i for i in args.exclude if i not in embedding.stimuli]
    if unknown:
        raise InputError(listed("excluded stimuli not in the embedding", unknown), parameter="exclude")
    if args.exclude_least_homogeneous > len(stimuli) - 3:
        raise InputError(f"cannot leave out {args.exclude_least_homogeneous} of {len(stimuli)} stimuli: the fit "
                         "needs at least 3", parameter="exclude_least_homogeneous")
    fem = args.engine.startswith("fem:")
    if args.forces and not fem:
        raise InputError("--forces re-runs the FEM: use a FEM --engine", parameter="forces")
    names = ("fit.csv", "fit.json", "fit.png") + (("sampling.png",) if fem else ())
    files = _outputs(args.out, names, args.overwrite, {"EMBEDDING": args.embedding, "--stimuli": args.stimuli})
    cache = Path(args.cache) if args.cache else Path(args.out) / "fem-cache"
    heightmaps = [s.heightmap() for s in stimuli]
    spreads, inhomogeneous = None, []
    if args.exclude_least_homogeneous:
        log(args, "homogeneity of the stimuli ...")
        spreads = homogeneity_spreads(stimuli, heightmaps)
        inhomogeneous = least_homogeneous(embedding.stimuli, spreads, args.exclude_least_homogeneous)
    excluded = list(dict.fromkeys([*args.exclude, *inhomogeneous]))
    if len(embedding.stimuli) - len(excluded) < 3:
        raise InputError(f"{len(excluded)} of {len(embedding.stimuli)} stimuli excluded: the fit needs at least 3",
                         parameter="exclude")
    log(args, f"V of {len(stimuli)} stimuli with {args.engine} ...")
    values = stimulus_values(embedding.stimuli, heightmaps, args.engine, cache, lambda m: log(args, m))
    included = np.array([s not in excluded for s in embedding.stimuli])
    fit = Fit(embedding.stimuli, embedding.coordinate, embedding.low, embedding.high, values, included,
              classical_measures(heightmaps))
    if fem:
        config = values[0].config
        keep = [v for v, k in zip(values, included) if k]
        fit.sampling = sampling_fit(keep, embedding.coordinate[included], args.distances, args.radii,
                                    config["window_mm"], config["pairs"], config["seed"])
        if args.forces:
            fit.forces[float(config["force_n"])] = fit.roughness  # the configuration's own force
        for force in args.forces:
            log(args, f"re-fit at {force:g} N ...")
            runs = stimulus_values(embedding.stimuli, heightmaps, args.engine, cache, lambda m: log(args, m),
                                   force_n=force)
            fit.forces[force] = np.array([v.roughness for v in runs])
    summary = {"embedding_file": str(args.embedding), "stimuli_table": str(args.stimuli), "engine": args.engine,
               "excluded": excluded, "least_homogeneous": inhomogeneous,
               "homogeneity_spread_jnd": None if spreads is None else dict(zip(embedding.stimuli, spreads.tolist())),
               "correlations": fit.correlations(),
               "sampling": fit.sampling.as_dict() if fit.sampling else None,
               "forces": fit.force_correlations() if fit.forces else None,
               "fem_configuration": values[0].config if fem else None, "fem_cache": str(cache) if fem else None}
    _made(files)
    _write_fit_csv(files["fit.csv"], fit)
    write_json(files["fit.json"], summary)
    plot_fit(fit, files["fit.png"])
    if fem:
        plot_sampling(fit, files["sampling.png"])
    c = summary["correlations"]["V"]
    line = f"V ({args.engine}) vs embedding: Pearson R {_fmt(c['all']['pearson'])}, Spearman {_fmt(c['all']['spearman'])}"
    if excluded:
        line += (f"; without {len(excluded)} excluded: R {_fmt(c['included']['pearson'])}, "
                 f"Spearman {_fmt(c['included']['spearman'])}")
    print(line)
    log(args, f"wrote {', '.join(str(p) for p in files.values())}")
    return 0


def _fmt(x) -> str:
    return "undefined" if x is None else f"{x:.3f}"


def _write_fit_csv(path: Path, fit) -> None:
    from roughness.core.files import write_csv

    measures = list(fit.measures)
    header = ["stimulus", "coordinate", "low", "high", "roughness", "roughness_stderr", "engine", "included", *measures]
    rows = ([v.stimulus, f"{fit.coordinate[i]:.6g}", _num(fit.low[i]), _num(fit.high[i]), f"{v.roughness:.6g}",
             _num(v.roughness_stderr), v.engine, int(fit.included[i]), *(f"{fit.measures[m][i]:.6g}" for m in measures)]
            for i, v in enumerate(fit.values))
    write_csv(path, header, rows)


def _num(x: float) -> str:
    import math

    return f"{x:.6g}" if math.isfinite(x) else ""


def run_design(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct, check_output, check_output_folder
    from roughness.perception.design import FIELDNAMES, balanced_design
    from roughness.perception.stimuli import read_stimuli
    from roughness.perception.trials import write_trials
    from roughness.surface.io import save_heightmap

    check_distinct({"--out": args.out, "--plates": args.plates}, {"--stimuli": args.stimuli})
    _check_trials(args)
    stimuli = read_stimuli(args.stimuli)
    ids = [s.stimulus for s in stimuli]
    out = check_output(args.out, args.overwrite, "out")
    plates = check_output_folder(args.plates, args.overwrite, "plates") if args.plates else None
    subjects = [f"s{i}" for i in range(1, args.subjects + 1)]
    trials = balanced_design(ids, args.trials, subjects, args.seed)
    if plates is not None:
        names = {s.stimulus: _file_name(s.stimulus) for s in stimuli}
        if len(set(names.values())) < len(names):
            raise InputError("stimulus ids that differ only in characters other than letters, digits, '.', '-' "
                             "and '_' would share a plate file name", parameter="plates")
        maps = {s.stimulus: s.plate_heightmap(args.plate_mm) for s in stimuli}  # every map, before writing any
        plates.mkdir(exist_ok=True)
        for stimulus, hm in maps.items():
            save_heightmap(hm, plates / f"{names[stimulus]}.stl", base_mm=args.base_mm, overwrite=args.overwrite)
    write_trials(out, (t.row() for t in trials), FIELDNAMES, args.overwrite)
    print(f"wrote {out}: {len(trials)} trials ({args.trials} per subject, {len(subjects)} subject(s)) over "
          f"{len(ids)} stimuli; fill the answer column with left or right"
          + (f"; {len(ids)} plates of {args.plate_mm:g} mm in {plates}" if plates is not None else ""))
    return 0


def _check_trials(args: argparse.Namespace) -> None:
    """--trials x --subjects within MAX_TRIALS, before the subjects' list or any FEM run is made."""
    from roughness.core.limits import MAX_TRIALS, check_size

    check_size(f"trials of all subjects together ({args.trials:,} x {args.subjects:,} subjects)",
               args.trials * args.subjects, MAX_TRIALS, "trials")


def _file_name(stimulus: str) -> str:
    """A stimulus id as a file name: characters other than letters, digits, '.', '-' and '_' become '_'."""
    return re.sub(r"[^\w.-]", "_", stimulus)


def run_simulate(args: argparse.Namespace) -> int:
    import numpy as np

    from roughness.perception.design import FIELDNAMES, balanced_design
    from roughness.perception.observer import DEFAULT_SIGMA, Observer, noiseless_answer, perceptual_coordinate
    from roughness.perception.stimuli import read_stimuli
    from roughness.perception.trials import write_trials
    from roughness.perception.values import stimulus_values

    _check_trials(args)
    stimuli = read_stimuli(args.stimuli)
    ids = [s.stimulus for s in stimuli]
    observer = Observer(DEFAULT_SIGMA if args.sigma is None else args.sigma, args.lapse)
    v = _read_truth(args.truth, ids) if args.truth else None
    files = _outputs(args.out, ("trials.csv", "truth.csv"), args.overwrite,
                     {"--stimuli": args.stimuli, "--truth": args.truth})
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
    write_trials(_made(files)["trials.csv"], rows, FIELDNAMES)
    _write_truth(files["truth.csv"], ids, v, truth)
    disagree = float(np.mean(left != noiseless_answer(truth, triplets)))
    roughest = ids[int(np.argmax(v))]
    print(json_text({"trials": len(rows), "stimuli": len(ids), "truth": source, "sigma": observer.sigma,
                      "lapse": observer.lapse, "noise_floor": disagree, "roughest": roughest}))
    log(args, f"the observer's answers disagree with the noise-free ones in {disagree:.1%} of trials (the best "
              f"achievable triplet error); embed with --roughest {roughest}")
    return 0


def run_plan(args: argparse.Namespace) -> int:
    import numpy as np

    from roughness.core.files import write_csv
    from roughness.perception.analysis import write_json
    from roughness.perception.embed import require_cvxpy
    from roughness.perception.observer import DEFAULT_SIGMA, Observer
    from roughness.perception.parallel import stderr_progress
    from roughness.perception.plan import plan_trials
    from roughness.perception.stimuli import read_stimuli
    from roughness.perception.values import stimulus_values

    from roughness.core.limits import MAX_TRIALS, check_size

    check_size("trials of one simulated experiment", max(args.trials), MAX_TRIALS, "trials")
    require_cvxpy()
    stimuli = read_stimuli(args.stimuli)
    ids = [s.stimulus for s in stimuli]
    observer = Observer(DEFAULT_SIGMA if args.sigma is None else args.sigma, args.lapse)
    v = _read_truth(args.truth, ids) if args.truth else None
    files = _outputs(args.out, ("plan.csv", "plan.json"), args.overwrite,
                     {"--stimuli": args.stimuli, "--truth": args.truth})
    if v is None:
        cache = Path(args.cache) if args.cache else Path(args.out) / "fem-cache"
        log(args, f"true V of {len(ids)} stimuli with {args.engine} ...")
        values = stimulus_values(ids, [s.heightmap() for s in stimuli], args.engine, cache, lambda m: log(args, m))
        v = np.array([x.roughness for x in values])
    plan = plan_trials(ids, v, args.trials, args.experiments, observer, args.tolerance, args.share, args.seed,
                       stderr_progress("simulated experiments", args.quiet))
    summary = {"stimuli_table": str(args.stimuli), "truth": args.truth or args.engine, "sigma": observer.sigma,
               "lapse": observer.lapse, "seed": args.seed, **plan.summary()}
    _made(files)
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


def _read_truth(path: str, ids: list[str]):
    import csv

    import numpy as np

    from roughness.core.errors import InputError
    from roughness.perception.trials import listed

    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rows = {r["stimulus"].strip(): float(r["roughness"]) for r in csv.DictReader(f)}
    except FileNotFoundError:
        raise InputError(f"truth file not found: {path}", parameter="truth") from None
    except (KeyError, TypeError, ValueError, AttributeError, csv.Error):  # UnicodeDecodeError is a ValueError
        raise InputError(f"{path}: expected a CSV table with columns stimulus,roughness (numbers)",
                         parameter="truth") from None
    missing = [i for i in ids if i not in rows]
    if missing:
        raise InputError(listed(f"{path}: no roughness for", missing), parameter="truth")
    return np.array([rows[i] for i in ids])


def _write_truth(path: Path, ids, v, coordinate) -> None:
    from roughness.core.files import write_csv

    write_csv(path, ["stimulus", "roughness", "coordinate"],
              ([s, f"{a:.6g}", f"{p:.6g}"] for s, a, p in zip(ids, v, coordinate)))
