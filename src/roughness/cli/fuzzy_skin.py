"""`roughness fuzzy-skin`: how a slicer's fuzzy skin will feel on a printed wall (roughness.fuzzy_feel)."""
from __future__ import annotations

import argparse

from .common import (
    JND,
    LENGTH,
    MAX_PALETTE,
    PIXEL,
    SEED,
    WAVELENGTH,
    Number,
    add_overwrite,
    add_quiet,
    count,
    defaults,
    finish,
    json_text,
    write_stdout,
)
from .fuzzy_skin_tune import check_tune, run_palette, run_tune
from .perception_common import number_list
from .simulate import SIGNED_RADIUS

MAX_DRAWS = 100


def add_parser(sub) -> None:
    from roughness.core.limits import MAX_JND
    from roughness.design.tune import TOLERANCE_JND
    from roughness.fuzzy_feel import fuzzy_skin_feel
    from roughness.fuzzy_palette import fuzzy_palette
    from roughness.fuzzy_tune import DRAWS, KNOB_RANGE, KNOBS
    from roughness.prediction import PREDICT_ENGINES
    from roughness.surface.fuzzy_noise import NOISE_TYPES
    from roughness.surface.fuzzy_skin import MODES, RANGES, FuzzySkin, fuzzy_wall

    skin, wall, feel = defaults(FuzzySkin), defaults(fuzzy_wall), defaults(fuzzy_skin_feel)
    palette = defaults(fuzzy_palette)
    domain = {name: Number(float, low=low, high=high) for name, (low, high) in RANGES.items()}
    lengths = number_list(LENGTH, "lengths in mm")
    p = sub.add_parser("fuzzy-skin", help="how a slicer's fuzzy skin will feel on a printed wall")
    p.add_argument("--config", metavar="FILE",
                   help="read the fuzzy skin and layer/nozzle settings from a PrusaSlicer .ini or OrcaSlicer .json "
                        "export (options given on the command line override its fuzzy skin settings)")
    lengths = number_list(LENGTH, "lengths in mm")
    p.add_argument("--fuzzy-skin-thickness", type=domain["fuzzy_skin_thickness"], metavar="MM",
                   help=f"largest offset of a point, both ways, mm (default {skin['fuzzy_skin_thickness']:g})")
    p.add_argument("--fuzzy-skin-point-distance", type=domain["fuzzy_skin_point_distance"], metavar="MM",
                   help="mean distance of the fuzzy points along the wall, mm; PrusaSlicer's fuzzy_skin_point_dist "
                        f"(default {skin['fuzzy_skin_point_distance']:g})")
    p.add_argument("--fuzzy-skin-noise-type", choices=NOISE_TYPES,
                   help=f"OrcaSlicer's noise (default {skin['fuzzy_skin_noise_type']})")
    p.add_argument("--fuzzy-skin-scale", type=domain["fuzzy_skin_scale"], metavar="MM",
                   help=f"feature size of the coherent noises, mm (default {skin['fuzzy_skin_scale']:g})")
    p.add_argument("--fuzzy-skin-octaves", type=count(*RANGES["fuzzy_skin_octaves"][::-1]), metavar="N",
                   help=f"octaves of perlin, billow, ridgedmulti (default {skin['fuzzy_skin_octaves']})")
    p.add_argument("--fuzzy-skin-persistence", type=domain["fuzzy_skin_persistence"], metavar="P",
                   help=f"persistence of perlin and billow (default {skin['fuzzy_skin_persistence']:g})")
    p.add_argument("--fuzzy-skin-mode", choices=MODES,
                   help=f"OrcaSlicer's fuzzy_skin_mode (default {skin['fuzzy_skin_mode']})")
    p.add_argument("--printer", metavar="NAME|FILE", default=None,
                   help="FDM printer profile (layer height, line width) or a JSON profile file (default: the "
                        "--config's, else fdm-0.4-0.2)")
    p.add_argument("--engine", choices=PREDICT_ENGINES, default="auto",
                   help="surrogate, spectral, fem, or auto (the surrogate, climbing where it is unsure) (default auto)")
    p.add_argument("--seed", type=SEED, default=wall["seed"],
                   help=f"seed of the slicer's random numbers (the slicers draw new ones at every slice) "
                        f"(default {wall['seed']})")
    p.add_argument("--draws", type=count(MAX_DRAWS),
                   help="walls judged per setting, each with its own random numbers (seeds --seed, --seed + 1, "
                        f"...): V is their mean, sure to their spread (default {feel['draws']}; {DRAWS} with --tune or --palette)")
    p.add_argument("--tile-mm", type=LENGTH, default=wall["tile_mm"],
                   help=f"side of the periodic wall tile, mm (default {wall['tile_mm']:g})")
    p.add_argument("--pixel-mm", type=PIXEL, default=wall["pixel_mm"],
                   help=f"pixel size, mm, at most half the layer height (default {wall['pixel_mm']:g})")
    p.add_argument("--radius-mm", type=SIGNED_RADIUS, metavar="MM",
                   help="the wall is a cylinder of this radius (a round grip or knob; > 0 convex, < 0 concave, mm): "
                        "the flat wall's V corrected as predict --curvature-mm corrects it, the correction's error "
                        "added to V's uncertainty (default: a flat wall)")
    p.add_argument("--sweep-thickness", type=lengths, metavar="MM,MM,...",
                   help="a table over these thicknesses (with --sweep-point-distance, or the one point distance)")
    p.add_argument("--sweep-point-distance", type=lengths, metavar="MM,MM,...",
                   help="a table over these point distances (with --sweep-thickness, or the one thickness)")
    p.add_argument("--plot", metavar="FILE",
                   help="with a sweep: V against point distance, a line per thickness (.png, .pdf, .svg)")
    p.add_argument("--out", metavar="FILE", help="write the printed wall's heightmap (.npz, .npy, .h5, .png, .tif; with "
                                                 "--tune: the tuned setting's)")
    p.add_argument("--tune", choices=tuple(KNOBS),
                   help="find the value of this setting (the others fixed) whose walls reach --target-lambda or "
                        "--target-jnd, searched and verified by the spectral engine over --draws walls")
    target = p.add_mutually_exclusive_group()
    target.add_argument("--target-lambda", type=WAVELENGTH, metavar="MM",
                        help="--tune: the target equivalent wavelength on the spectral standard scale, mm")
    target.add_argument("--target-jnd", type=Number(float, low=-MAX_JND, high=MAX_JND), metavar="N",
                        help="--tune: the target N JND from the given settings (positive: rougher)")
    p.add_argument("--tune-range", type=lengths, metavar="MM,MM",
                   help="--tune, --palette: the smallest and largest value searched, mm (default "
                        + "; ".join(f"{k} {lo:g},{hi:g}" for k, (lo, hi) in KNOB_RANGE.items()) + ")")
    p.add_argument("--palette", type=count(MAX_PALETTE, 2), metavar="K",
                   help="K settings of the --tune setting (default thickness) that feel clearly different, at least "
                        "--min-jnd apart, spread over its range, verified by the spectral engine over --draws walls")
    p.add_argument("--min-jnd", type=JND, default=palette["min_jnd"], metavar="N",
                   help=f"--palette: the least distance between any two settings, JND (default {palette['min_jnd']:g})")
    p.add_argument("--tolerance-jnd", type=JND, default=TOLERANCE_JND, metavar="N",
                   help="--tune, --palette: stop when the verified mean is this close to the target, JND (default "
                        f"{TOLERANCE_JND:g})")
    p.add_argument("--json", action="store_true", help="print the results as JSON, one line per setting")
    add_quiet(p)
    add_overwrite(p)
    finish(p, run, target_lambda_mm="--target-lambda", target_jnd="--target-jnd", jnd="--target-jnd",
           tune_range="--tune-range", k="--palette")


