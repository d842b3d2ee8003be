"""`roughness predict`: roughness in milliseconds (surrogate), FEM where out of domain."""
from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time

from .common import (
    BATCH,
    FRACTION,
    LENGTH,
    PARALLEL,
    add_cluster_args,
    add_overwrite,
    add_quiet,
    add_reading_args,
    defaults,
    error_message,
    finish,
    float_pair,
    json_text,
    load,
    load_input,
    log,
    positive,
    readings,
    show_notes,
)
from .printer import add_printer_arg
from .simulate import add_curvature_args, curved_base

MAP_PROGRESS_SECONDS = 10.0  # interval of --map progress messages
# --max-std: an ensemble spread of 10 x (V + 0.001) is no answer at all (the shipped threshold is 0.06).
MAX_RELATIVE_SPREAD = 10.0


def add_parser(sub) -> None:
    from roughness.engines import SurrogateEngine
    from roughness.maps import WORKERS
    from roughness.prediction import PREDICT_ENGINES, PredictOptions, predict
    from roughness.surrogate.roughness_map import roughness_map

    given, options = defaults(predict), defaults(PredictOptions)
    mapping, threads = defaults(roughness_map), defaults(SurrogateEngine)["threads"]
    pr = sub.add_parser("predict", help="roughness in milliseconds (surrogate), FEM where out of domain")
    pr.add_argument("inputs", nargs="+", metavar="HEIGHTMAP",
                    help="heightmap files, folders of them, or roughness dataset files (.h5); "
                         "FILE:pixel-mm=MM,height-mm=MM gives a file (or every file of a folder) its own units")
    pr.add_argument("--model", help="ONNX surrogate (default: the shipped models/roughness-cnn.onnx)")
    pr.add_argument("--engine", choices=PREDICT_ENGINES, default=given["engine"],
                    help=f"surrogate (ms), spectral (the skin as an infinite layer: tens of ms, no mesh), fem "
                         f"(seconds), or auto: the surrogate, FEM for inputs outside its domain "
                         f"(default: {given['engine']})")
    pr.add_argument("--max-std", type=positive(MAX_RELATIVE_SPREAD),
                    help="ensemble models: --engine auto also runs the FEM where the relative spread "
                         "roughness_std / (V + 0.001) exceeds this (default: the threshold measured when the "
                         "ensemble was exported; single-network models give no spread)")
    pr.add_argument("--fidelity", choices=("coarse", "default", "fine", "converged"),
                    help="FEM fidelity (default: that of the model's training labels; the standard scale "
                         "is tabulated for coarse, default and fine; converged answers are placed on fine's)")
    pr.add_argument("--tolerance", type=FRACTION,
                    help="--fidelity converged: target relative discretization error of V (default: 0.03)")
    add_reading_args(pr)
    pr.add_argument("--tile", action="store_true", help="repeat small heightmaps as periodic textures (default: off)")
    pr.add_argument("--centre", type=float_pair, metavar="X,Y", help="footprint centre in mm (default: map centre)")
    add_curvature_args(pr)
    pr.add_argument("--batch-size", type=BATCH, default=options["batch_size"],
                    help=f"heightmaps per surrogate batch (default: {options['batch_size']})")
    pr.add_argument("--threads", type=PARALLEL, default=threads, help=f"onnxruntime threads (default: {threads})")
    pr.add_argument("--json", action="store_true", help="one JSON object per input and line (default: text)")
    pr.add_argument("--map", metavar="FILE", help="roughness map of a whole object (one input): the footprint slid "
                    "over the map, saved as .png (figure) or .npy (V per position); refused if FILE exists "
                    "unless --overwrite")
    pr.add_argument("--step-mm", type=LENGTH, default=mapping["step_mm"],
                    help=f"--map: distance between footprint positions in mm (default: {mapping['step_mm']:g})")
    add_cluster_args(pr, "solve the windows of a spectral --map", WORKERS, None)
    add_printer_arg(pr, "the digital texture's V and the difference in JND are reported too")
    add_quiet(pr)
    add_overwrite(pr)
    finish(pr, run, centre_mm="--centre", curved="--curvature-mm", radius_mm="--curvature-mm", shape="--base",
           axis="--curvature-axis")


