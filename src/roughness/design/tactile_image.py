"""Tactile images: a picture with a few flat colours becomes a plate whose regions carry distinguishable textures.

Colours: the picture's flat colours are found with a colour tolerance (``roughness.design.colours``:
CIELAB, JPEG noise merged, anti-aliased edge pixels joining the nearest), each covering at least
0.5% of its pixels. A ``Layout`` (``roughness.design.layout``) says what each becomes: a raised line
(``roughness.design.lines``), a flat region (the background) or a textured region, matched to palette members as
assigned or by lightness (the lightest colour gets the smoothest texture, the darkest the roughest); without one,
every colour is a textured region. The picture is scaled to ``width_mm`` on ``pixel_mm`` pixels (nearest neighbour,
or with smooth edges: ``roughness.design.edges``); each region carries its texture read periodically, every
texture standing on the plate's floor (z = 0 at its lowest point). Outlines (optional) are smooth raised lines
along the region boundaries, as in the paper's lion: a raised cosine of width ``outline_mm`` and height
``outline_height_mm`` (default: the median relief of the textures). A key strip (optional,
``roughness.design.key``) goes under the picture; textured areas too narrow to read are listed
(``roughness.design.readability``).

The plate's roughness map is the surrogate's V at footprint positions ``step_mm`` apart; the
regions' values are read at positions whose whole footprint lies in one region, clear of outlines. The strain image
(optional, FEM) tiles the plate with footprints whose central 8 mm strain windows abut and shows the
fluctuation of the maximum compressive strain, as the paper's figure of its lion; each footprint's field
is shown minus its mean (V, built from differences, is blind to that offset; without it the tiles'
seams would show the footprints' different indentations rather than the texture).

How different the regions look, beside how different they feel (``roughness.design.look.region_looks``): the plate
the roughness map is of (as printed, with a printer) is rendered whole and each region's pixels more than
``look.BAND_MM`` inside its borders (outlines and lines are borders too: their shadows fall on the regions beside
them) are compared with every other region's, in look JND (1: the assumed visibility threshold).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.checks import flag, non_negative, positive
from roughness.core.errors import InputError
from roughness.core.figures import new_figure, save_figure
from roughness.core.limits import MAX_IMAGE_PIXELS, MAX_MAP_POSITIONS, MAX_PLATE_PIXELS, check_size
from roughness.core.reprs import short_repr
from roughness.perceptual_scale import FLOOR_LAMBDA_MM, jnd
from roughness.surface.heightmap import Heightmap, pixel_size

from .colours import TOLERANCE, PictureColours, cluster_colours, hex_colour
from .edges import smooth_labels, smooth_mask
from .evaluation import Evaluator
from .key import KeyEntry, KeySpec, key_entries, key_height_mm, key_strip
from .layout import FLAT, Layout
from .lines import fill_lines, line_relief
from .look import RegionLooks, region_looks
from .pages import scale_bar_mm
from .plate_relief import compose, outline
from .readability import MIN_TEXTURE_WIDTH_MM, SmallArea, merge_small_areas, small_areas

if TYPE_CHECKING:
    from matplotlib.figure import Figure

WIDTH_MM = 60.0
PIXEL_MM = 0.1
STEP_MM = 1.0


@dataclass(frozen=True)
class Region:
    colour: tuple[int, int, int]
    texture: str
    pixels: int
    fem_roughness: float | None  # of the texture alone (palette), if known
    fem_lambda_mm: float | None
    plate_roughness: float | None  # median surrogate V over footprints wholly in the region (None: none fit)
    plate_lambda_mm: float | None
    footprints: int
    digital_plate_roughness: float | None = None  # with a printer: the same median on the digital plate


@dataclass(frozen=True)
class TactilePlate:
    heightmap: Heightmap  # the plate's relief (mm)
    labels: np.ndarray  # region index per plate pixel
    regions: tuple[Region, ...]
    map_x_mm: np.ndarray
    map_y_mm: np.ndarray
    roughness_map: np.ndarray  # surrogate V per footprint position (rows = y)
    map_labels: np.ndarray  # region whose footprint it wholly lies in, -1 if mixed
    colours: PictureColours  # the picture's flat colours and what their clustering did
    strain: np.ndarray | None = None  # fluctuation of lambda3 mosaic (FEM), on strain_axis_mm
    strain_extent_mm: tuple[float, float, float, float] | None = None
    notes: tuple[str, ...] = field(default=())
    layout: Layout | None = None  # lines, background and assignments (None: every colour a textured region)
    small_areas: tuple[SmallArea, ...] = ()  # textured areas too narrow to read a texture in
    small_specks: int = 0  # and specks under readability.MIN_AREA_MM2 not listed
    key: tuple[KeyEntry, ...] = ()  # the key strip's entries (none: no key)
    line_mask: np.ndarray | None = None  # the strokes drawn as lines, on the picture's part of the plate
    looks: RegionLooks | None = None  # how different the regions look (None: not measured)

    def __repr__(self) -> str:
        regions = ", ".join(f"{hex_colour(r.colour)} {r.texture}" for r in self.regions)
        return short_repr(self, repr(self.heightmap), f"{len(self.regions)} regions [{regions}]",
                          "strain image" if self.strain is not None else "", f"{len(self.notes)} note(s)"
                          if self.notes else "")

    def felt_lambdas_mm(self, which: str = "plate") -> list[float | None]:
        """Each region's equivalent wavelength (mm) on the plate's map ("plate") or of its texture (FEM), counted
        at least at the scale's floor (``FLOOR_LAMBDA_MM``, where a flat region is): below it nothing is felt finer,
        and a V near 0 would otherwise count as a wavelength far below anything a fingertip tells apart. None: not
        measured."""
        lam = [r.plate_lambda_mm if which == "plate" else r.fem_lambda_mm for r in self.regions]
        return [FLOOR_LAMBDA_MM if r.texture == FLAT else None if x is None else max(x, FLOOR_LAMBDA_MM)
                for r, x in zip(self.regions, lam, strict=True)]

    def distances_jnd(self, which: str = "plate") -> np.ndarray:
        """Signed pairwise distances of the regions (JND, ``felt_lambdas_mm``): on the plate's map ("plate") or of
        the textures (FEM); NaN where a region is not measured."""
        lam = self.felt_lambdas_mm(which)
        return np.array([[jnd(a, b) if a and b else np.nan for b in lam] for a in lam])

    def summary(self) -> dict:
        width, height = self.heightmap.size_mm
        return {"width_mm": width, "height_mm": height, "pixel_mm": self.heightmap.pixel_mm,
                "relief_mm": float(np.ptp(self.heightmap.heights)),
                "regions": [{"colour": hex_colour(r.colour), "texture": r.texture, "pixels": r.pixels,
                             "fem_roughness": r.fem_roughness, "fem_lambda_mm": r.fem_lambda_mm,
                             "plate_roughness": r.plate_roughness, "plate_lambda_mm": r.plate_lambda_mm,
                             "digital_plate_roughness": r.digital_plate_roughness,
                             "footprints_inside": r.footprints} for r in self.regions],
                "colour_clustering": self.colours.summary(),
                "plate_distances_jnd": _rounded(self.distances_jnd("plate")),
                "texture_distances_jnd": _rounded(self.distances_jnd("fem")), **self._look_summary(),
                **self._layout_summary(),
                "small_areas": [a.as_dict() for a in self.small_areas], "small_specks": self.small_specks,
                "key": [{"label": e.label, "braille": e.braille(), "colour": hex_colour(self.regions[e.region].colour),
                         "texture": self.regions[e.region].texture, "swatch_mm": [round(v, 2) for v in e.swatch_mm]}
                        for e in self.key],
                "notes": list(self.notes)}

    def _look_summary(self) -> dict:
        """How different the regions look (look JND, ``design.look``) beside how far apart they feel on the plate's
        map: the matrix, and each pair's full comparison (region a beside region b, b the reference)."""
        if self.looks is None:
            return {}
        feel = self.distances_jnd("plate")
        colours = [hex_colour(r.colour) for r in self.regions]
        return {"plate_look_differences_jnd": _rounded(self.looks.matrix),
                "look_pairs": [{"a": colours[a], "b": colours[b],
                                "feel_distance_jnd": None if np.isnan(feel[a, b]) else round(float(feel[a, b]), 3),
                                "look": None if look is None else look.as_dict()}
                               for a, row in enumerate(self.looks.differences) for b, look in enumerate(row) if a < b],
                "look_unmeasured": list(self.looks.unmeasured)}

    def _layout_summary(self) -> dict:
        """Lines (their colours, threshold and measured widths, mm), their style and the flat background."""
        if self.layout is None:
            return {}
        colours = self.colours.colours
        mm_per_px = self.heightmap.size_mm[0] / self.colours.labels.shape[1]
        lines = self.layout.lines
        return {"background": None if self.layout.background is None else hex_colour(colours[self.layout.background]),
                "flat_colours": [hex_colour(colours[i]) for i in self.layout.flat],
                "lines": None if lines is None else {
                    **lines.summary(mm_per_px, [hex_colour(c) for c in colours]), "width_mm": self.layout.style.width_mm, "height_mm": self.layout.style.height_mm,
                    "gap_mm": self.layout.style.gap_mm}}


