"""`roughness dataset build|info|verify`: HDF5 datasets of FEM results."""
from __future__ import annotations

import argparse
import json
import sys

from .common import at_least_one


def add_parser(sub) -> None:
    from roughness.simulate.config import FIDELITIES

    data = sub.add_parser("dataset", help="build, inspect and verify HDF5 datasets of FEM results")
    data_sub = data.add_subparsers(dest="dataset_command", required=True)
    b = data_sub.add_parser("build", help="simulate a recipe's samples in parallel (Dask), resumable")
    b.add_argument("--out", required=True, help="HDF5 file, created or resumed")
    b.add_argument("--n", type=int, required=True, help="number of samples (the first n of the recipe)")
    b.add_argument("--recipe", help="recipe JSON (default: bump textures only)")
    b.add_argument("--fidelity", choices=FIDELITIES, default="coarse")
    b.add_argument("--workers", type=int, default=2, help="local Dask worker processes (one thread each)")
    b.add_argument("--scheduler", help="address of an existing Dask scheduler instead of a local cluster")
    b.add_argument("--seed", type=int, help="override the recipe's seed")
    b.add_argument("--quiet", action="store_true")
    b.set_defaults(run=build)
    i = data_sub.add_parser("info", help="counts by family, value ranges, failures")
    i.add_argument("file")
    i.add_argument("--json", action="store_true")
    i.set_defaults(run=info)
    v = data_sub.add_parser("verify", help="check schema, ids and finite values; exit 1 if anything is wrong")
    v.add_argument("file")
    v.set_defaults(run=verify)


def build(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from roughness.dataset.build import build
    from roughness.dataset.recipe import Recipe, load_recipe
    from roughness.simulate.config import SimConfig

    at_least_one("--workers", args.workers)
    recipe = load_recipe(args.recipe) if args.recipe else Recipe()
    if args.seed is not None:
        recipe = replace(recipe, seed=args.seed)
    config = SimConfig(fidelity=args.fidelity)
    try:
        counts = build(args.out, args.n, recipe, config, workers=args.workers, scheduler=args.scheduler,
                       quiet=args.quiet)
    except KeyboardInterrupt:
        print(f"roughness: interrupted; the samples written so far are kept in {args.out}; "
              "run the same command again to resume", file=sys.stderr)
        return 130
    print(json.dumps(counts))
    return 0


def info(args: argparse.Namespace) -> int:
    from roughness.dataset.store import info

    summary = info(args.file)
    print(json.dumps(summary, indent=None if args.json else 1, default=str))
    return 0


def verify(args: argparse.Namespace) -> int:
    from roughness.dataset.store import verify

    problems = verify(args.file)
    for p in problems:
        print(f"problem: {p}")
    print(f"{args.file}: {'OK' if not problems else f'{len(problems)} problem(s)'}")
    return 1 if problems else 0
