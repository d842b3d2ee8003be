"""The ``roughness`` command line."""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

COMPARE_ENGINES = ("fem:coarse", "fem:default", "surrogate", "ra", "p90", "glcm_sum_of_squares", "glcm_sum_variance")


def _float_pair(text: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y in mm, got {text!r}") from None
    return x, y


def _add_heightmap_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("heightmap", help="heightmap file: .npy (mm), 8/16-bit .png/.tif, .h5")
    p.add_argument("--pixel-mm", type=float, help="pixel size in mm (required unless the file states it)")
    p.add_argument("--height-mm", type=float, help="height of full-scale white in mm (PNG/TIFF)")
    p.add_argument("--tile", action="store_true", help="repeat a small heightmap as a periodic texture")
    p.add_argument("--centre", type=_float_pair, metavar="X,Y", help="footprint centre in mm (default: map centre)")


def build_parser() -> argparse.ArgumentParser:
    from simulate.config import BONE_MODELS, CONTACT_MODES, ELEMENTS, FIDELITIES

    parser = argparse.ArgumentParser(prog="roughness", description=__doc__)
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("simulate", help="FEM roughness of a heightmap (reference engine)")
    _add_heightmap_args(sim)
    sim.add_argument("--fidelity", choices=FIDELITIES, default="default",
                     help="mesh resolution: coarse 0.3 mm, default 0.2 mm, fine 0.14 mm, auto from feature size")
    sim.add_argument("--force", type=float, default=10.0, help="normal force in N (default 10)")
    sim.add_argument("--poisson", type=float, default=0.45, help="tissue Poisson ratio (default 0.45)")
    sim.add_argument("--contact", choices=CONTACT_MODES, default="stick")
    sim.add_argument("--element", choices=ELEMENTS, default="p1", help="p2 for Poisson ratio close to 0.5")
    sim.add_argument("--bone", choices=BONE_MODELS, default="rigid")
    sim.add_argument("--seed", type=int, default=0, help="seed of the disk-pair sampling")
    sim.add_argument("--json", action="store_true", help="print one JSON object")
    sim.add_argument("--save-strain", metavar="PNG", help="image of the strain map at receptor depth")
    sim.add_argument("--save-vtu", metavar="FILE", help="deformed mesh with strain for ParaView")
    sim.add_argument("--quiet", action="store_true", help="no progress messages on stderr")
    sim.set_defaults(run=_simulate)

    tex = sub.add_parser("texture", help="make textures: standard bumps, flat tops, natural families")
    tex_sub = tex.add_subparsers(dest="texture_command", required=True)
    make = tex_sub.add_parser("make", help="write a texture heightmap (.npy in mm, 16-bit .png, float .tif)")
    make.add_argument("name", help="standard-<lambda>, flattop-<d>, flat, bumps, or a family (roughness texture list)")
    make.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="family parameter")
    make.add_argument("--seed", type=int, default=0)
    make.add_argument("--size-mm", type=float, default=12.0, help="side of the square map (mm)")
    make.add_argument("--pixel-mm", type=float, default=0.05, help="pixel size (mm)")
    make.add_argument("--height-mm", type=float, help="PNG only: height of full-scale white (default: the range)")
    make.add_argument("--out", required=True, help="output file (.npy, .png, .tif)")
    make.set_defaults(run=_texture_make)
    listing = tex_sub.add_parser("list", help="texture names, families and their parameter ranges")
    listing.set_defaults(run=_texture_list)

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
    b.set_defaults(run=_dataset_build)
    i = data_sub.add_parser("info", help="counts by family, value ranges, failures")
    i.add_argument("file")
    i.add_argument("--json", action="store_true")
    i.set_defaults(run=_dataset_info)
    v = data_sub.add_parser("verify", help="check schema, ids and finite values; exit 1 if anything is wrong")
    v.add_argument("file")
    v.set_defaults(run=_dataset_verify)
    tr = sub.add_parser("train", help="train the CNN surrogate on a dataset file (CPU, needs torch)")
    tr.add_argument("data", help="HDF5 dataset from `roughness dataset build`")
    tr.add_argument("--out", required=True, help="folder for checkpoint.pt, metrics.json, history.csv")
    tr.add_argument("--seed", type=int, default=0)
    tr.add_argument("--holdout-family", help="family never trained on, scored as out-of-family (default: the "
                    "dataset recipe's; 'none' to train on all)")
    tr.add_argument("--max-epochs", type=int, default=200)
    tr.add_argument("--max-minutes", type=float, default=25.0, help="wall-clock budget for the epochs")
    tr.add_argument("--threads", type=int, default=2, help="torch threads")
    tr.set_defaults(run=_train)
    ex = sub.add_parser("export", help="export a training checkpoint to ONNX, checked against PyTorch")
    ex.add_argument("checkpoint")
    ex.add_argument("--out", required=True, help="ONNX file to write")
    ex.add_argument("--int8", metavar="FILE", help="also write an int8 model (static QDQ, per-channel weights)")
    ex.set_defaults(run=_export)

    pr = sub.add_parser("predict", help="roughness in milliseconds (surrogate), FEM where out of domain")
    pr.add_argument("inputs", nargs="+", metavar="HEIGHTMAP",
                    help="heightmap files, folders of them, or roughness dataset files (.h5)")
    pr.add_argument("--model", help="ONNX surrogate (default: the shipped model)")
    pr.add_argument("--engine", choices=("surrogate", "fem", "auto"), default="auto",
                    help="auto (default): surrogate, FEM for inputs outside its domain")
    pr.add_argument("--fidelity", choices=("coarse", "default"),
                    help="FEM fidelity (default: that of the model's training labels; the standard scale "
                         "is tabulated for these two)")
    pr.add_argument("--pixel-mm", type=float, help="pixel size in mm (required unless the file states it)")
    pr.add_argument("--height-mm", type=float, help="height of full-scale white in mm (PNG/TIFF)")
    pr.add_argument("--tile", action="store_true", help="repeat small heightmaps as periodic textures")
    pr.add_argument("--centre", type=_float_pair, metavar="X,Y", help="footprint centre in mm (default: map centre)")
    pr.add_argument("--batch-size", type=int, default=256)
    pr.add_argument("--threads", type=int, default=1, help="onnxruntime threads (default 1)")
    pr.add_argument("--json", action="store_true", help="one JSON object per input and line")
    pr.add_argument("--map", metavar="FILE", help="roughness map of a whole object (one input): the footprint slid "
                    "over the map, saved as .png (figure) or .npy (V per position)")
    pr.add_argument("--step-mm", type=float, default=1.0, help="--map: distance between footprint positions (mm)")
    pr.add_argument("--quiet", action="store_true", help="no progress messages on stderr")
    pr.set_defaults(run=_predict)
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
    cmp.set_defaults(run=_compare)
    return parser


