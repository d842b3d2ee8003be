"""`roughness tactile-image IMAGE --out DIR`: a flat-colour picture as a textured, printable plate."""
from __future__ import annotations

import argparse
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from .common import (
    HEIGHT,
    JND,
    LENGTH,
    MAX_LENGTH_MM,
    MAX_PALETTE,
    PIXEL,
    Number,
    add_model_tail,
    count,
    defaults,
    finish,
    json_text,
    log,
    positive,
    write_stdout,
)
from .printer import add_printer_arg, printer_of

MAX_DELTA_E = 300.0  # --colour-tolerance: beyond the largest CIELAB Delta E between two sRGB colours (259)

if TYPE_CHECKING:
    from roughness.design.colours import PictureColours
    from roughness.design.evaluation import Evaluator
    from roughness.design.layout import Layout
    from roughness.design.palette import Palette
    from roughness.design.tactile_image import TactilePlate
    from roughness.surface.heightmap import Heightmap


def add_parser(sub) -> None:
    from roughness.design.colours import TOLERANCE
    from roughness.design.lines import LINE_GAP_MM, LINE_HEIGHT_MM, LINE_WIDTH_MM, MAX_STROKE_MM
    from roughness.design.pages import MARGIN_MM, PAGES_MM
    from roughness.design.palette import family_palette
    from roughness.design.tactile_image import tactile_image
    from roughness.surface.stl import DEFAULT_BASE_MM

    given, pal = defaults(tactile_image), defaults(family_palette)
    p = sub.add_parser("tactile-image", help="a picture with a few flat colours as a plate whose regions carry "
                                             "distinguishable textures (height map, STL, roughness map)")
    p.add_argument("image", metavar="IMAGE", help="picture (.png, .jpg, ...) with a few flat colours")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="new folder: plate.npz (mm), plate.stl, plate.json, clustered.png (the picture in its "
                        "flat colours), relief.png, roughness_map.png/.npy, strain.png (with --strain)")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--size-mm", type=LENGTH, default=given["width_mm"],
                      help=f"plate width in mm; the height follows the picture (default {given['width_mm']:g})")
    size.add_argument("--page", choices=sorted(PAGES_MM),
                      help=f"fit the plate on this sheet less {MARGIN_MM:g} mm margins (A4, A3, Letter, Tabloid: "
                           "swell-paper sizes; braille: the 11 x 11.5 inch embosser page); --pixel-mm 0.2 keeps an "
                           "A4 plate within the pixel limit")
    p.add_argument("--pixel-mm", type=PIXEL,
                   help=f"plate pixel size in mm (default {given['pixel_mm']:g}; with a printer, the textures' own "
                        "pixel where finer, 0.05 for the built-in textures, so that the plate prints as its palette "
                        "was verified)")
    source = p.add_mutually_exclusive_group()
    source.add_argument("--palette", metavar="DIR", help="textures from a `roughness palette` folder")
    source.add_argument("--k", type=count(MAX_PALETTE),
                        help="make a palette of K textures first (default: as many as the picture has colours)")
    p.add_argument("--colour-tolerance", type=positive(MAX_DELTA_E), default=TOLERANCE, metavar="DELTA_E",
                   help="colours closer than this (CIELAB Delta E) are one flat colour: JPEG noise and anti-aliased "
                        f"edges join the nearest (default {TOLERANCE:g})")
    p.add_argument("--min-jnd", type=JND, default=pal["min_jnd"],
                   help=f"new palette: smallest pairwise distance in JND (default {pal['min_jnd']:g})")
    p.add_argument("--family", default="standard-1.0", help="new palette: the texture to scale (default standard-1.0)")
    lines = p.add_argument_group("lines, background and textures (tactile-graphics conventions)")
    lines.add_argument("--line-width-mm", type=LENGTH, default=MAX_STROKE_MM,
                       help="strokes narrower than this on the plate (outlines, arrows) are made as raised lines, not "
                            f"regions (default {MAX_STROKE_MM:g})")
    lines.add_argument("--line-colour", metavar="#RRGGBB", help="this colour is the lines' (instead of detecting them)")
    lines.add_argument("--no-lines", action="store_true", help="no line detection: every colour is a region")
    lines.add_argument("--line-bar-mm", type=LENGTH, default=LINE_WIDTH_MM,
                       help=f"width of a raised line at its foot (default {LINE_WIDTH_MM:g}, within the 1.1-3 mm of "
                            "the Round Table's 3D-printing guidelines)")
    lines.add_argument("--line-height-mm", type=HEIGHT, default=LINE_HEIGHT_MM,
                       help=f"height of a raised line (default {LINE_HEIGHT_MM:g}: a definite line, ibid.)")
    lines.add_argument("--line-gap-mm", type=Number(float, low=0, high=MAX_LENGTH_MM), metavar="MM", default=LINE_GAP_MM,
                       help=f"textures stop this far from a raised line's foot (default {LINE_GAP_MM:g})")
    lines.add_argument("--background", default="auto", metavar="auto|none|#RRGGBB",
                       help="the colour left flat: auto (the colour most on the picture's border), none (texture "
                            "every region) or a colour (default auto)")
    lines.add_argument("--assign", metavar="SPEC|@FILE",
                       help="textures by colour: '#ff0000=1,#00ff00=3,#0000ff=flat' (palette members from 1, "
                            "smoothest first) or @FILE with one COLOUR=N a line; default: the lightest textured colour "
                            "gets the smoothest texture")
    key = p.add_argument_group("key (legend) with braille labels")
    key.add_argument("--key", action="store_true",
                     help="add a key strip under the picture: a 15 mm sample of each texture beside its braille label")
    key.add_argument("--key-labels", metavar="SPEC",
                     help="the labels by colour: '#dc781e=sun,#1e286e=sea' (default: a, b, c, ... lightest first)")
    key.add_argument("--braille-table", metavar="TABLE",
                     help="a liblouis table for the labels (e.g. en-ueb-g2.ctb: contracted; needs liblouis); "
                          "default: uncontracted English, built in")
    p.add_argument("--merge-small", action="store_true",
                   help="textured areas narrower than 6.35 mm join the region nearest them (default: listed only)")
    p.add_argument("--sharp-edges", action="store_true",
                   help="enlarge the picture pixel by pixel (default: region edges follow the shapes, smoothed)")
    p.add_argument("--outline-mm", type=LENGTH, help="width of smooth raised lines along region edges (default: none)")
    p.add_argument("--outline-height-mm", type=HEIGHT,
                   help="height of the raised lines in mm (default: 1.2 x the tallest texture)")
    p.add_argument("--step-mm", type=LENGTH, default=given["step_mm"],
                   help=f"roughness map: distance between footprint positions in mm (default {given['step_mm']:g})")
    p.add_argument("--strain", action="store_true",
                   help="also the FEM strain image (one FEM run per 8 mm of plate squared: minutes)")
    p.add_argument("--base-mm", type=LENGTH,
                   help=f"plate thickness below the relief's lowest point in mm (default {DEFAULT_BASE_MM:g})")
    add_printer_arg(p, "the new palette is made of textures that stay --min-jnd apart as printed, and the plate's "
                       "roughness map is of the printed plate (the files are the digital design)")
    add_model_tail(p, "print plate.json's content (default: text)")
    finish(p, run, width_mm="--size-mm")


