"""`roughness texture make|list`: standard bumps, flat tops and natural families."""
from __future__ import annotations

import argparse
import json


def add_parser(sub) -> None:
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
    make.set_defaults(run=run_make)
    listing = tex_sub.add_parser("list", help="texture names, families and their parameter ranges")
    listing.set_defaults(run=run_list)


def run_make(args: argparse.Namespace) -> int:
    from roughness.dataset.catalogue import make_texture, parse_params
    from roughness.simulate.io import save_heightmap

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


def run_list(args: argparse.Namespace) -> int:
    from roughness.dataset.natural import PARAMETER_RANGES
    from roughness.dataset.textures import texture_names

    print("named: " + ", ".join(texture_names()))
    print("bumps: --param lambda_mm=... [top=cap|flat] [top_diameter_mm=] [height_mm=] [base_diameter_mm=]")
    for family, ranges in PARAMETER_RANGES.items():
        print(f"{family}: " + ", ".join(f"{k} {v[0]}..{v[1]}" if isinstance(v[0], float) else f"{k} {'|'.join(v)}"
                                        for k, v in ranges.items()))
    return 0