def _version() -> str:
    from roughness import __version__

    return f"roughness {__version__}"


def _log(args: argparse.Namespace, message: str) -> None:
    if not getattr(args, "quiet", False):
        print(message, file=sys.stderr, flush=True)


def _simulate(args: argparse.Namespace) -> int:
    from simulate.io import load_heightmap
    from simulate.model import Simulator
    from simulate.config import SimConfig

    hm = load_heightmap(args.heightmap, pixel_mm=args.pixel_mm, height_mm=args.height_mm)
    config = SimConfig(fidelity=args.fidelity, force_n=args.force, poisson=args.poisson, contact=args.contact,
                       element=args.element, bone=args.bone, seed=args.seed)
    for path in (args.save_strain, args.save_vtu):
        if path and not os.path.isdir(os.path.dirname(os.path.abspath(path))):
            from simulate.heightmap import InputError

            raise InputError(f"cannot write {path}: its folder does not exist")
    _log(args, f"{args.heightmap}: {hm.shape[1]} x {hm.shape[0]} px of {hm.pixel_mm} mm; "
               f"{config.resolved(hm).fidelity} fidelity, contact spacing {config.spacing_mm(hm)} mm; "
               "preparing the skin block (cached after the first run) ...")
    sim = Simulator(config)
    result = sim.run(hm, centre_mm=args.centre, tile=args.tile)
    if args.save_strain:
        from simulate.output import save_strain_png

        save_strain_png(result, args.save_strain)
        _log(args, f"strain map written to {args.save_strain}")
    if args.save_vtu:
        from simulate.output import save_vtu

        save_vtu(result, sim.block(result.config), args.save_vtu)
        _log(args, f"deformed mesh written to {args.save_vtu}")
    if args.json:
        print(json.dumps({"input": args.heightmap, **result.summary()}))
    else:
        _print_result(result)
    for w in result.warnings:
        _log(args, f"note: {w}")
    return 0