@dataclass(frozen=True)
class _Textures:
    """The plate's textures ``(name, heightmap, FEM V or None)``, smoothest first, and the palette made for them
    (None: read from --palette)."""

    members: list[tuple[str, Heightmap, float | None]]
    made: Palette | None
    forecast: dict = field(default_factory=dict)  # member -> profile -> Forecast (a digital palette made here)


@dataclass
class _Progress:
    """tactile_image's progress on stderr: every FEM footprint of the strain image, the map at each tenth."""

    args: argparse.Namespace
    tenths: dict[str, int] = field(default_factory=dict)

    def __call__(self, stage: str, done: int, total: int) -> None:
        if stage == "strain image" or self.tenths.get(stage) != done * 10 // total:
            self.tenths[stage] = done * 10 // total
            unit = " FEM footprints" if stage == "strain image" else " positions"
            log(self.args, f"  {stage}: {done}/{total}{unit}")


def run(args: argparse.Namespace) -> int:
    """Cluster the picture's colours, find a texture for each, compose and map the plate, write it, report."""
    from roughness.core.files import check_distinct, check_output_folder
    from roughness.design.evaluation import Evaluator
    from roughness.design.tactile_image import PIXEL_MM, key_height, plate_pixel, plate_shape, tactile_image

    check_distinct({"--out": args.out}, {"IMAGE": args.image, "--palette": args.palette, "--model": args.model,
                                         "--printer": args.printer})
    out = check_output_folder(args.out, args.overwrite, "out")
    printer = printer_of(args)
    found = _picture_colours(args)
    if args.page:
        from roughness.design.pages import page_width

        args.size_mm = page_width(args.page, found.labels.shape)
        log(args, f"tactile-image: a plate {args.size_mm:.1f} mm wide fits the {args.page} page")
    evaluator = Evaluator(args.model, args.verify, printer=printer)
    layout = _layout(args, found)
    key = None
    if args.key or args.key_labels or args.braille_table:
        from roughness.design.key import key_spec

        key = key_spec(found, args.key_labels, args.braille_table)
    # the plate's size with its key, checked before any palette is made
    key_mm = key_height(layout, key, args.size_mm)
    plate_shape(found.labels.shape, args.size_mm, args.pixel_mm or PIXEL_MM, args.step_mm, evaluator.footprint_mm,
                key_mm)
    # a picture of lines on a flat background needs no palette
    textures = _textures(args, len(layout.textured), evaluator) if layout.textured else _Textures([], None)
    log(args, "tactile-image: composing the plate, mapping its roughness (surrogate), rendering its look"
        + ("; FEM strain image" if args.strain else ""))
    pixel_mm, pixel_note = plate_pixel(args.pixel_mm, found.labels.shape, args.size_mm,
                                       [hm for _, hm, _ in textures.members], evaluator.printer, key_mm)
    plate = tactile_image(found, textures.members, args.size_mm, pixel_mm, args.outline_mm,
                          args.outline_height_mm, args.step_mm, args.strain, evaluator, _Progress(args),
                          layout=layout, key=key, smooth_edges=not args.sharp_edges, merge_small=args.merge_small)
    if pixel_note:
        from dataclasses import replace

        plate = replace(plate, notes=(pixel_note, *plate.notes))
    from roughness.design.guidelines import check_plate

    checks = check_plate(plate, args.min_jnd)
    summary = {"image": args.image, "out": str(out), **plate.summary(),
               "guidelines": [c.as_dict() for c in checks], "verifier": evaluator.verifier,
               **({"print_forecast": textures.made.forecast} if textures.forecast else {}),
               "provenance": evaluator.provenance.as_dict(),
               **({"printer": printer.as_dict()} if printer else {})}
    _write(args, out, plate, textures.made, summary)
    if args.json:
        write_stdout(json_text(summary))
        return 0
    write_stdout("\n".join(_text_lines(args, out, plate, summary, evaluator.verifier)
                            + _forecast_lines(textures.forecast)))
    return 0


