"""`roughness texture make|list`: standard bumps, flat tops and natural families."""
from __future__ import annotations

import argparse

from .common import HEIGHT, LENGTH, PIXEL, SEED, add_overwrite, finish, json_text, write_stdout


def add_parser(sub) -> None:
    from roughness.dataset.grid import PIXEL_MM, SIZE_MM
    from roughness.surface.stl import DEFAULT_BASE_MM

    tex = sub.add_parser("texture", help="make textures: standard bumps, flat tops, natural families")
    tex_sub = tex.add_subparsers(dest="texture_command", required=True)
    make = tex_sub.add_parser("make", help="write a texture heightmap (.npz/.npy/.h5 in mm, 16-bit .png, float .tif) "
                              "or a printable plate (.stl)")
    make.add_argument("name", metavar="NAME",
                      help="standard-<lambda>, flattop-<d>, flat, bumps, or a family (see: roughness texture list)")
    make.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                      help="family parameter, repeatable (default: the family's defaults)")
    make.add_argument("--seed", type=SEED, default=0, help="random seed, an integer >= 0 (default 0)")
    make.add_argument("--size-mm", type=LENGTH, default=SIZE_MM, help=f"side of the square map in mm (default {SIZE_MM:g})")
    make.add_argument("--pixel-mm", type=PIXEL, default=PIXEL_MM, help=f"pixel size in mm (default {PIXEL_MM:g})")
    make.add_argument("--height-mm", type=HEIGHT,
                      help="PNG only: height in mm of full-scale white (default: the height range)")
    make.add_argument("--base-mm", type=LENGTH,
                      help=f"STL only: plate thickness below the texture's lowest point in mm (default {DEFAULT_BASE_MM:g})")
    make.add_argument("--out", required=True, metavar="FILE",
                      help="output file: .npz, .npy, .h5 (mm), .png (16-bit), .tif (float mm), .stl (printable plate)")
    add_overwrite(make)
    finish(make, run_make, params="--param")
    listing = tex_sub.add_parser("list", help="texture names, families and their parameter ranges")
    finish(listing, run_list)


def run_make(args: argparse.Namespace) -> int:
    from roughness.core.checks import positive
    from roughness.core.errors import InputError
    from roughness.core.files import check_output
    from roughness.dataset.catalogue import make_texture, parse_params
    from roughness.surface.io import SAVE_SUFFIXES, save_heightmap

    out = check_output(args.out, args.overwrite, "out")
    suffix = out.suffix.lower()
    if suffix not in SAVE_SUFFIXES:
        raise InputError(f"cannot save {out}: unsupported format {suffix or '(no suffix)'!r}; "
                         f"supported: {', '.join(SAVE_SUFFIXES)}", "out")
    if args.height_mm is not None:
        positive("height_mm", args.height_mm)
        if suffix != ".png":
            raise InputError("applies only to PNG output", "height_mm")
    if args.base_mm is not None and suffix != ".stl":
        raise InputError("applies only to STL output", "base_mm")
    hm, recipe = make_texture(args.name, seed=args.seed, size_mm=args.size_mm, pixel_mm=args.pixel_mm,
                              params=parse_params(args.param))
    save_heightmap(hm, out, height_mm=args.height_mm, base_mm=args.base_mm, overwrite=args.overwrite)
    ny, nx = hm.shape
    note = "; a printable plate in mm" if suffix == ".stl" else "; the file states its pixel size" \
        if suffix != ".npy" else ""
    write_stdout(f"wrote {out}: {nx} x {ny} px of {hm.pixel_mm} mm, heights {hm.heights.min():.3f} to "
                 f"{hm.heights.max():.3f} mm{note}\n{json_text(recipe)}")
    return 0


def run_list(args: argparse.Namespace) -> int:
    from roughness.dataset.families import PARAMETER_LIMITS
    from roughness.dataset.textures import texture_names

    lines = ["named: " + ", ".join(texture_names()),
             "bumps: --param lambda_mm=... [top=cap|flat] [top_diameter_mm=] [height_mm=] [base_diameter_mm=]",
             "families (the values each parameter accepts; lateral scales need 4 pixels and at most half the map):"]
    lines += [f"{family}: " + ", ".join(f"{k} {v[0]:g}..{v[1]:g}" if isinstance(v[0], float) else f"{k} {'|'.join(v)}"
                                        for k, v in ranges.items()) for family, ranges in PARAMETER_LIMITS.items()]
    write_stdout("\n".join(lines))
    return 0