def _rounded(a: np.ndarray) -> list:
    return [[None if np.isnan(x) else round(float(x), 3) for x in row] for row in a]


def read_image(path: str | Path) -> np.ndarray:
    """RGB pixels (h, w, 3) uint8 of a picture file (``picture_rgb``); InputError if it cannot be read or declares
    more than MAX_IMAGE_PIXELS (checked from its header, before decoding)."""
    from PIL import UnidentifiedImageError

    from roughness.surface.io import open_image

    path = Path(path)
    if not path.is_file():
        raise InputError(f"image not found: {path}" if not path.exists() else f"{path} is not a file",
                         parameter="image")
    try:
        with open_image(path, MAX_IMAGE_PIXELS, "image") as image:
            return picture_rgb(image)
    except InputError:
        raise
    except (UnidentifiedImageError, OSError, ValueError) as err:
        raise InputError(f"{path} is not a readable image: {err}", parameter="image") from None


def picture_rgb(image) -> np.ndarray:
    """A PIL picture as RGB pixels (h, w, 3) uint8 whose distinct colours are the picture's.

    16/32-bit greyscale (modes I;16*, I) is scaled to 8 bits (v / 257; values outside 0..65535: min..max),
    floating-point greyscale (F) min..max: Pillow's own conversion clips them at 255, merging all but black.
    A picture with transparency is composited over white, or over black when what is drawn on it is light
    (a white logo on a transparent background): its shapes may be in the alpha channel only.
    """
    mode = image.mode
    if mode.startswith("I") or mode == "F":
        values = np.asarray(image, dtype=float)
        if mode == "F" or values.min() < 0 or values.max() > 65535:
            low, span = values.min(), np.ptp(values)
            grey = (values - low) * (255 / span) if span > 0 else np.zeros_like(values)
        else:
            grey = values / 257
        return np.repeat(np.round(grey).astype(np.uint8)[..., None], 3, axis=2)
    if "A" in mode or "a" in mode or "transparency" in image.info:
        rgba = np.asarray(image.convert("RGBA"))
        drawn = rgba[rgba[..., 3] > 0, :3]
        light = drawn.size > 0 and float(drawn.mean(axis=0) @ [0.299, 0.587, 0.114]) > 127.5
        alpha = rgba[..., 3:].astype(np.float32) / 255
        background = 0.0 if light else 255.0
        return np.round(rgba[..., :3] * alpha + background * (1 - alpha)).astype(np.uint8)
    return np.asarray(image.convert("RGB"))