def _picture_colours(args: argparse.Namespace) -> PictureColours:
    """IMAGE's flat colours (within --colour-tolerance); InputError if --k textures cannot cover them."""
    from roughness.design.colours import cluster_colours
    from roughness.design.tactile_image import describe_picture, hex_colour, read_image

    rgb = read_image(args.image)
    found = cluster_colours(rgb, args.colour_tolerance, source=describe_picture(args.image))
    colours = found.colours
    log(args, f"tactile-image: {args.image}: {rgb.shape[1]:,} x {rgb.shape[0]:,} pixels, {found.describe()}: "
        + ", ".join(hex_colour(c) for c in colours))
    return found


def _layout(args: argparse.Namespace, found: PictureColours) -> Layout:
    """Lines, flat background and assignments of the picture's colours (--line-*, --background, --assign);
    InputError if --k textures cannot cover the colours to texture."""
    from roughness.core.errors import InputError
    from roughness.design.layout import assign_argument, plan_layout
    from roughness.design.lines import LineStyle
    from roughness.design.tactile_image import hex_colour

    assign = assign_argument(args.assign) if args.assign else None
    mm_per_px = args.size_mm / found.labels.shape[1]
    layout = plan_layout(found, mm_per_px, None if args.no_lines else args.line_width_mm,
                         None if args.no_lines else args.line_colour,
                         None if args.background == "none" else args.background, assign,
                         LineStyle(args.line_bar_mm, args.line_height_mm, args.line_gap_mm))
    textured = [hex_colour(found.colours[i]) for i in layout.textured]
    log(args, f"tactile-image: lines {', '.join(hex_colour(found.colours[i]) for i in layout.line_colours) or 'none'}; "
        f"flat {', '.join(hex_colour(found.colours[i]) for i in layout.flat) or 'none'}; "
        f"textured {', '.join(textured) or 'none'}")
    if args.k is not None and args.k < len(textured):
        raise InputError(f"the picture has {len(textured)} flat colours to texture ({', '.join(textured)}; colours "
                         f"within Delta E {found.tolerance:g} merged): a palette of {args.k} textures cannot cover "
                         f"them (give at least {len(textured)}, or a larger --colour-tolerance)", "k")
    if args.k is not None and args.k > len(textured):
        log(args, f"tactile-image: --k {args.k} is more than the {len(textured)} colours to texture found; if the "
                  "picture has more flat colours, lower --colour-tolerance (clustered.png shows what was found)")
    return layout


