"""`roughness dataset build|info|verify`: HDF5 datasets of FEM results."""
from __future__ import annotations

import argparse
import sys

from roughness.core.limits import MAX_DATASET_SAMPLES

from .common import FRACTION, SEED, add_cluster_args, add_overwrite, count, finish, json_text, write_stdout


def add_parser(sub) -> None:
    from roughness.dataset.build import BUILD_CONFIG, ENGINES, WORKERS
    from roughness.simulate.config import FIDELITIES

    data = sub.add_parser("dataset", help="build, inspect and verify HDF5 datasets of FEM results")
    data_sub = data.add_subparsers(dest="dataset_command", required=True)
    b = data_sub.add_parser("build", help="simulate a recipe's samples in parallel (Dask), resumable")
    b.add_argument("--out", required=True, metavar="DATASET",
                   help="HDF5 dataset file: created, or resumed if it is a dataset of the same configuration")
    b.add_argument("--n", type=count(MAX_DATASET_SAMPLES), required=True, help="number of samples (the first n of the recipe)")
    b.add_argument("--recipe", metavar="JSON", help="recipe file (default: the built-in recipe, bump textures only)")
    b.add_argument("--engine", choices=ENGINES, default="fem",
                   help="what labels the samples: fem, or spectral (the skin as an infinite layer, no mesh: "
                        "--fidelity and --tolerance do not apply) (default fem)")
    b.add_argument("--fidelity", choices=FIDELITIES,
                   help=f"FEM mesh resolution of every sample; converged: refined until the estimated "
                        f"discretization error of V is below --tolerance (default {BUILD_CONFIG.fidelity})")
    b.add_argument("--tolerance", type=FRACTION, default=BUILD_CONFIG.tolerance,
                   help=f"--fidelity converged: target relative discretization error of V "
                        f"(default {BUILD_CONFIG.tolerance})")
    add_cluster_args(b, "simulate the samples", WORKERS, WORKERS)
    b.add_argument("--seed", type=SEED, help="replace the recipe's seed (default: the recipe's)")
    b.add_argument("--labels", metavar="LABELS", help="labels file of an earlier build of this configuration "
                   "(roughness dataset labels): samples whose remade texture matches take its results, without FEM")
    b.add_argument("--quiet", action="store_true", help="no progress messages on stderr")
    finish(b, build)
    lab = data_sub.add_parser("labels", help="write a dataset's FEM results without its maps (small: to commit; "
                              "build --labels remakes the dataset from it)")
    lab.add_argument("dataset", metavar="DATASET", help="HDF5 dataset file")
    lab.add_argument("--out", required=True, metavar="LABELS", help="labels file to write (.jsonl.gz)")
    add_overwrite(lab)
    finish(lab, labels)
    i = data_sub.add_parser("info", help="counts by family, value ranges, failures")
    i.add_argument("dataset", metavar="DATASET", help="HDF5 dataset file")
    i.add_argument("--json", action="store_true", help="one JSON line instead of indented JSON")
    finish(i, info)
    v = data_sub.add_parser("verify", help="check schema, ids and finite values; exit 1 if anything is wrong")
    v.add_argument("dataset", metavar="DATASET", help="HDF5 dataset file")
    finish(v, verify)


def build(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from roughness.core.files import check_distinct
    from roughness.dataset.build import BUILD_CONFIG, Interrupted, build, build_provenance
    from roughness.dataset.recipe import Recipe, load_recipe

    check_distinct({"--out": args.out}, {"--recipe": args.recipe, "--labels": args.labels,
                                         "--scheduler-file": args.scheduler_file})
    recipe = load_recipe(args.recipe) if args.recipe else Recipe()
    if args.seed is not None:
        recipe = replace(recipe, seed=args.seed)
    if args.engine == "spectral" and args.fidelity is not None:
        from roughness.core.errors import InputError

        raise InputError("--fidelity sets the FEM's mesh; the spectral engine has none", parameter="fidelity")
    config = replace(BUILD_CONFIG, fidelity=args.fidelity or BUILD_CONFIG.fidelity, tolerance=args.tolerance)
    labels = None
    if args.labels:
        from roughness.dataset.labels import load_labels

        labels = load_labels(args.labels)
    try:
        counts = build(args.out, args.n, recipe, config, workers=args.workers, scheduler=args.scheduler,
                       quiet=args.quiet, labels=labels, engine=args.engine, scheduler_file=args.scheduler_file)
    except Interrupted as stop:
        print(f"roughness: interrupted; {stop.stored} of {args.n} samples written to {args.out}; "
              "run the same command again to resume", file=sys.stderr)
        return 130
    write_stdout(json_text(counts | {"provenance": build_provenance(config, args.engine).as_dict()}))
    return 0


def labels(args: argparse.Namespace) -> int:
    from roughness.core.files import check_distinct
    from roughness.dataset.labels import export_labels

    check_distinct({"--out": args.out}, {"DATASET": args.dataset})
    written = export_labels(args.dataset, args.out, args.overwrite)
    ok = sum(label.values["status"] == "ok" for label in written.labels.values())
    write_stdout(json_text({"labels": str(args.out), "samples": len(written), "ok": ok}))
    return 0


def info(args: argparse.Namespace) -> int:
    from roughness.dataset.inspection import info

    write_stdout(json_text(info(args.dataset), indent=None if args.json else 1, default=str))
    return 0


def verify(args: argparse.Namespace) -> int:
    from roughness.dataset.inspection import verify

    problems = verify(args.dataset)
    lines = [f"problem: {p}" for p in problems] + [f"{args.dataset}: {f'{len(problems)} problem(s)' if problems else 'OK'}"]
    write_stdout("\n".join(lines))
    return 1 if problems else 0