def _settings(args: argparse.Namespace):
    """The fuzzy skin, printer and notes of --config, the options and --printer."""
    from dataclasses import fields, replace

    from roughness.surface.fuzzy_skin import FuzzySkin
    from roughness.surface.printing import printer_profile
    from roughness.surface.slicer_config import read_slicer_config

    skin, profile, notes = FuzzySkin(), printer_profile("fdm-0.4-0.2"), ()
    if args.config:
        read = read_slicer_config(args.config)
        skin, profile, notes = read.skin, read.profile, read.notes
    given = {f.name: getattr(args, f.name) for f in fields(FuzzySkin) if getattr(args, f.name) is not None}
    skin = replace(skin, **given)
    if args.printer:
        profile = printer_profile(args.printer)
    return skin, profile, notes


def _line(feel) -> str:
    """A setting's V with its uncertainty and its place on the standard scale."""
    spread = feel.draw_std
    sure = [f"{spread:.4f} over {len(feel.predictions)} draws"] if spread is not None else []
    if feel.engine_error is not None:
        sure.append(f"{feel.engine_error:.4f} engine")
    where = feel.placement
    if where is None:
        scale = f"answered by different engines ({', '.join(feel.engines)}): not placed on one standard scale"
    elif where.below_scale:
        scale = f"below the standard scale (V < floor {where.floor:.4f}): no equivalent lambda"
    else:
        extrapolated = "" if where.on_scale else " (extrapolated off the scale)"
        low, high = feel.lambda_range_mm or (where.equivalent_lambda_mm, where.equivalent_lambda_mm)
        scale = (f"~ lambda {where.equivalent_lambda_mm:.3f} mm ({low:.3f}-{high:.3f}){extrapolated}, "
                 f"{where.jnd_from_nearest + 0.0:+.1f} JND from {where.nearest_standard}")
    said = sorted({n for p in feel.predictions for n in p.domain_notes})
    if feel.curvature is not None:
        sure.append(f"{feel.curvature_error:.4f} curvature")
        said.append(f"{feel.curvature.note}; the flat wall's V {feel.roughness / feel.factor:.4f}")
    notes = "".join(f"\n  note: {n}" for n in said)
    engines = ", ".join(sorted({p.engine for p in feel.predictions}))
    return (f"{feel.skin.describe()}: V = {feel.roughness:.4f} ± {' ± '.join(sure) or 'unknown'} "
            f"({engines}; {', '.join(feel.engines)} scale), {scale}{notes}")