def _textures(args: argparse.Namespace, colours: int, evaluator: Evaluator) -> _Textures:
    """The textures of --palette (InputError if fewer than the ``colours``), or a new palette of --k (default: one
    per colour) from --family, --min-jnd apart."""
    from roughness.core.errors import InputError
    from roughness.design.palette import family_palette, load_palette

    if args.palette:
        textures = [(name, hm, m.get("fem_roughness")) for name, hm, m in load_palette(args.palette)]
        if len(textures) < colours:
            raise InputError(f"the picture has {colours} flat colours but the palette only {len(textures)} "
                             "textures", "palette")
        return _Textures(textures, None)
    k = args.k or max(2, colours)  # a palette has 2 members at least: one colour to texture takes the rougher
    log(args, f"tactile-image: making a palette of {k} textures {args.min_jnd:g} JND apart")
    palette = family_palette(k, args.min_jnd, args.family, "height", evaluator,
                             progress=lambda line: log(args, "  " + line))
    if evaluator.printer is None:  # a digital palette: how each member would fare on the common printers
        from dataclasses import replace

        from roughness.design.palette import print_forecast

        forecast = print_forecast(palette.members, evaluator)
        palette = replace(palette, forecast={name: {profile: f.as_dict() for profile, f in by_profile.items()}
                                             for name, by_profile in forecast.items()})
        return _Textures([(m.name, m.heightmap, m.fem.roughness) for m in palette.members], palette, forecast)
    return _Textures([(m.name, m.heightmap, m.fem.roughness) for m in palette.members], palette)


def _write(args: argparse.Namespace, out: Path, plate: TactilePlate, made: Palette | None, summary: dict) -> None:
    """Into the new folder ``out``: the palette made (if any), the plate (.npz, .stl), its roughness map, figures,
    clustered picture and ``summary`` (plate.json)."""
    import numpy as np
    from PIL import Image

    from roughness.core.files import atomic_write
    from roughness.design.palette import save_palette
    from roughness.design.tactile_image import save_figures
    from roughness.surface.io import save_heightmap

    out.mkdir(parents=True, exist_ok=True)
    if made is not None:
        save_palette(made, out / "palette", overwrite=args.overwrite)
    save_heightmap(plate.heightmap, out / "plate.npz", overwrite=args.overwrite)
    save_heightmap(plate.heightmap, out / "plate.stl", base_mm=args.base_mm, overwrite=args.overwrite)
    atomic_write(out / "roughness_map.npy", lambda tmp: np.save(tmp, plate.roughness_map), args.overwrite)
    save_figures(plate, out)
    atomic_write(out / "clustered.png", lambda tmp: Image.fromarray(plate.colours.clustered()).save(tmp, format="PNG"),
                 args.overwrite)
    atomic_write(out / "plate.json", lambda tmp: Path(tmp).write_text(json_text(summary, indent=1) + "\n"),
                 args.overwrite)


