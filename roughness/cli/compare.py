"""`roughness compare`: engines timed and scored against a reference engine."""
from __future__ import annotations

import argparse
import sys

from .common import at_least_one, log

COMPARE_ENGINES = ("fem:coarse", "fem:default", "surrogate", "ra", "p90", "glcm_sum_of_squares", "glcm_sum_variance")


def add_parser(sub) -> None:
    cmp = sub.add_parser("compare", help="time and score engines against a reference engine (resumable)")
    cmp.add_argument("input", help="dataset file (.h5), folder of heightmaps, or recipe (.json, with --n)")
    cmp.add_argument("--out", required=True, help="folder for results.jsonl (the cache), tables, plots, report.md")
    cmp.add_argument("--engines", nargs="+", default=list(COMPARE_ENGINES), metavar="ENGINE",
                     help="fem:coarse fem:default fem:fine surrogate[:MODEL.onnx] ra p90 glcm_sum_of_squares "
                          "glcm_sum_variance (default: all but fem:fine)")
    cmp.add_argument("--reference", default="fem:fine", help="engine the others are scored against")
    cmp.add_argument("--n", type=int, help="number of textures (the first n; required for a recipe)")
    cmp.add_argument("--pixel-mm", type=float, help="pixel size of a folder's heightmaps (mm)")
    cmp.add_argument("--height-mm", type=float, help="full-scale height of a folder's PNG/TIFF heightmaps (mm)")
    cmp.add_argument("--quiet", action="store_true")
    cmp.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from roughness.compare import ResultCache, run, textures_of
    from roughness.engines import make_engine
    from roughness.report import write_report

    if args.n is not None:
        at_least_one("--n", args.n)
    specs = list(dict.fromkeys([args.reference, *args.engines]))
    engines = [make_engine(spec) for spec in specs]
    textures, stored = textures_of(args.input, args.n, args.pixel_mm, args.height_mm)
    out = Path(args.out)
    cache = ResultCache(out, {e.spec: e.identity for e in engines})
    try:
        run(textures, engines, cache, stored, quiet=args.quiet)
    except KeyboardInterrupt:
        print(f"roughness: interrupted; results so far are kept in {cache.path}; run the same command again to "
              "resume", file=sys.stderr)
        return 130
    cost = next((e.model.meta.get("cost_core_seconds") for e in engines if e.kind == "surrogate"), None)
    table = write_report(textures, {e.spec: e.kind for e in engines}, args.reference, cache, out, cost, args.input)
    print(table)
    log(args, f"report written to {out / 'report.md'}")
    return 0