def _texture_make(args: argparse.Namespace) -> int:
    from dataset.catalogue import make_texture, parse_params
    from simulate.io import save_heightmap

    hm, recipe = make_texture(args.name, seed=args.seed, size_mm=args.size_mm, pixel_mm=args.pixel_mm,
                              params=parse_params(args.param))
    save_heightmap(hm, args.out, height_mm=args.height_mm)
    ny, nx = hm.shape
    full = args.height_mm if args.height_mm is not None else float(hm.heights.max() - hm.heights.min())
    note = f"; full-scale white = {full:.4g} mm (pass --height-mm {full:.4g} when loading)" \
        if args.out.lower().endswith(".png") else ""
    print(f"wrote {args.out}: {nx} x {ny} px of {hm.pixel_mm} mm, heights {hm.heights.min():.3f} to "
          f"{hm.heights.max():.3f} mm{note}")
    print(json.dumps(recipe))
    return 0


def _texture_list(args: argparse.Namespace) -> int:
    from dataset.natural import PARAMETER_RANGES
    from dataset.textures import texture_names

    print("named: " + ", ".join(texture_names()))
    print("bumps: --param lambda_mm=... [top=cap|flat] [top_diameter_mm=] [height_mm=] [base_diameter_mm=]")
    for family, ranges in PARAMETER_RANGES.items():
        print(f"{family}: " + ", ".join(f"{k} {v[0]}..{v[1]}" if isinstance(v[0], float) else f"{k} {'|'.join(v)}"
                                        for k, v in ranges.items()))
    return 0


