"""`roughness tune HEIGHTMAP --target-lambda L | --target-v V | --like REF | --jnd N --out OUT`: reach a target
roughness."""
from __future__ import annotations

import argparse

from .common import (
    FACTOR,
    JND,
    LENGTH,
    WAVELENGTH,
    Number,
    add_model_tail,
    add_reading_args,
    count,
    defaults,
    finish,
    json_text,
    load_input,
    log,
    positive,
    readings,
    write_stdout,
)
from .printer import add_printer_arg, print_report, printer_of

MAX_TARGET_V = 10.0  # --target-v: the standard scale's V at the 10 mm footprint is 7.5 (MAX_WAVELENGTH_MM)
MAX_FEM_RUNS = 100  # --max-fem: each verification is an FEM run of seconds to minutes; searches settle in 2-4


def add_parser(sub) -> None:
    from roughness.design.tune import FACTOR_RANGE, KNOBS, MAX_RELATIVE_JND, tune
    from roughness.surface.stl import DEFAULT_BASE_MM

    given = defaults(tune)
    p = sub.add_parser("tune", help="scale a texture's heights or lateral size to reach a target roughness "
                                    "(surrogate search, FEM-verified)")
    p.add_argument("heightmap", metavar="HEIGHTMAP", help="texture to scale: .npy (mm), 8/16-bit .png/.tif, .npz, .h5")
    target = p.add_mutually_exclusive_group(required=True)
    target.add_argument("--target-lambda", type=WAVELENGTH, metavar="MM",
                        help="target equivalent wavelength on the standard scale (mm)")
    target.add_argument("--target-v", type=positive(MAX_TARGET_V), metavar="V", help="target roughness V (FEM scale)")
    target.add_argument("--like", metavar="REF", help="feel like this texture (its FEM V is the target)")
    target.add_argument("--jnd", type=Number(float, low=-MAX_RELATIVE_JND, high=MAX_RELATIVE_JND), metavar="N",
                        help="N JNDs rougher than the input (negative: smoother), e.g. +1 or -0.5: the input's FEM "
                             "V sets the start, one JND is a 19%% step in equivalent wavelength")
    p.add_argument("--by", choices=KNOBS, default=given["by"],
                   help=f"scale the heights or the lateral size (default: {given['by']})")
    p.add_argument("--keep-look", action="store_true",
                   help="reach the target with the mix of lateral and height scale that changes the look least "
                        "(roughness.design.look_keeping: about ten tunes, so use --verify spectral; --by and the "
                        "factor range do not apply); the look change is reported beside the feel change")
    p.add_argument("--out", required=True, metavar="FILE",
                   help="the scaled texture: .npz, .npy, .h5 (mm), .png (16-bit), .tif, or .stl (printable plate)")
    p.add_argument("--base-mm", type=LENGTH,
                   help=f"STL only: plate thickness below the texture's lowest point in mm (default {DEFAULT_BASE_MM:g})")
    ranges = ", ".join(f"{k} {lo:g}..{hi:g}" for k, (lo, hi) in FACTOR_RANGE.items())
    p.add_argument("--min-factor", type=FACTOR, help=f"smallest scale factor searched (default: {ranges})")
    p.add_argument("--max-factor", type=FACTOR, help="largest scale factor searched (default: see --min-factor)")
    p.add_argument("--tolerance-jnd", type=JND, default=given["tolerance_jnd"],
                   help=f"stop when the FEM is this close to the target, in JND (default {given['tolerance_jnd']:g})")
    p.add_argument("--max-fem", type=count(MAX_FEM_RUNS), default=given["max_fem"],
                   help=f"most FEM verifications (default {given['max_fem']})")
    add_reading_args(p)
    p.add_argument("--tile", action="store_true", help="the texture is a periodic tile (for maps under 10 mm)")
    add_printer_arg(p, "the input, --like and the result are judged as printed; --out is the digital design, "
                       "whose own V and the difference in JND are reported")
    add_model_tail(p, "one JSON object (default: text)")
    finish(p, run, target_lambda_mm="--target-lambda")


