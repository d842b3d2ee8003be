"""`roughness hidden-shapes --shape circle --out DIR`: the paper's seen-not-felt and felt-not-seen plates."""
from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from .common import (
    HEIGHT,
    JND,
    LENGTH,
    SEED,
    Number,
    add_overwrite,
    add_quiet,
    add_reading_args,
    finish,
    json_text,
    log,
    write_stdout,
)

if TYPE_CHECKING:
    from roughness.design.hidden_shapes import HiddenPlate

PLATE_MM = 50.0


def add_parser(sub) -> None:
    from roughness.design.hidden_shapes import FELT_JND, GAP_MARGIN_MM, RECESS_MM, STEP_MM
    from roughness.design.shapes import SHAPES
    from roughness.surface.stl import DEFAULT_BASE_MM

    given = {"felt_jnd": FELT_JND, "gap_margin_mm": GAP_MARGIN_MM, "recess_mm": RECESS_MM, "step_mm": STEP_MM}
    p = sub.add_parser("hidden-shapes", help="plates that show a shape but do not let it be felt, and plates that let "
                                             "it be felt but hardly show it (the paper's Fig. 25), checked")
    shape = p.add_mutually_exclusive_group(required=True)
    shape.add_argument("--shape", choices=SHAPES, help="a built-in shape, half the plate's side across")
    shape.add_argument("--mask", metavar="PICTURE", help="a picture whose dark pixels are the shape (stretched over "
                                                         "the plate; the plate's height follows its aspect)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="new folder: per mode seen.* / felt.*: .npz (mm), .stl, .3mf, .png (look, heightmap and feel "
                        "map side by side); hidden_shapes.json (both measures per region, the checks)")
    p.add_argument("--mode", choices=("seen", "felt", "both"), default="both",
                   help="seen: seen, not felt; felt: felt, not seen; both (default)")
    p.add_argument("--texture", metavar="FILE|NAME",
                   help="the base texture, laid periodically: a heightmap file or a named texture (roughness texture "
                        "list); default: bumps 1 mm apart, 2.5 mm tall on 1 mm bases (the standard textures leave no "
                        "floor clear of the skin at 10 N)")
    p.add_argument("--seed", type=SEED, default=0, help="seed of a named texture (default 0)")
    add_reading_args(p)
    p.add_argument("--size-mm", type=LENGTH, default=PLATE_MM, help=f"plate width in mm (default {PLATE_MM:g})")
    p.add_argument("--felt-jnd", type=JND, default=given["felt_jnd"],
                   help=f"felt plates: JNDs between shape and background (default {given['felt_jnd']:g})")
    p.add_argument("--gap-margin-mm", type=Number(float, low=0, high=10), metavar="MM", default=given["gap_margin_mm"],
                   help="seen plates: change only where the skin stays more than this above the texture "
                        f"(default {given['gap_margin_mm']:g})")
    p.add_argument("--recess-mm", type=HEIGHT, default=given["recess_mm"],
                   help=f"seen plates: how deep the shape is recessed there (default {given['recess_mm']:g})")
    p.add_argument("--step-mm", type=LENGTH, default=given["step_mm"],
                   help=f"feel map: distance between footprint positions in mm (default {given['step_mm']:g})")
    p.add_argument("--base-mm", type=LENGTH,
                   help=f"plate thickness below the relief's lowest point in mm (default {DEFAULT_BASE_MM:g})")
    p.add_argument("--json", action="store_true", help="print hidden_shapes.json's content (default: text)")
    add_quiet(p)
    add_overwrite(p)
    finish(p, run, width_mm="--size-mm")


def run(args: argparse.Namespace) -> int:
    """Read the shape and the texture, make and check each plate, write it, report."""
    from roughness.core.files import check_distinct, check_output_folder
    from roughness.design.hidden_shapes import MODES, default_base, hidden_plate
    from roughness.design.tactile_image import plate_shape, read_image
    from roughness.simulate.config import SimConfig

    check_distinct({"--out": args.out}, {"--mask": args.mask, "--texture": args.texture})
    out = check_output_folder(args.out, args.overwrite, "out")
    tile, notes = _texture(args)
    if tile is None:
        tile = default_base()
    rgb = read_image(args.mask) if args.mask else None
    shape = plate_shape(rgb.shape if rgb is not None else (1, 1), args.size_mm, tile.pixel_mm, args.step_mm,
                        SimConfig().width_mm)
    mask = _mask(args, rgb, shape)
    modes = MODES if args.mode == "both" else (args.mode,)
    plates = {}
    for mode in modes:
        plates[mode] = hidden_plate(tile, mask, mode, gap_margin_mm=args.gap_margin_mm, recess_mm=args.recess_mm,
                                    felt_jnd=args.felt_jnd, step_mm=args.step_mm,
                                    progress=lambda line: log(args, f"hidden-shapes: {line}"))
    summary = {"shape": args.shape or args.mask, "out": str(out), "texture": args.texture or "default bumps",
               "texture_notes": notes, **{mode: plate.summary() for mode, plate in plates.items()}}
    _write(args, out, plates, summary)
    if args.json:
        write_stdout(json_text(summary))
    else:
        write_stdout("\n".join(_text_lines(out, plates)))
    return 0


def _texture(args: argparse.Namespace):
    """The --texture tile (None: the default base) and notes on reading it."""
    if args.texture is None:
        return None, []
    from .object_inputs import read_texture

    return read_texture(args)


def _mask(args: argparse.Namespace, rgb, shape: tuple[int, int]):
    from roughness.design.shapes import builtin_mask, check_mask, picture_mask

    return check_mask(picture_mask(rgb, shape) if rgb is not None else builtin_mask(args.shape, shape))


def _write(args: argparse.Namespace, out: Path, plates: dict[str, HiddenPlate], summary: dict) -> None:
    """Into the new folder ``out``: each plate's heightmap (.npz), STL, 3MF and figure, and ``summary``."""
    from types import SimpleNamespace

    from roughness.core.figures import save_figure
    from roughness.core.files import atomic_write
    from roughness.design.hidden_shapes import figure
    from roughness.objects.meshes import write_mesh
    from roughness.surface.io import save_heightmap
    from roughness.surface.stl import DEFAULT_BASE_MM, plate

    out.mkdir(parents=True, exist_ok=True)
    base = DEFAULT_BASE_MM if args.base_mm is None else args.base_mm
    for mode, hidden in plates.items():
        save_heightmap(hidden.heightmap, out / f"{mode}.npz", overwrite=args.overwrite)
        save_heightmap(hidden.heightmap, out / f"{mode}.stl", base_mm=base, overwrite=args.overwrite)
        solid = plate(hidden.heightmap, base)
        write_mesh(SimpleNamespace(vertices=solid.vertices, faces=solid.triangles), out / f"{mode}.3mf",
                   overwrite=args.overwrite)
        save_figure(figure(hidden), out / f"{mode}.png", dpi=110, overwrite=args.overwrite)
    atomic_write(out / "hidden_shapes.json", lambda tmp: Path(tmp).write_text(json_text(summary, indent=1) + "\n"),
                 args.overwrite)


def _text_lines(out: Path, plates: dict[str, HiddenPlate]) -> list[str]:
    lines = [f"written to {out}: " + ", ".join(f"{m}.npz/.stl/.3mf/.png" for m in plates) + ", hidden_shapes.json"]
    for mode, p in plates.items():
        title = "seen, not felt" if mode == "seen" else "felt, not seen"
        w, h = p.heightmap.size_mm
        feel = ("not measured" if p.feel is None or p.feel.jnd is None else
                f"{p.feel.jnd:+.2f} ± {p.feel.jnd_stderr:.2f} JND (spectral: V {p.inside.roughness:.4f} inside over "
                f"{p.inside.positions} footprints, {p.outside.roughness:.4f} outside over {p.outside.positions})")
        lines += [f"{title}: {w:.0f} x {h:.0f} mm, relief {p.heightmap.heights.max():.2f} mm; {p.change['how']}",
                  f"  feel, shape vs background: {feel}",
                  f"  look, shape vs background: {p.look.difference:.2f} look JND (Weber contrast "
                  f"{p.look.weber_contrast:+.4f}; threshold {p.look.threshold:g} assumed; the base plate's same "
                  f"regions: {p.base_look.difference:.2f})"]
        lines += [f"  check {c.claim}: {'PASS' if c.passed else 'FAIL'} ({c.value})" for c in p.checks]
        lines += [f"  note: {n}" for n in p.notes]
    return lines