def _dataset_build(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from dataset.build import build
    from dataset.recipe import Recipe, load_recipe
    from simulate.config import SimConfig

    _at_least_one("--workers", args.workers)
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


def _dataset_info(args: argparse.Namespace) -> int:
    from dataset.store import info

    summary = info(args.file)
    print(json.dumps(summary, indent=None if args.json else 1, default=str))
    return 0


def _dataset_verify(args: argparse.Namespace) -> int:
    from dataset.store import verify

    problems = verify(args.file)
    for p in problems:
        print(f"problem: {p}")
    print(f"{args.file}: {'OK' if not problems else f'{len(problems)} problem(s)'}")
    return 1 if problems else 0


def _train(args: argparse.Namespace) -> int:
    from simulate.heightmap import InputError

    _require_torch("train")
    from surrogate.train import TrainConfig, train

    if not os.path.isfile(args.data):
        raise InputError(f"dataset file not found: {args.data}")
    _at_least_one("--max-epochs", args.max_epochs)
    _at_least_one("--threads", args.threads)
    train(TrainConfig(data=args.data, out=args.out, seed=args.seed, holdout_family=args.holdout_family,
                      max_epochs=args.max_epochs, max_minutes=args.max_minutes, threads=args.threads))
    return 0


def _export(args: argparse.Namespace) -> int:
    from simulate.heightmap import InputError

    _require_torch("export")
    from surrogate.export import ExportError, export

    try:
        report = export(args.checkpoint, args.out)
    except ValueError as err:
        raise InputError(str(err)) from None
    except ExportError as err:
        print(f"roughness: export check failed, nothing written: {err}", file=sys.stderr)
        return 1
    print(json.dumps(report))
    if args.int8:
        from surrogate.quantize import QuantizationError, quantize

        try:
            print(json.dumps(quantize(args.out, args.int8)))
        except QuantizationError as err:
            print(f"roughness: int8 check failed, {args.int8} not written: {err}", file=sys.stderr)
            return 1
    return 0


def _require_torch(command: str) -> None:
    from importlib.util import find_spec

    from simulate.heightmap import InputError

    if find_spec("torch") is None or find_spec("onnx") is None:
        raise InputError(f"`roughness {command}` needs PyTorch and onnx: pip install \".[train]\" "
                         "(torch==2.13.0 is the CPU build)")


def _predict(args: argparse.Namespace) -> int:
    from surrogate.inputs import InputReader
    from surrogate.predictor import SurrogateModel, predict

    model = SurrogateModel(args.model or _default_model(), threads=_at_least_one("--threads", args.threads))
    if args.map:
        return _predict_map(args, model)
    reader = InputReader(args.inputs, args.pixel_mm, args.height_mm, model.footprint_mm, args.centre, args.tile)
    start, done = time.monotonic(), 0

    def show(p) -> None:
        nonlocal done
        done += 1
        print(json.dumps(p.as_dict()) if args.json else _prediction_line(p), flush=True)
        if reader.total > 1 and not args.quiet and (done % 500 == 0 or done == reader.total):
            _log(args, f"predicted {done}/{reader.total} in {time.monotonic() - start:.1f} s")

    predict(reader.heightmaps(), engine=args.engine, model=model, centre_mm=args.centre, tile=args.tile,
            fidelity=args.fidelity, batch_size=_at_least_one("--batch-size", args.batch_size),
            sources=reader.sources(), on_result=show)
    for source, error in reader.errors:
        print(f"roughness: error: {error}", file=sys.stderr)
        if args.json:
            print(json.dumps({"input": source, "error": error}))
    return 2 if reader.errors else 0


def _predict_map(args: argparse.Namespace, model) -> int:
    from simulate.heightmap import InputError
    from simulate.io import load_heightmap
    from surrogate.roughness_map import roughness_map, save_map

    if len(args.inputs) != 1 or os.path.isdir(args.inputs[0]):
        raise InputError("--map takes exactly one heightmap file")
    if args.engine == "fem":
        raise InputError("--map runs the surrogate (thousands of footprints); use --engine surrogate or auto")
    hm = load_heightmap(args.inputs[0], args.pixel_mm, args.height_mm)
    start = time.perf_counter()
    result = roughness_map(model, hm, args.step_mm, args.tile, _at_least_one("--batch-size", args.batch_size))
    save_map(result, args.map)
    summary = {"input": args.inputs[0], "map": args.map, **result.summary(), "seconds": time.perf_counter() - start}
    print(json.dumps(summary) if args.json else
          f"{args.inputs[0]}: {summary['positions']} footprint positions, V {summary['roughness_min']:.4f} to "
          f"{summary['roughness_max']:.4f} (median {summary['roughness_median']:.4f}), "
          f"{100 * summary['in_domain_fraction']:.0f}% in domain, {summary['seconds']:.2f} s; map written to {args.map}")
    return 0


def _default_model() -> str:
    from surrogate.predictor import DEFAULT_MODEL

    return str(DEFAULT_MODEL)


def _at_least_one(flag: str, value: int) -> int:
    from simulate.heightmap import InputError

    if value < 1:
        raise InputError(f"{flag} must be at least 1, got {value}")
    return value


def _prediction_line(p) -> str:
    where = p.placement
    scale = (f"~ lambda {where.equivalent_lambda_mm:.3f} mm on the standard scale, {where.jnd_from_nearest:+.1f} JND "
             f"from {where.nearest_standard}" if where.on_scale else
             f"off the standard scale ({where.jnd_from_nearest:+.1f} JND from {where.nearest_standard})")
    domain = "in domain" if p.in_domain else "OUT OF DOMAIN: " + "; ".join(p.domain_notes)
    return f"{p.source}: V = {p.roughness:.4f} ({p.engine}, {domain}, {1e3 * p.seconds:.1f} ms), {scale}"


def _compare(args: argparse.Namespace) -> int:
    from pathlib import Path

    from roughness.compare import ResultCache, run, textures_of
    from roughness.engines import make_engine
    from roughness.report import write_report

    if args.n is not None:
        _at_least_one("--n", args.n)
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
    _log(args, f"report written to {out / 'report.md'}")
    return 0


def _print_result(r) -> None:
    print(f"roughness V        {r.roughness:.5f} ± {r.roughness_stderr:.5f} (strain variation at "
          f"{r.config.depth_mm} mm depth, d = r = {r.config.pair_distance_mm} mm)")
    print(f"contact fraction   {100 * r.contact_fraction:.1f}%")
    print(f"indentation        {r.indentation_mm:.3f} mm at {r.config.force_n} N")
    if r.converged:
        status = "converged" + (f"; {r.unresolved_nodes} nodes held in contact under slight tension"
                                if r.unresolved_nodes else "")
    else:
        status = f"NOT converged; {r.unresolved_nodes} nodes unresolved"
    print(f"contact rounds     {r.iterations} ({status})")
    print(f"mesh               {r.nodes} nodes, {r.config.element.upper()}, h = {r.config.h_contact_mm} mm")
    print(f"time               {r.seconds:.2f} s")


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from simulate.heightmap import InputError
    from simulate.errors import SimulationError

    try:
        return args.run(args)
    except InputError as err:
        print(f"roughness: error: {err}", file=sys.stderr)
        return 2
    except SimulationError as err:
        print(f"roughness: simulation failed: {err}", file=sys.stderr)
        return 3
    except OSError as err:
        print(f"roughness: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("roughness: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