def describe_picture(path: str | Path) -> str:
    """What a picture file is, from its header: e.g. ``x.png (a 16-bit greyscale picture, mode I;16)``."""
    from PIL import Image

    kinds = {"1": "1-bit black-and-white", "L": "8-bit greyscale", "LA": "8-bit greyscale with alpha",
             "P": "8-bit palette", "RGB": "8-bit RGB", "RGBA": "8-bit RGB with alpha", "CMYK": "8-bit CMYK",
             "I;16": "16-bit greyscale", "I;16B": "16-bit greyscale", "I;16L": "16-bit greyscale",
             "I": "32-bit integer greyscale", "F": "32-bit floating-point greyscale"}
    with Image.open(path) as image:
        width, height = image.size
        return f"{path} (a {width} x {height} {kinds.get(image.mode, 'picture')} picture, mode {image.mode})"


def flat_colours(rgb: np.ndarray, tolerance: float = TOLERANCE, source: str = "the picture"
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The picture's flat colours (n, 3), lightest first, and each pixel's index (h, w): ``cluster_colours``."""
    found = cluster_colours(rgb, tolerance, source=source)
    return found.colours, found.labels


def plate_labels(labels: np.ndarray, width_mm: float, pixel_mm: float) -> np.ndarray:
    """The picture's region indices scaled to a plate ``width_mm`` wide on ``pixel_mm`` pixels (nearest neighbour)."""
    h, w = labels.shape
    ny, nx = plate_shape(labels.shape, width_mm, pixel_mm)
    rows = np.minimum(((np.arange(ny) + 0.5) * h / ny).astype(int), h - 1)
    cols = np.minimum(((np.arange(nx) + 0.5) * w / nx).astype(int), w - 1)
    return labels[np.ix_(rows, cols)]


def plate_pixel(pixel_mm: float | None, picture_shape: tuple[int, ...], width_mm: float,
                textures: Sequence[Heightmap], printer: object = None, key_mm: float = 0.0) -> tuple[float, str | None]:
    """The plate's pixel (mm), and a note when it is not the default: ``pixel_mm`` if given; with a printer, the
    textures' finest pixel where it is finer than PIXEL_MM and the plate stays within MAX_PLATE_PIXELS, since a
    palette verified as printed at its own pixel prints alike only at that pixel (the bead erodes bumps resampled
    coarser more: a four-colour fdm-0.4-0.2 palette 2.04 JND apart as printed tiles came 1.81 apart on a 0.1 mm plate
    and 2.02 at 0.05 mm, studies/results/print_tactile_image.md); else PIXEL_MM. ``key_mm``: the key strip's height
    (``key_height``), counted with the plate."""
    if pixel_mm is not None:
        return pixel_size(pixel_mm), None
    finest = min((t.pixel_mm for t in textures), default=PIXEL_MM)
    if printer is None or finest >= PIXEL_MM:
        return PIXEL_MM, None
    try:
        plate_shape(picture_shape, width_mm, finest, key_mm=key_mm)
    except InputError:
        return PIXEL_MM, (f"the plate is composed at {PIXEL_MM:g} mm pixels: at the textures' {finest:g} mm it would "
                          "hold too many; the printer's model then erodes the textures more than their verification "
                          "as printed tiles said (see the regions' V on the plate)")
    return finest, (f"the plate is composed at the textures' {finest:g} mm pixels (not {PIXEL_MM:g}), so that the "
                    "printer's model prints them as they were verified; --pixel-mm sets it")


def plate_shape(picture_shape: tuple[int, ...], width_mm: float, pixel_mm: float, step_mm: float | None = None,
                footprint_mm: float | None = None, key_mm: float = 0.0) -> tuple[int, int]:
    """(ny, nx) plate pixels for a picture (h, w, ...); InputError above MAX_PLATE_PIXELS (with a key strip
    ``key_mm`` tall below it: ``key_height``), or (given the map's ``step_mm`` and ``footprint_mm``) above
    MAX_MAP_POSITIONS: checked before a palette is made or a plate composed."""
    from roughness.surrogate.roughness_map import centre_count

    width_mm, pixel_mm = positive("size_mm", width_mm), pixel_size(pixel_mm)
    step_mm = None if step_mm is None else positive("step_mm", step_mm)
    h, w = picture_shape[:2]
    across = width_mm / pixel_mm
    check_size(f"pixels across a {width_mm:g} mm plate at {pixel_mm:g} mm", across, MAX_PLATE_PIXELS, "size_mm")
    nx = round(across)
    ny = max(2, round(nx * h / w))
    key_rows = math.ceil(key_mm / pixel_mm) if key_mm > 0 else 0
    check_size(f"pixels of a {width_mm:g} mm plate{' with its key' if key_rows else ''} at {pixel_mm:g} mm (use larger "
               "pixels or a smaller plate)", nx * (ny + key_rows), MAX_PLATE_PIXELS, "size_mm")
    if step_mm is not None and footprint_mm is not None:
        check_size(f"footprint positions of its roughness map in steps of {step_mm:g} mm",
                   centre_count(nx * pixel_mm, footprint_mm, step_mm, False)
                   * centre_count(ny * pixel_mm, footprint_mm, step_mm, False), MAX_MAP_POSITIONS, "step_mm")
    return ny, nx


def key_height(layout: Layout, key: KeySpec | None, width_mm: float) -> float:
    """Height (mm) of the key strip that a plate ``width_mm`` wide carries below ``layout``'s picture (0 without a
    key): an entry per textured region, as ``tactile_image`` lays them out; counted with the plate's pixels before
    any palette is made."""
    if key is None:
        return 0.0
    textured = set(layout.textured)
    regions = [n for n, c in enumerate(layout.regions) if c in textured]
    labels = {n: key.labels[c] for n, c in enumerate(layout.regions) if c in key.labels}
    return key_height_mm(key_entries(regions, labels, key.table), width_mm, key.style)


def check_outline(outline_mm: object, outline_height_mm: object) -> None:
    """InputError unless the outline's width (mm) is None or positive and its height (mm) None or >= 0."""
    if outline_mm is not None:
        positive("outline_mm", outline_mm)
    if outline_height_mm is not None:
        non_negative("outline_height_mm", outline_height_mm)


def footprint_labels(labels: np.ndarray, pixel_mm: float, xs: np.ndarray, ys: np.ndarray, footprint_mm: float
                     ) -> np.ndarray:
    """For each footprint centre (ys x xs, mm): the region it wholly lies in, or -1."""
    half = round(footprint_mm / 2 / pixel_mm)
    out = np.full((len(ys), len(xs)), -1)
    for a, cy in enumerate(ys):
        for b, cx in enumerate(xs):
            i, j = round(cy / pixel_mm), round(cx / pixel_mm)
            window = labels[max(i - half, 0):i + half, max(j - half, 0):j + half]
            first = window.flat[0]
            if first >= 0 and np.all(window == first):
                out[a, b] = first
    return out


def tactile_image(picture: np.ndarray | PictureColours, textures: list[tuple[str, Heightmap, float | None]],
                  width_mm: float = WIDTH_MM, pixel_mm: float = PIXEL_MM, outline_mm: float | None = None,
                  outline_height_mm: float | None = None, step_mm: float = STEP_MM, strain: bool = False,
                  evaluator: Evaluator | None = None, progress=None, tolerance: float = TOLERANCE,
                  layout: Layout | None = None, key: KeySpec | None = None, smooth_edges: bool = False,
                  merge_small: bool = False) -> TactilePlate:
    """A plate from a picture (RGB pixels, or its colours already clustered) and textures ``(name, heightmap,
    FEM V or None)`` ordered smoothest first (module docstring); ``tolerance``: Delta E, for RGB pixels;
    ``layout``: which colours are lines, flat or which texture (``roughness.design.layout``; default: every colour
    a region, textured by the lightness rule); ``key``: add a key strip under the picture (``roughness.design.key``);
    ``smooth_edges``: region boundaries follow the shapes, not the picture's pixels (``roughness.design.edges``;
    default: nearest neighbour); ``merge_small``: textured areas too narrow to read join the region nearest them
    (``readability.merge_small_areas``; default: listed only).

    ``progress(stage, done, total)``: after each batch of the roughness map (stage "roughness map") and each
    FEM footprint of the strain image (stage "strain image").
    """
    width_mm, pixel_mm, step_mm = positive("size_mm", width_mm), positive("pixel_mm", pixel_mm), positive("step_mm", step_mm)
    check_outline(outline_mm, outline_height_mm)
    strain = flag("strain", strain)
    evaluator = evaluator or Evaluator()
    found = picture if isinstance(picture, PictureColours) else cluster_colours(picture, tolerance)
    colours = found.colours
    layout = layout or Layout(len(colours))
    members, rule = layout.members(len(textures))
    notes = [f"textures: {rule}"] if layout.flat or layout.assign or len(textures) > len(members) else []
    region_colours = layout.regions
    line_mask = layout.lines.mask if layout.lines else np.zeros(found.labels.shape, dtype=bool)
    region_of = np.full(len(colours), -1)
    region_of[region_colours] = np.arange(len(region_colours))
    region_labels = region_of[fill_lines(found.labels, line_mask)]
    if smooth_edges:
        shape = plate_shape(found.labels.shape, width_mm, pixel_mm)
        labels, plate_lines = smooth_labels(region_labels, shape), smooth_mask(line_mask, shape)
    else:
        labels, plate_lines = plate_labels(region_labels, width_mm, pixel_mm), plate_labels(line_mask, width_mm, pixel_mm)
    chosen = [textures[members[i]] if i in members else None for i in region_colours]
    keep_out = None
    if layout.lines:
        lines_relief, keep_out = line_relief(plate_lines, pixel_mm, layout.style)
    if merge_small:
        labels, merged = merge_small_areas(labels, np.zeros(labels.shape, dtype=bool) if keep_out is None else keep_out,
                                           pixel_mm, [i for i, t in enumerate(chosen) if t])
        if merged:
            notes.append(f"{merged} textured area(s) narrower than {MIN_TEXTURE_WIDTH_MM:g} mm merged into the region "
                         "nearest to them")
    plate = compose(labels, [t[1] if t else None for t in chosen], pixel_mm, outline_mm, outline_height_mm)
    if keep_out is not None:
        plate = Heightmap(np.where(keep_out, lines_relief, plate.heights), pixel_mm)
    entries: list[KeyEntry] = []
    if key is not None:
        by_region = {i: key.labels[c] for i, c in enumerate(region_colours) if c in key.labels}
        listed = key_entries([i for i, t in enumerate(chosen) if t], by_region, key.table)
        background = -1 if layout.background is None else int(region_of[layout.background])
        strip, strip_labels, entries = key_strip(listed, [t[1] if t else None for t in chosen], plate.size_mm[0],
                                                 plate.size_mm[1], pixel_mm, background, key.style)
        check_size("pixels of the plate with its key", plate.heights.size + strip.size, MAX_PLATE_PIXELS, "size_mm")
        plate = Heightmap(np.vstack([plate.heights, strip]), pixel_mm)
        labels = np.vstack([labels, strip_labels])
        if keep_out is not None:
            keep_out = np.vstack([keep_out, np.zeros(strip.shape, dtype=bool)])
    footprint = evaluator.footprint_mm
    if min(plate.size_mm) < footprint:
        raise InputError(f"the plate ({plate.size_mm[0]:.1f} x {plate.size_mm[1]:.1f} mm) is smaller than the "
                         f"{footprint:g} mm skin footprint: its roughness cannot be mapped", parameter="size_mm")
    from roughness.surrogate.roughness_map import roughness_map

    map_progress = (lambda done, total: progress("roughness map", done, total)) if progress else None
    felt = evaluator.as_printed(plate)  # the plate a fingertip touches
    rmap = roughness_map(evaluator.model, felt, step_mm, progress=map_progress)
    digital_map = roughness_map(evaluator.model, plate, step_mm) if evaluator.printer else None
    if evaluator.printer:
        notes.append("the roughness map and the regions' look are of the plate as printed by "
                     f"{evaluator.printer.describe()}; "
                     "plate.npz and plate.stl are the digital design")
    clear = labels if not outline_mm else np.where(outline(labels, pixel_mm, outline_mm, 1.0) > 0, -1, labels)
    if keep_out is not None:
        clear = np.where(keep_out, -1, clear)
    where = footprint_labels(clear, pixel_mm, rmap.x_mm, rmap.y_mm, footprint)
    regions = []
    for i, (c, texture) in enumerate(zip(region_colours, chosen)):
        colour = colours[c]
        name, fem_v = (texture[0], texture[2]) if texture else (FLAT, None)
        inside = rmap.roughness[where == i]
        v = float(np.median(inside)) if inside.size else None
        v_digital = float(np.median(digital_map.roughness[where == i])) if digital_map is not None and inside.size else None
        if v is None:
            notes.append(f"no {footprint:g} mm footprint fits wholly inside the region of colour "
                         f"{hex_colour(colour)}: its plate value is not measured")
        regions.append(Region(tuple(int(c) for c in colour), name, int((labels == i).sum()), fem_v,
                              evaluator.lambda_of(fem_v) if fem_v else None, v,
                              evaluator.lambda_of(v) if v else None, int(inside.size), v_digital))
    textured = {i: hex_colour(colours[c]) for i, (c, t) in enumerate(zip(region_colours, chosen)) if t}
    small, specks = small_areas(labels, clear < 0, pixel_mm, textured)
    notes += [a.describe() for a in small]
    looks = region_looks(felt, clear, [hex_colour(colours[c]) for c in region_colours])
    strain_progress = (lambda done, total: progress("strain image", done, total)) if progress else None
    strain_mosaic, extent = (strain_image(felt, evaluator, strain_progress) if strain else (None, None))
    return TactilePlate(plate, labels, tuple(regions), rmap.x_mm, rmap.y_mm, rmap.roughness, where, found,
                        strain_mosaic, extent, tuple(notes), layout, tuple(small), specks, tuple(entries),
                        plate_lines if layout.lines else None, looks)


def strain_image(plate: Heightmap, evaluator: Evaluator, progress=None
                 ) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """The FEM's strain fluctuation over the plate: footprints whose central strain windows abut, stitched.

    ``progress(done, total)`` is called after each footprint.
    """
    window = float(evaluator.fem.config.window_mm)  # the strain window: the tiles' step
    footprint = evaluator.footprint_mm
    width, height = plate.size_mm
    xs = np.arange(footprint / 2, width - footprint / 2 + 1e-9, window)
    ys = np.arange(footprint / 2, height - footprint / 2 + 1e-9, window)
    rows = []
    for cy in ys:
        row = []
        for cx in xs:
            evaluator.fem.centre_mm = (float(cx), float(cy))
            field = evaluator.fem.simulate(plate).fluctuation
            row.append(field - field.mean())
            if progress:
                progress(len(rows) * len(xs) + len(row), len(xs) * len(ys))
        rows.append(np.hstack(row))
    evaluator.fem.centre_mm = None
    mosaic = np.vstack(rows)
    return mosaic, (xs[0] - window / 2, xs[-1] + window / 2, ys[-1] + window / 2, ys[0] - window / 2)


def figures(plate: TactilePlate) -> dict[str, Figure]:
    """The plate's figures by file name: relief.png (relief with a scale bar), roughness_map.png and, if
    computed, strain.png (no pyplot: the backend is left as it was)."""
    width, height = plate.heightmap.size_mm
    extent = (0, width, height, 0)
    size = (6.4, 6.4 * height / width + 0.8)
    out = {}

    fig = new_figure(figsize=size)
    ax = fig.subplots()
    image = ax.imshow(plate.heightmap.heights, cmap="gray", extent=extent)
    fig.colorbar(image, ax=ax, label="height (mm)", shrink=0.8)
    ax.set(xlabel="x (mm)", ylabel="y (mm)", title="plate relief: " + ", ".join(
        f"{hex_colour(r.colour)}: {r.texture}" for r in plate.regions))
    ax.title.set_fontsize(8)
    bar = scale_bar_mm(width)
    ax.plot([width - bar, width], [-0.02 * height] * 2, color="tab:orange", linewidth=3, clip_on=False)
    ax.text(width - bar / 2, -0.03 * height, f"{bar:g} mm", color="tab:orange", ha="center", va="bottom")
    out["relief.png"] = fig

    x, y = plate.map_x_mm, plate.map_y_mm
    half = (x[1] - x[0]) / 2 if len(x) > 1 else 0.5
    fig = new_figure(figsize=size)
    ax = fig.subplots()
    image = ax.imshow(plate.roughness_map, extent=(x[0] - half, x[-1] + half, y[-1] + half, y[0] - half),
                      cmap="magma")
    ax.contour((np.arange(plate.labels.shape[1]) + 0.5) * plate.heightmap.pixel_mm,
               (np.arange(plate.labels.shape[0]) + 0.5) * plate.heightmap.pixel_mm, plate.labels,
               levels=np.arange(len(plate.regions)) + 0.5, colors="cyan", linewidths=0.6)
    ax.set(xlim=(0, width), ylim=(height, 0), xlabel="x (mm)", ylabel="footprint centre y (mm)",
           title="predicted V per footprint centre (surrogate); cyan: region edges")
    ax.title.set_fontsize(9)
    fig.colorbar(image, ax=ax, label="V", shrink=0.8)
    out["roughness_map.png"] = fig

    if plate.strain is not None:
        fig = new_figure(figsize=size)
        ax = fig.subplots()
        limit = float(np.percentile(np.abs(plate.strain), 99))
        image = ax.imshow(plate.strain, extent=plate.strain_extent_mm, cmap="RdBu_r", vmin=-limit, vmax=limit)
        ax.set(xlim=(0, width), ylim=(height, 0), xlabel="x (mm)", ylabel="y (mm)",
               title="strain fluctuation at the receptors (FEM, per 8 mm window)")
        ax.title.set_fontsize(9)
        fig.colorbar(image, ax=ax, label="strain", shrink=0.8)
        out["strain.png"] = fig
    for fig in out.values():
        fig.tight_layout()
    return out


def save_figures(plate: TactilePlate, folder: Path) -> dict[str, Figure]:
    """``figures(plate)`` written into ``folder`` (PNG); returns them."""
    return {name: save_figure(fig, Path(folder) / name, 90) for name, fig in figures(plate).items()}
