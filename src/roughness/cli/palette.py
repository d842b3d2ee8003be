"""`roughness palette --k K [--min-jnd M] [--family F | --from FOLDER] --out DIR`: textures a fingertip tells apart."""
from __future__ import annotations

import argparse

from .common import (
    JND,
    LENGTH,
    MAX_PALETTE,
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
from .printer import add_printer_arg, merged, print_report, printer_of


def add_parser(sub) -> None:
    from roughness.design.palette import DEFAULT_FAMILY, family_palette
    from roughness.design.tune import KNOBS
    from roughness.surface.stl import DEFAULT_BASE_MM

    given = defaults(family_palette)
    p = sub.add_parser("palette", help="K textures pairwise at least M JND apart (FEM-verified), with a preview sheet")
    p.add_argument("--k", type=count(MAX_PALETTE), required=True, help="number of textures, >= 2")
    p.add_argument("--min-jnd", type=JND, default=given["min_jnd"],
                   help=f"smallest pairwise distance in JNDs of equivalent wavelength (default {given['min_jnd']:g})")
    source = p.add_mutually_exclusive_group()
    source.add_argument("--family", default=DEFAULT_FAMILY,
                        help="texture to scale into K members: a name or family of `roughness texture list` "
                             f"(default {DEFAULT_FAMILY})")
    source.add_argument("--from", dest="candidates", metavar="FOLDER",
                        help="choose K from the heightmaps in this folder instead")
    p.add_argument("--by", choices=KNOBS, default=given["by"],
                   help=f"--family: scale the heights or the lateral size (default {given['by']})")
    p.add_argument("--seed", type=SEED, default=given["seed"], help="--family: the texture's seed (default 0)")
    p.add_argument("--tolerance-jnd", type=JND, default=given["tolerance_jnd"],
                   help=f"--family: each member within this of its target, FEM (default {given['tolerance_jnd']:g})")
    add_reading_args(p)
    p.add_argument("--tile", action="store_true", help="--from: the heightmaps are periodic tiles")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="new folder: texture-N.npz (mm), palette.json (V, lambda, pairwise JNDs), preview.png")
    p.add_argument("--stl", action="store_true", help="also write each texture as a printable plate texture-N.stl")
    p.add_argument("--base-mm", type=LENGTH,
                   help=f"--stl: plate thickness below the texture's lowest point in mm (default {DEFAULT_BASE_MM:g})")
    add_printer_arg(p, "the textures are chosen and spaced as printed; the files are the digital designs, whose "
                       "own V and the differences in JND are reported")
    add_model_tail(p, "print palette.json's content (default: text)")
    finish(p, run)


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct, check_output_folder
    from roughness.design.evaluation import Evaluator
    from roughness.design.palette import candidate_names, family_palette, folder_palette, save_palette

    check_distinct({"--out": args.out}, {"--from": args.candidates, "--model": args.model, "--printer": args.printer})
    out = check_output_folder(args.out, args.overwrite, "out")
    if args.k < 2:
        raise InputError(f"a palette needs at least 2 textures, got {args.k}", "k")
    if args.base_mm is not None and not args.stl:
        raise InputError("applies only with --stl", "base_mm")
    evaluator = Evaluator(args.model, args.verify, printer=printer_of(args))

    def progress(line: str) -> None:
        log(args, "  " + line)

    if args.candidates:
        from roughness.surface.io import heightmap_files

        files = heightmap_files(args.candidates)
        candidates = [(name, load_input(args, str(f), several=True))
                      for name, f in zip(candidate_names(files), files)]
        printing = merged([print_report(evaluator, hm, args.tile) for _, hm in candidates])  # each refused now if
        # the printer cannot print it at its pixel size
        log(args, f"palette: choosing {args.k} of {len(candidates)} textures, {args.min_jnd:g} JND apart")
        palette = folder_palette(candidates, args.k, args.min_jnd, evaluator, args.tile, progress)
    else:
        from roughness.dataset.catalogue import make_texture

        printing = print_report(evaluator, make_texture(args.family, seed=args.seed)[0], False) \
            if evaluator.printer else None
        log(args, f"palette: {args.k} variants of {args.family} by {args.by}, {args.min_jnd:g} JND apart")
        palette = family_palette(args.k, args.min_jnd, args.family, args.by, evaluator, args.tolerance_jnd,
                                 seed=args.seed, progress=progress)
    if printing:
        for m in palette.members:
            printing.verify(m.heightmap, m.fem.roughness, args.tile and bool(args.candidates), m.name)
        palette = replace(palette, printing=printing.as_dict())
    palette = replace(palette, provenance=evaluator.provenance)
    if palette.verified:  # an unverified palette is no result: nothing is written that tactile-image could take
        save_palette(palette, out, args.stl, args.base_mm, args.overwrite)
    summary = {**palette.summary(), "verifier": evaluator.verifier, "readings": readings(args),
               "written": str(out) if palette.verified else None}
    if args.json:
        write_stdout(json_text(summary))
    else:
        lines = [f"{m.name}: V {m.fem.roughness:.4f} ± {m.fem.roughness_stderr:.4f} ({evaluator.verifier}), lambda "
                 f"{m.fem.equivalent_lambda_mm:.3f} mm" + ("" if m.fem.on_scale else " (extrapolated off the scale)")
                 for m in palette.members]
        lines.append(f"closest pair {palette.closest_jnd:.2f} JND ({evaluator.verifier}): "
                     + (f"VERIFIED >= {args.min_jnd:g} JND; written to {out}" if palette.verified else
                        f"NOT VERIFIED >= {args.min_jnd:g} JND; nothing written (ask for fewer textures or a smaller "
                        "--min-jnd)"))
        lines += _look_lines(palette) + [f"note: {n}" for n in palette.notes]
        write_stdout("\n".join(lines + (printing.lines() if printing else [])))
    return 0 if palette.verified else 1


def _look_lines(palette) -> list[str]:
    """How alike the members look (design.look), beside how far apart they feel: the pair most alike in look."""
    import numpy as np

    look = np.maximum(palette.look_differences, palette.look_differences.T)
    if len(look) < 2:
        return []
    i, j = np.unravel_index(np.argmin(look + np.diag([np.inf] * len(look))), look.shape)
    a, b = palette.members[i], palette.members[j]
    return [f"most alike in look: {a.name} and {b.name}, {look[i, j]:.2f} look JND apart (2% contrast threshold "
            f"assumed), {abs(palette.distances_jnd[i, j]):.2f} JND apart in feel"]
