"""`roughness perception fit EMBEDDING --stimuli TABLE --out DIR`: V of the stimuli against their embedding."""
from __future__ import annotations

import argparse
from pathlib import Path

from .common import FORCE, LENGTH, add_overwrite, add_quiet, count, finish, log
from .perception_common import made, number_list, output_files

length_list = number_list(LENGTH, "lengths in mm")  # 0.4,0.8,1.2
force_list = number_list(FORCE, "forces in N")
MAX_STIMULI = 1000  # --exclude-least-homogeneous: an experiment has tens of stimuli (the paper 29)


def id_list(text: str) -> list[str]:
    return [v.strip() for v in text.split(",") if v.strip()]


def add_parser(sub) -> None:
    fit = sub.add_parser("fit", help="V of the stimuli against the embedding: Pearson/Spearman, classical measures, "
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
    fit.add_argument("--exclude-least-homogeneous", type=count(MAX_STIMULI, low=0), default=0, metavar="N",
                     help="also leave out the N least homogeneous stimuli, as the paper did (N = 5): largest spread "
                          "in JNDs from the stimuli table's 'homogeneity' column, else computed with the "
                          "surrogate (roughness homogeneity); default 0")
    fit.add_argument("--distances", type=length_list, default=[0.4, 0.6, 0.8, 1.0, 1.2, 1.6], metavar="MM,MM",
                     help="pair distances d of the re-fit (mm)")
    fit.add_argument("--radii", type=length_list, default=[0.2, 0.4, 0.6, 0.8, 1.0, 1.2], metavar="MM,MM",
                     help="disk radii r of the re-fit (mm)")
    fit.add_argument("--forces", type=force_list, default=[], metavar="N,N",
                     help="forces (N) of a re-fit over force (new FEM runs, cached; default: none)")
    add_overwrite(fit)
    add_quiet(fit)
    finish(fit, run_fit, force_n="--forces")


def run_fit(args: argparse.Namespace) -> int:
    import numpy as np

    from roughness.core.errors import InputError
    from roughness.perception.analysis import read_embedding_csv, write_json
    from roughness.perception.fit import (
        Fit,
        classical_measures,
        homogeneity_spreads,
        least_homogeneous,
        r_text,
        sampling_fit,
    )
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
    files = output_files(args.out, names, args.overwrite,
                         {"EMBEDDING": args.embedding, "--stimuli": args.stimuli})
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
    made(files)
    _write_fit_csv(files["fit.csv"], fit)
    write_json(files["fit.json"], summary)
    plot_fit(fit, files["fit.png"])
    if fem:
        plot_sampling(fit, files["sampling.png"])
    c = summary["correlations"]["V"]
    line = (f"V ({args.engine}) vs embedding: Pearson R {r_text(c['all']['pearson'])}, "
            f"Spearman {r_text(c['all']['spearman'])}")
    if excluded:
        line += (f"; without {len(excluded)} excluded: R {r_text(c['included']['pearson'])}, "
                 f"Spearman {r_text(c['included']['spearman'])}")
    print(line)
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
