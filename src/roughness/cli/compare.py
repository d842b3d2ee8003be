"""`roughness compare`: engines timed and scored against a reference engine."""
from __future__ import annotations

import argparse
import sys
from functools import partial

from roughness.core.limits import MAX_DATASET_SAMPLES

from .common import add_overwrite, add_quiet, add_reading_args, count, finish, load, log, show_notes

COMPARE_ENGINES = ("fem:coarse", "fem:default", "surrogate", "ra", "p90", "glcm_sum_of_squares", "glcm_sum_variance")
REFERENCE = "fem:fine"


def add_parser(sub) -> None:
    cmp = sub.add_parser("compare", help="time and score engines against a reference engine (resumable)")
    cmp.add_argument("input", metavar="INPUT",
                     help="dataset file (.h5), folder of heightmaps, or recipe (.json, with --n)")
    cmp.add_argument("--out", required=True,
                     help="folder for results.jsonl (the cache), tables, plots, report.md; rerunning the same "
                          "comparison there resumes it, another comparison is refused unless --overwrite")
    cmp.add_argument("--engines", nargs="+", default=list(COMPARE_ENGINES), metavar="ENGINE",
                     help="fem:coarse fem:default fem:fine fem:converged[@TOL] surrogate[:MODEL.onnx] ra p90 "
                          f"glcm_sum_of_squares glcm_sum_variance (default: {' '.join(COMPARE_ENGINES)})")
    cmp.add_argument("--reference", default=REFERENCE,
                     help=f"engine the others are scored against (default: {REFERENCE})")
    cmp.add_argument("--n", type=count(MAX_DATASET_SAMPLES), help="number of textures, the first n (default: all; required for a recipe)")
    add_reading_args(cmp)
    add_quiet(cmp)
    add_overwrite(cmp)
    finish(cmp, run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from roughness.compare import check_report_folder, run, textures_of, write_manifest
    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct
    from roughness.engines import engine_provenance, make_engine
    from roughness.report import write_report
    from roughness.result_cache import ResultCache

    specs = list(dict.fromkeys([args.reference, *args.engines]))
    engines = [make_engine(spec, "reference" if spec == args.reference else "engines") for spec in specs]
    out = Path(args.out)
    check_distinct({"--out": out}, {"INPUT": args.input})
    manifest = {"input": args.input, "n": args.n, "reference": args.reference, "engines": sorted(specs)}
    check_report_folder(out, manifest, args.overwrite)
    shown = set()  # files whose notes were shown (a texture is loaded again for the report)

    def load_file(path: Path):
        hm, loaded = load(args, str(path), several=True)
        if path not in shown:
            shown.add(path)
            show_notes(args, loaded.lines())
        return hm

    textures, stored = textures_of(args.input, args.n, load_file)
    provenance = {e.spec: engine_provenance(e).as_dict() for e in engines}
    cache = ResultCache(out, {e.spec: e.identity for e in engines}, partial(write_manifest, out, manifest, provenance),
                        provenance)
    try:
        outcome = run(textures, engines, cache, stored, quiet=args.quiet)
    except KeyboardInterrupt:
        print(f"roughness: interrupted; results so far are kept in {cache.path}; run the same command again to "
              "resume", file=sys.stderr)
        return 130
    if not outcome.keys:
        raise InputError(f"none of the {len(textures)} textures of {args.input} could be compared (reasons above)",
                         parameter="input")
    write_manifest(out, manifest, provenance)  # also when every result was cached
    cost = next((e.model.meta.cost_core_seconds for e in engines if e.kind == "surrogate"), None)
    table = write_report(textures, outcome, {e.spec: e.kind for e in engines}, args.reference, cache, out, cost,
                         args.input)
    print(table)
    log(args, f"report written to {out / 'report.md'}")
    if outcome.input_errors:
        log(args, f"{len(outcome.input_errors)} of {len(textures)} inputs could not be compared (listed in the report)")
        return 2
    return 0
