"""`roughness fuzzy-skin --tune` and `--palette`: the fuzzy skin setting that reaches a target feel
(roughness.fuzzy_tune), and settings that feel clearly different (roughness.fuzzy_palette)."""
from __future__ import annotations

import argparse

from .common import json_text, log, write_stdout


def check_tune(args: argparse.Namespace) -> None:
    """InputError for options that do not go with --tune or --palette (or need them), before any work."""
    from roughness.core.errors import InputError
    from roughness.fuzzy_tune import ENGINE

    targets = args.target_lambda is not None or args.target_jnd is not None
    if args.palette:
        if targets or args.out:
            raise InputError("--palette spreads its settings over the --tune setting's range: leave out "
                             "--target-lambda/--target-jnd/--out", "palette")
    elif not args.tune:
        if targets or args.tune_range:
            raise InputError("--target-lambda, --target-jnd and --tune-range go with --tune", "tune")
        return
    elif not targets:
        raise InputError("--tune needs a target: --target-lambda MM or --target-jnd N", "tune")
    option = "--palette" if args.palette else "--tune"
    if args.sweep_thickness or args.sweep_point_distance or args.plot:
        raise InputError(f"{option} leaves out --sweep-thickness/--sweep-point-distance/--plot", "tune")
    if args.engine not in ("auto", ENGINE):
        raise InputError(f"{option} searches and verifies with the {ENGINE} engine; leave out --engine {args.engine}",
                         "engine")
    if args.tune_range is not None and len(args.tune_range) != 2:
        raise InputError("--tune-range takes two values, the smallest and largest searched (mm)", "tune_range")
    if args.draws is not None and args.draws < 2:
        raise InputError(f"{option} needs at least 2 --draws: the spread between walls is part of how sure it is",
                         "draws")


def run_tune(args: argparse.Namespace, skin, profile, header: list[str], out) -> int:
    """Tune ``skin``'s --tune setting on ``profile``; print the result (text after ``header``, or JSON); write the
    tuned setting's first wall to ``out`` if given. Exit code 1 if the target was not reached."""
    from roughness.fuzzy_feel import fuzzy_skin_feel
    from roughness.fuzzy_tune import DRAWS, ENGINE, lambda_target, relative_target, tune_fuzzy_skin
    from roughness.surface.io import save_heightmap

    draws = args.draws or DRAWS
    progress = None if args.quiet else (lambda line: log(args, "  " + line))
    if args.target_jnd is not None:
        log(args, f"fuzzy-skin: the given settings by the {ENGINE} engine over {draws} walls")
        given = fuzzy_skin_feel(skin, profile, ENGINE, args.seed, draws, args.tile_mm, args.pixel_mm, args.radius_mm)
        target = relative_target(given, args.target_jnd)
    else:
        target = lambda_target(args.target_lambda)
    log(args, f"fuzzy-skin: target {target.describe()}; searching {args.tune}")
    result = tune_fuzzy_skin(skin, target, args.tune, profile, args.tune_range, args.tolerance_jnd, seed=args.seed,
                             draws=draws, tile_mm=args.tile_mm, pixel_mm=args.pixel_mm, radius_mm=args.radius_mm,
                             progress=progress)
    if out is not None:
        save_heightmap(result.feel.walls[0].heightmap, out, overwrite=args.overwrite)
        header.append(f"wrote {out}: the tuned setting's wall of seed {args.seed}")
    if args.json:
        write_stdout(json_text(result.summary()))
    else:
        write_stdout("\n".join([*header, result.describe(), *(f"note: {n}" for n in result.notes)]))
    return 0 if result.reached else 1


def run_palette(args: argparse.Namespace, skin, profile, header: list[str]) -> int:
    """--palette K settings of the --tune setting (default thickness) of ``skin`` on ``profile``; print them (text
    after ``header``, or JSON). Exit code 1 if the closest pair is nearer than --min-jnd."""
    from roughness.fuzzy_palette import fuzzy_palette
    from roughness.fuzzy_tune import DRAWS

    knob = args.tune or "thickness"
    log(args, f"fuzzy-skin: {args.palette} settings of {knob} at least {args.min_jnd:g} JND apart")
    palette = fuzzy_palette(args.palette, skin, knob, args.min_jnd, profile, args.tune_range, args.tolerance_jnd,
                            args.seed, args.draws or DRAWS, args.tile_mm, args.pixel_mm, args.radius_mm,
                            progress=None if args.quiet else (lambda line: log(args, "  " + line)))
    if args.json:
        write_stdout(json_text(palette.summary()))
    else:
        write_stdout("\n".join([*header, *palette.lines(), *(f"note: {n}" for n in palette.notes)]))
    return 0 if palette.verified else 1