def run(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError
    from roughness.prediction import PredictOptions, predictions
    from roughness.simulate.config import SimConfig
    from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel

    from .inputs import InputReader
    from .predict_look import Looks
    from .printer import PrintPairs, printer_of

    cluster = next((name for name in ("workers", "scheduler", "scheduler_file") if getattr(args, name) is not None),
                   None)
    if cluster and not args.map:
        raise InputError("Dask solves the windows of a spectral --map; without --map there are none",
                         parameter=cluster)
    if args.map:
        from roughness.core.files import check_distinct
        from roughness.surrogate.roughness_map import check_map_path

        check_distinct({"--map": args.map}, {"HEIGHTMAP": args.inputs, "--model": args.model,
                                             "--printer": args.printer, "--scheduler-file": args.scheduler_file})
        if args.curvature_mm is not None:
            raise InputError("--map slides the footprint over a flat object; it does not take --curvature-mm")
        check_map_path(args.map, args.overwrite)
    printer = printer_of(args)
    if args.engine == "spectral":  # the surrogate only judges its domain (--model's, else the shipped one's)
        model, footprint_mm = args.model, defaults(SimConfig)["width_mm"]
    else:
        model = SurrogateModel(args.model or DEFAULT_MODEL, threads=args.threads)
        footprint_mm = model.footprint_mm
    if args.map:
        return _predict_map(args, None if args.engine == "spectral" else model, printer)
    loaded = {}  # input name -> what loading did to it, until its answer is shown

    def load_one(text: str, several: bool):
        hm, loaded[text] = load(args, text, several)
        return hm

    reader = InputReader(args.inputs, footprint_mm, args.centre, args.tile, load_one)
    pairs = PrintPairs(reader, printer, args.tile) if printer is not None else None  # each input, then its print
    looks = Looks(args.centre, args.tile, pairs is not None) if args.json else None  # how each looks (JSON only)
    start, done, digital = time.monotonic(), 0, []

    def show(p) -> None:
        nonlocal done
        if printer is not None and not digital:
            digital.append(p)  # shown with its print, which comes next
            return
        done += 1
        record = loaded.pop(p.source, None)
        if record and record.tile and record.tile.notes():  # a small or seamed patch: out of domain, and why
            p = dataclasses.replace(p, in_domain=False, domain_notes=[*p.domain_notes, *record.tile.notes()])
        show_notes(args, record.lines(tile=False) if record else [])
        loaded_json = {"readings": [record.as_dict()] if record else []}
        if printer is None:
            print(json_text(p.as_dict() | looks.take() | loaded_json) if args.json else prediction_line(p), flush=True)
        else:
            _show_printed(args, digital.pop(), p, pairs.prints.popleft(), loaded_json, looks)
        if reader.total > 1 and not args.quiet and (done % 500 == 0 or done == reader.total):
            log(args, f"predicted {done}/{reader.total} in {time.monotonic() - start:.1f} s")

    options = PredictOptions(centre_mm=args.centre, tile=args.tile, fidelity=args.fidelity, tolerance=args.tolerance,
                             max_std=args.max_std, batch_size=args.batch_size, curved=curved_base(args))
    # each input was checked as it was loaded (surface.loading; the reader skips those that fail)
    named = reader.named() if pairs is None else pairs.named()
    predictions(named if looks is None else looks.named(named), args.engine, model, options, on_result=show)
    for source, error in reader.errors:
        message = error_message(error, args.flags)
        print(f"roughness: error: {message}", file=sys.stderr)
        if args.json:
            print(json_text({"input": source, "error": message}))
    return 2 if reader.errors else 0


def _predict_map(args: argparse.Namespace, model, printer) -> int:
    """--map: V of every footprint position over the heightmap, or over its print when there is a printer
    (--printer, else the project's default)."""
    from roughness.core.errors import InputError
    from roughness.maps import predict_map
    from roughness.surface.printing import printed
    from roughness.surrogate.roughness_map import save_map

    if len(args.inputs) != 1 or os.path.isdir(args.inputs[0]):
        raise InputError("--map takes exactly one heightmap file")
    if args.engine == "fem":
        raise InputError("--map needs thousands of footprints: use --engine spectral (one solve over the whole map, "
                         "or overlapping windows of a larger one), surrogate or auto")
    hm = load_input(args, args.inputs[0])
    print_notes = []
    if printer is not None:  # the map of the plate as printed: the print made once, then mapped as any heightmap
        made_print = printed(hm, printer, args.tile)
        hm = made_print.heightmap
        print_notes = [f"mapped as printed by {printer.describe()} (the digital heightmap is not mapped; "
                       "--printer none maps it)", *(f"print: {step}" for step in made_print.steps),
                       *made_print.notes]
    start = last = time.perf_counter()

    def progress(done: int, total: int) -> None:
        nonlocal last
        now = time.perf_counter()
        if done == total or now - last >= MAP_PROGRESS_SECONDS:
            last = now
            eta = (now - start) / done * (total - done)
            log(args, f"map: {done:,}/{total:,} footprint positions, {now - start:.0f} s, ETA {eta:.0f} s")

    made = predict_map(hm, args.engine, args.step_mm, args.tile, model, args.batch_size, progress=progress,
                       workers=args.workers, scheduler=args.scheduler, scheduler_file=args.scheduler_file,
                       quiet=args.quiet, units_ok=True)  # units checked as the file was loaded (--units-ok)
    result, notes, provenance = made.map, [*print_notes, *made.notes], made.provenance
    save_map(result, args.map, args.overwrite)
    summary = {"input": args.inputs[0], "map": args.map, "engine": args.engine,
               "printer": printer.as_dict() if printer is not None else None, **result.summary(), "notes": notes,
               "seconds": time.perf_counter() - start, "readings": readings(args), "provenance": provenance.as_dict()}
    print(json_text(summary) if args.json else
          f"{args.inputs[0]}: {summary['positions']} footprint positions, V {summary['roughness_min']:.4f} to "
          f"{summary['roughness_max']:.4f} (median {summary['roughness_median']:.4f}), "
          f"{100 * summary['in_domain_fraction']:.0f}% in domain, {summary['seconds']:.2f} s; map written to {args.map}"
          + "".join(f"\n  note: {note}" for note in notes))
    return 0


def _show_printed(args: argparse.Namespace, digital, printed, result, readings: dict, looks) -> None:
    """One input's prediction for its print, with the digital texture's and the difference between them
    (``readings``: what loading did to the input, and ``looks``: how the digital texture and its print look, for the
    JSON)."""
    from .printer import PrintDifference

    diff = PrintDifference(digital.roughness, printed.roughness, digital.placement.equivalent_lambda_mm,
                           printed.placement.equivalent_lambda_mm)
    notes = list(result.notes)
    if digital.engine != printed.engine:
        notes.append(f"the digital texture was answered by the {digital.engine}, the print by the {printed.engine}: "
                     "each is placed on its own engine's standard scale")
    if args.json:
        digital_look = looks.take()
        print(json_text({**printed.as_dict(), **looks.take(), "printer": result.profile.as_dict(),
                         "print_steps": list(result.steps), "print_notes": notes, "print_difference": diff.as_dict(),
                         "digital": digital.as_dict() | digital_look, **readings}),
              flush=True)
        return
    lines = [prediction_line(printed).replace(": V = ", " as printed: V = ", 1),
             f"  printer {result.profile.describe()}: {diff.describe()}",
             *(f"  print: {step}" for step in result.steps), *(f"  note: {note}" for note in notes)]
    print("\n".join(lines), flush=True)


def prediction_line(p) -> str:
    from roughness.prediction import domain_words

    where = p.placement
    jnd = None if where.jnd_from_nearest is None else round(where.jnd_from_nearest, 1) + 0.0  # no "-0.0"
    scale = (f"below the standard scale (V < floor {where.floor:.4f}, the scale's finest bumps): no equivalent "
             "lambda" if where.below_scale else
             f"~ lambda {where.equivalent_lambda_mm:.3f} mm on the standard scale, {jnd:+.1f} JND "
             f"from {where.nearest_standard}" if where.on_scale else
             f"off the standard scale: ~ lambda {where.equivalent_lambda_mm:.3f} mm extrapolated by the scale's power "
             f"law, {jnd:+.1f} JND from {where.nearest_standard}")
    domain = domain_words(p)
    corrected = [n for n in p.domain_notes if n.startswith("curved base (")]  # the curvature correction applied
    uncertain = [n for n in p.domain_notes if n not in corrected]
    if p.in_domain and uncertain:  # an ensemble's answer above the spread limit (auto would run the FEM)
        domain += " but " + "; ".join(uncertain)
    if p.in_domain and corrected:
        domain += "; " + "; ".join(corrected)
    sure = f" ± {p.roughness_stderr:.4f} (Monte Carlo)" if p.roughness_stderr is not None else ""  # FEM only
    sure += f" ± {p.roughness_std:.4f} (ensemble spread)" if p.roughness_std is not None else ""
    if p.curvature_error is not None:
        sure += f" ± {p.curvature_error:.4f} (curvature correction)"
    if p.discretization_error is not None:
        sure += f" ± {p.discretization_error * abs(p.roughness):.4f} (discretization)"
    return f"{p.source}: V = {p.roughness:.4f}{sure} ({p.engine}, {domain}, {1e3 * p.seconds:.1f} ms), {scale}"
