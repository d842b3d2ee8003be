"""`roughness homogeneity HEIGHTMAP`: does a texture feel the same everywhere? V on random windows, spread, verdict."""
from __future__ import annotations

import argparse

from roughness.core.limits import MAX_WINDOWS

from .common import (
    LENGTH,
    SEED,
    add_model_tail,
    add_reading_args,
    count,
    defaults,
    finish,
    json_text,
    load_input,
    log,
    readings,
    write_stdout,
)
from .printer import add_printer_arg, printer_of


def add_parser(sub) -> None:
    from roughness.design.evaluation import ENGINES
    from roughness.design.homogeneity import homogeneity

    given = defaults(homogeneity)
    p = sub.add_parser("homogeneity", help="does a texture feel the same everywhere? V on random windows, "
                                           "relative variance, spread in JNDs, verdict")
    p.add_argument("heightmap", metavar="HEIGHTMAP", help="heightmap file: .npy (mm), 8/16-bit .png/.tif, .npz, .h5")
    add_reading_args(p)
    p.add_argument("--window-mm", type=LENGTH,
                   help="window side in mm (default: the 10 mm skin footprint; a smaller window, such as the "
                        "paper's 5 mm, is felt alone, mirror-tiled)")
    p.add_argument("--n", type=count(MAX_WINDOWS), default=given["n"], help=f"number of windows, >= 3 (default {given['n']})")
    p.add_argument("--seed", type=SEED, default=given["seed"], help="seed of the window placement (default 0)")
    p.add_argument("--engine", choices=ENGINES, default=given["engine"],
                   help="surrogate (milliseconds) or fem: the verifier of --verify, per window (the FEM: seconds, "
                        f"the reference; spectral: tens of milliseconds) (default: {given['engine']})")
    p.add_argument("--tile", action="store_true", help="the map is a periodic tile: windows anywhere, wrapping")
    p.add_argument("--map", metavar="FILE.png", help="picture of the windows coloured by their V")
    add_printer_arg(p, "the verdict, V and spreads are of the printed surface, the digital texture's beside them "
                       "(same windows)")
    add_model_tail(p, "one JSON object (default: text)")
    finish(p, run)


def run(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct, check_output
    from roughness.design.evaluation import Evaluator
    from roughness.design.homogeneity import homogeneity, homogeneity_as_printed, save_map
    from roughness.engines import model_provenance

    check_distinct({"--map": args.map}, {"HEIGHTMAP": args.heightmap, "--model": args.model, "--printer": args.printer})
    if args.map:
        if not args.map.lower().endswith(".png"):
            raise InputError(f"cannot write {args.map}: the map is a .png picture", parameter="map")
        check_output(args.map, args.overwrite, "map")
    if args.n < 3:
        raise InputError(f"needs at least 3 windows, got {args.n}", parameter="n")
    printer = printer_of(args)  # an unknown printer is refused before the map is read
    hm = load_input(args, args.heightmap)
    evaluator = Evaluator(args.model, args.verify, printer=printer)
    engine = evaluator.verifier if args.engine == "fem" else args.engine
    log(args, f"homogeneity: {args.n} windows with the {engine}"
        + (f", as printed by {evaluator.printer.name} and digital" if evaluator.printer else ""))
    run_test = homogeneity_as_printed if evaluator.printer else homogeneity
    result = run_test(hm, args.engine, args.window_mm, args.n, args.seed, args.tile, evaluator,
                      progress=lambda done, total: log(args, f"  {engine} window {done}/{total}"))
    if args.map:
        save_map(result, result.print_result.heightmap if result.print_result else hm, args.map, args.overwrite)
    provenance = evaluator.provenance if args.engine == "fem" else model_provenance(evaluator.model)
    summary = {"input": args.heightmap, **result.summary(), "verifier": engine, "readings": readings(args),
               "provenance": provenance.as_dict()}
    if args.json:
        write_stdout(json_text(summary))
        return 0
    what = f"{args.heightmap} as printed" if evaluator.printer else args.heightmap
    lines = [f"{what}: {_verdict_text(result, engine)}" + (f"; map written to {args.map}" if args.map else "")]
    if result.digital is not None and result.print_result is not None:
        lines += [f"  digital design: {_verdict_text(result.digital, engine)}",
                  f"  printer {evaluator.printer.describe()}",
                  *(f"  print note: {note}" for note in result.print_result.notes)]
    write_stdout("\n".join(lines))
    return 0


def _verdict_text(result, engine: str) -> str:
    """The verdict, mean V, relative variance and spreads of one ``Homogeneity`` in words."""
    stats = ""  # every window below the scale: the note says so
    if result.spread_jnd is not None:
        paper = ("undefined (mean V below the scale)" if result.relative_variance is None else
                 f"{result.relative_variance:.1e} (the paper: ~1e-4 typical, > 1e-3 inhomogeneous: "
                 f"{result.paper_verdict})")
        stats = (f", relative variance {paper}; spread {result.spread_jnd:.2f} JND (SD), 10-90% range "
                 f"{result.range_jnd:.2f} JND (a fingertip tells parts apart at >= 1)")
    note = f"; {result.note}" if result.note else ""
    return (f"{result.verdict.upper()} - V over {len(result.roughness)} windows of {result.window_mm:g} mm "
            f"({engine}): mean {result.mean_roughness:.4f}{stats}{note}")