def run(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct, check_output
    from roughness.fuzzy_feel import fuzzy_skin_feel, fuzzy_skin_sweep
    from roughness.objects.progress import StageMeter
    from roughness.surface.io import save_heightmap

    check_distinct({"--out": args.out, "--plot": args.plot}, {"--config": args.config, "--printer": args.printer})
    check_tune(args)
    skin, profile, notes = _settings(args)
    out = check_output(args.out, args.overwrite, "out") if args.out else None
    sweep = args.sweep_thickness or args.sweep_point_distance
    plot = check_output(args.plot, args.overwrite, "plot") if args.plot else None
    if plot is not None and (not sweep or plot.suffix.lower() not in (".png", ".pdf", ".svg")):
        raise InputError("--plot draws a sweep (--sweep-thickness/--sweep-point-distance) to a .png, .pdf or .svg",
                         "plot")
    if sweep and out is not None:
        raise InputError("--out writes one wall: leave out --sweep-thickness/--sweep-point-distance", "out")
    header = [f"printer {profile.describe()}; the wall judged flat, as a periodic {args.tile_mm:g} mm tile "
              f"(seeds from {args.seed}: draws of the slicer's random numbers)", *(f"note: {n}" for n in notes)]
    if args.palette:
        return run_palette(args, skin, profile, header)
    if args.tune:
        return run_tune(args, skin, profile, header, out)
    draws = args.draws or defaults(fuzzy_skin_feel)["draws"]
    if not sweep:
        feel = fuzzy_skin_feel(skin, profile, args.engine, args.seed, draws, args.tile_mm, args.pixel_mm,
                               args.radius_mm)
        if out is not None:
            save_heightmap(feel.walls[0].heightmap, out, overwrite=args.overwrite)
            header.append(f"wrote {out}: the printed wall of seed {args.seed}, x along it, y up it, heights out of it (mm)")
        write_stdout(json_text(feel.as_dict()) if args.json else "\n".join([*header, _line(feel)]))
        return 0
    thicknesses = args.sweep_thickness or (skin.fuzzy_skin_thickness,)
    distances = args.sweep_point_distance or (skin.fuzzy_skin_point_distance,)
    total = len(thicknesses) * len(distances)
    meter = None if args.quiet else StageMeter()
    report = None if meter is None else meter.stage(f"{total} fuzzy skin settings")
    done = []

    def step(feel) -> None:
        done.append(feel)
        if report is not None:
            report(len(done) / total)

    feels = fuzzy_skin_sweep(skin, thicknesses, distances, profile, args.engine, args.seed, draws,
                             args.tile_mm, args.pixel_mm, args.radius_mm, on_result=step)
    if meter is not None:
        meter.close()
    if plot is not None:
        from roughness.fuzzy_feel import plot_sweep

        plot_sweep(feels, plot)
        header.append(f"wrote {plot}")
    if args.json:
        write_stdout("\n".join(json_text(f.as_dict()) for f in feels))
    else:
        write_stdout("\n".join([*header, *(_line(f) for f in feels)]))
    return 0