def _text_lines(args: argparse.Namespace, out: Path, plate: TactilePlate, summary: dict, verifier: str) -> list[str]:
    """The text output: the plate, its colours, each region's texture and felt roughness, the closest pair, notes."""
    import numpy as np

    from roughness.design.tactile_image import hex_colour

    lines = [f"plate {summary['width_mm']:.1f} x {summary['height_mm']:.1f} mm, relief {summary['relief_mm']:.2f} mm, "
             f"written to {out} (plate.npz, plate.stl, plate.json, clustered.png, relief.png, roughness_map.png"
             + (", strain.png)" if args.strain else ")"), f"colours: {plate.colours.describe()}"]
    printed = " as printed" if "printer" in summary else ""
    made = printed if not args.palette else " (as its palette.json says)"  # a --palette folder: its own values
    lines += _line_lines(summary)
    for r in plate.regions:
        flat = "flat (background)" if r.texture == "flat" and hex_colour(r.colour) == summary.get("background") \
            else "flat"
        fem = (f"texture V{made} {r.fem_roughness:.4f} ({verifier})" if r.fem_roughness else
               flat if r.texture == "flat" else "texture V not verified")
        digital = (f" (digital {r.digital_plate_roughness:.4f})" if r.digital_plate_roughness is not None else "")
        wavelength = ("" if r.texture == "flat" or r.plate_lambda_mm is None  # flat: below the scale
                      else f", lambda {r.plate_lambda_mm:.3f} mm")
        on_plate = (f"on the plate{printed} V {r.plate_roughness:.4f}{digital}{wavelength} over {r.footprints} "
                    "footprints (surrogate: no uncertainty of its own)" if r.plate_roughness is not None else
                    "no footprint fits inside the region")
        lines.append(f"{hex_colour(r.colour)} -> {fem}; {on_plate}" if r.texture == "flat" else
                     f"{hex_colour(r.colour)} -> {r.texture}: {fem}; {on_plate}")
    d = plate.distances_jnd("plate")
    pairs = [abs(d[i, j]) for i in range(len(d)) for j in range(i + 1, len(d)) if not np.isnan(d[i, j])]
    if pairs:
        lines.append(f"closest regions on the plate's map: {min(pairs):.2f} JND apart (surrogate)")
    lines += _look_lines(plate)
    lines += [f"key {e['label']} ({e['braille']}): {e['colour']} -> {e['texture']}, sample at x {e['swatch_mm'][0]:.0f}-"
              f"{e['swatch_mm'][2]:.0f}, y {e['swatch_mm'][1]:.0f}-{e['swatch_mm'][3]:.0f} mm" for e in summary["key"]]
    lines += [f"guideline {c['rule']}: {'PASS' if c['passed'] else 'FAIL'}, {c['value']}"
              + (f" ({c['where']})" if c["where"] else "") for c in summary["guidelines"]]
    return lines + [f"note: {n}" for n in plate.notes]


def _look_lines(plate: TactilePlate) -> list[str]:
    """How different each pair of regions looks (the larger of its two directions, design.look) beside how far apart
    they feel on the plate's map."""
    import numpy as np

    from roughness.design.look import THRESHOLD
    from roughness.design.tactile_image import hex_colour

    if plate.looks is None or len(plate.regions) < 2:
        return []
    looks, feel = plate.looks.differences, plate.distances_jnd("plate")
    lines = [f"how different the regions look (look JND, rendered: exact for these heights; 1 = a {THRESHOLD:.0%} "
             "contrast, an assumed visibility threshold) and feel (JND on the plate's map, surrogate):"]
    for a in range(len(looks)):
        for b in range(a + 1, len(looks)):
            pair = [x for x in (looks[a][b], looks[b][a]) if x is not None]
            look = max(pair, key=lambda x: x.difference) if pair else None
            lines.append(f"  {hex_colour(plate.regions[a].colour)} / {hex_colour(plate.regions[b].colour)}: "
                         + (f"look {look.difference:.2f} ({look.verdict})" if look else "look not measured")
                         + (", feel not measured" if np.isnan(feel[a, b]) else f", feel {abs(feel[a, b]):.2f} JND"))
    return lines + [f"  look not measured: {why}" for why in plate.looks.unmeasured]


def _line_lines(summary: dict) -> list[str]:
    """The lines found and how they are made, in words (none without line detection)."""
    lines = summary.get("lines")
    if not lines:
        return []
    if not lines["line_colours"]:
        return [f"lines: none (no colour's strokes are mostly narrower than {lines['threshold_mm']:.3g} mm)"]
    widths = ", ".join(f"{c} strokes {w:.2f} mm wide on average" for c, w in zip(lines["line_colours"],
                                                                               lines["stroke_width_mm"]))
    return [f"lines: {widths} (lines: narrower than {lines['threshold_mm']:.3g} mm) made as smooth raised lines "
            f"{lines['width_mm']:g} mm wide, {lines['height_mm']:g} mm high, textures {lines['gap_mm']:g} mm clear"]


def _forecast_lines(forecast: dict) -> list[str]:
    """A digital palette's forecast in words: per member, its V on each profile and the JNDs printing costs."""
    if not forecast:
        return []
    lines = ["no printer: the textures are digital; printed (surrogate forecast, no uncertainty of its own; "
             "--printer NAME chooses textures that survive that printer):"]
    for name, by_profile in forecast.items():
        first = next(iter(by_profile.values()), None)
        digital = f"digital V {first.digital_roughness:.4f}; " if first else ""
        lines.append(f"  {name}: {digital}" + ("; ".join(f.describe() for f in by_profile.values())
                                                 or "no profile prints it at its pixel size"))
    notes = dict.fromkeys(f"{f.profile}: {n}" for by in forecast.values() for f in by.values() for n in f.notes)
    return lines + [f"  print note: {n}" for n in notes]