def run(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct, check_output
    from roughness.design.evaluation import Evaluator
    from roughness.design.tune import FACTOR_RANGE, target_of, tune
    from roughness.surface.io import SAVE_SUFFIXES, save_heightmap

    check_distinct({"--out": args.out}, {"HEIGHTMAP": args.heightmap, "--like": args.like, "--model": args.model,
                                      "--printer": args.printer})
    out = check_output(args.out, args.overwrite, "out")
    if out.suffix.lower() not in SAVE_SUFFIXES:
        raise InputError(f"cannot save {out}: unsupported format {out.suffix or '(no suffix)'!r}; "
                         f"supported: {', '.join(SAVE_SUFFIXES)}", "out")
    if args.base_mm is not None and out.suffix.lower() != ".stl":
        raise InputError("applies only to STL output", "base_mm")
    if args.keep_look and (args.min_factor or args.max_factor):
        raise InputError("--keep-look searches its own mixes of lateral and height factors", "min_factor")
    lo, hi = FACTOR_RANGE[args.by]
    factors = (args.min_factor or lo, args.max_factor or hi)
    if not factors[0] < factors[1]:
        raise InputError(f"the factor range must rise, got {factors[0]:g}..{factors[1]:g}", "min_factor")
    printer = printer_of(args)
    hm = load_input(args, args.heightmap, several=bool(args.like))
    reference = load_input(args, args.like, several=True) if args.like else None
    evaluator = Evaluator(args.model, args.verify, printer=printer)
    printing = print_report(evaluator, hm, args.tile)  # refuses a map too coarse for the printer before any work
    if reference is not None:
        log(args, f"tune: FEM of the reference {args.like}")
    if args.jnd is not None:
        log(args, f"tune: {evaluator.verifier} of the input {args.heightmap}")
    target = target_of(evaluator, args.target_lambda, args.target_v, reference, args.like or "", args.tile,
                       args.jnd, hm)
    kept = None
    if args.keep_look:
        from roughness.design.look_keeping import keep_look

        log(args, f"tune: target {target.describe()}; the mix of lateral and height scale that keeps the look")
        kept = keep_look(hm, target, evaluator, args.tile, tolerance_jnd=args.tolerance_jnd, max_fem=args.max_fem,
                         progress=lambda line: log(args, "  " + line))
        result = kept.chosen.result
    else:
        log(args, f"tune: target {target.describe()}; surrogate search over {args.by} factors "
                  f"{factors[0]:g}..{factors[1]:g}")
        result = tune(hm, target, args.by, evaluator, factors, args.tolerance_jnd, args.max_fem, args.tile,
                      progress=lambda line: log(args, "  " + line))
    save_heightmap(result.heightmap, out, base_mm=args.base_mm, overwrite=args.overwrite)
    summary = {"input": args.heightmap, "out": str(out), **result.summary(), "verifier": evaluator.verifier,
               "provenance": evaluator.provenance.as_dict(),
               "readings": readings(args), **({"keep_look": kept.summary()} if kept else {})}
    if printing:
        printing.verify(result.heightmap, result.achieved.roughness, args.tile)
        summary["printing"] = printing.as_dict()
    if args.json:
        write_stdout(json_text(summary))
    else:
        a = result.achieved
        lines = [f"{args.heightmap} -> {out}: " + (_kept_text(kept) if kept else f"{args.by} x {result.factor:.4f}"),
                 f"target: {target.describe()}",
                 (f"achieved ({evaluator.verifier}): V {a.roughness:.4f} ± {a.roughness_stderr:.4f}, lambda "
                  f"{a.equivalent_lambda_mm:.3f} mm; error {result.jnd_error:+.2f} ± {result.jnd_stderr:.2f} JND "
                  f"({'within' if result.reached else 'NOT within'} {result.tolerance_jnd:g} JND after "
                  f"{len(result.steps)} {evaluator.verifier} run(s)); surrogate V {result.surrogate_roughness:.4f}"
                  + (", searched with the spectral engine" if result.search_engine == "spectral" else "")),
                 *(_look_lines(kept) if kept else []),
                 *(f"note: {n}" for n in result.notes), *(printing.lines() if printing else [])]
        write_stdout("\n".join(lines))
    return 0 if result.reached else 1


def _kept_text(kept) -> str:
    c = kept.chosen
    return f"lateral x {c.lateral:.4f}, height x {c.height or 1:.4f} (the mix that keeps the look)"


def _look_lines(kept) -> list[str]:
    """The look change of the kept mix beside the plain knobs' (height alone, lateral alone), for the same feel."""
    c = kept.chosen
    lines = [f"look change: {c.look.difference:.2f} look JND (Weber contrast {c.look.weber_contrast:+.4f}; "
             f"threshold {c.look.threshold:g} assumed)"]
    for label, found in (("height alone", [k for k in kept.candidates if k.lateral == 1.0]),
                         ("lateral alone", [k for k in kept.candidates if k.height is None])):
        if found and found[0].reached:
            lines.append(f"  {label}: {found[0].look.difference:.2f} look JND for the same target")
        elif found:
            lines.append(f"  {label}: target not reached")
    return lines
