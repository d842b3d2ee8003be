"""What a 3D printer makes of a digital texture: the expected printed surface of a heightmap (mm).

A printer does not reproduce the digital heights. This module models the geometric limits that a
fingertip can feel on a textured plate printed flat, texture up:

FDM (fused filament), in the order the printer applies them:
1. the slicer closes cracks in each layer's outline narrower than twice ``closing_radius_mm``
   (PrusaSlicer's ``slice_closing_radius``): a flat grey closing with a disk of that radius;
2. layer quantisation: each layer is printed where the model reaches its middle (slicers slice at
   mid-layer), so heights round to the nearest whole layer above the plate (the texture's lowest
   point, taken as the top of a base of whole layers);
3. the bead's width: every layer is made of extruded lines ``line_width_mm`` wide, so a part of a
   layer narrower than one line is not printed: a flat grey opening with a disk of the line width
   (per layer, as openings commute with the layering). This is what rounds a bump's tip: a cap
   narrower than the line is cut down to where the bump is one line wide;
4. the bead's ends: a line's cross-section is a rectangle with semicircular ends of the layer's
   height (nophead 2014, below), so each layer's edge is rounded down to its middle along a quarter
   circle of radius half a layer.
The ridges between neighbouring lines of a top layer (a fraction of the layer height), seam
blobs and over-extrusion are not modelled.

SLA / MSLA (resin):
1. layer quantisation, as above;
2. each layer is exposed on the LCD's pixel grid (``pixel_mm``): heights are sampled at the
   printer's pixel centres (grid aligned with the map's origin) and held over each printer pixel;
3. light bleed: each layer's exposure is blurred by a Gaussian of ``bleed_mm`` (standard
   deviation) and cures where it reaches half the full dose (correct exposure), which rounds
   corners and removes features finer than the blur.
Resin shrinkage (a uniform scale, < 1%) and cross-layer curing of overhangs (a textured top has
none) are not modelled.

Sources of the shipped profiles' parameters (``PROFILES``; each profile's ``source`` says which):
- PrusaSlicer 2.x defaults for a 0.4 mm nozzle, as written in its G-code headers: extrusion widths
  0.45 mm (perimeters, infill; 1.125 x nozzle, the automatic width), ``slice_closing_radius =
  0.049``; print profiles 0.20mm QUALITY and 0.10mm DETAIL (layer heights 0.2 and 0.1 mm).
- Bead cross-section "a rectangle with semi-circular ends" of diameter the layer height:
  C. Palmer (nophead), "Why slicers get the dimensions wrong", HydraRaptor blog, 2014.
- Anycubic Photon Mono 4K (MSLA): XY 35 um, Z 50 um, 6.1" 3840 x 2400 mono LCD (manufacturer's
  specification, as listed at https://xyzdims.com/tag/photon-mono-4k).
- Original Prusa SL1S SPEED (MSLA): 120.96 x 68.04 mm display of 2560 x 1440 pixels (PrusaSlicer's
  SL1S printer profile: display_width / display_pixels_x = 0.047 mm); 0.05 mm layers ("0.05 Normal").
- Light bleed: an estimate. J. Mrazek, "Getting perfectly crisp and dimensionally accurate 3D prints
  on a resin printer" (blog.honzamrazek.cz, 2022) reports calibrated MSLA parts accurate to about one
  LCD pixel (~50 um) with exposure bleeding as a main error; a Gaussian of 0.02 mm (about half a
  pixel) keeps the modelled blur within that.

Resolution: the morphology works on the heightmap's pixels. A bead narrower than 2 pixels cannot be
represented (refused: resample the map finer); an LCD pixel or a blur below the map's pixel leaves
that step without effect at this resolution (said in the notes).

Work: the disks filter row by row (a 1-D filter per row of the disk), so a wide bead costs time, not
memory; the per-layer steps (bead ends, light bleed) run once per distinct layer. Before anything is
filtered, layers x pixels (MAX_LAYER_PIXELS) and pixels x kernel taps (MAX_FILTER_TAPS) are checked.
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from roughness.core.checks import in_range, real
from roughness.core.errors import InputError
from roughness.core.limits import (
    MAX_FILTER_TAPS,
    MAX_LAYER_PIXELS,
    MAX_PRINT_LAYERS,
    PIXEL_RTOL,
    Limit,
    check_size,
)

from .heightmap import Heightmap

MIN_BEAD_PIXELS = 2  # a bead narrower than this many map pixels: its morphology is meaningless
COARSE_BEAD_PIXELS = 4  # below this, the bead's rounding is resolved only roughly (a note says so)
MIN_BLEED_PIXELS = 0.5  # a light bleed (standard deviation) below half a map pixel has no effect
AUTO_WIDTH = 1.125  # PrusaSlicer's automatic extrusion width, x nozzle diameter (0.45 mm for 0.4 mm)
MAX_PROFILE_BYTES = 65_536  # a printer profile is a few lines of JSON


@dataclass(frozen=True)
class FdmProfile:
    """A fused-filament printer and slicer setting (lengths in mm)."""

    name: str
    nozzle_mm: float  # nozzle orifice diameter
    layer_mm: float  # layer height
    line_width_mm: float  # extrusion (line) width: the bead's width
    closing_radius_mm: float  # slicer's gap closing radius (cracks narrower than twice it are closed)
    source: str = "custom profile"
    kind: str = "fdm"
    chosen_by: str = field(default="", compare=False)  # where a default printer came from (ROUGHNESS_PRINTER, ...)

    def __post_init__(self) -> None:
        nozzle = in_range("nozzle_mm", self.nozzle_mm, 0.05, 3.0)
        layer = in_range("layer_mm", self.layer_mm, 0.01, nozzle)  # slicers refuse layers thicker than the nozzle
        width = in_range("line_width_mm", self.line_width_mm, 0.5 * nozzle, 3.0 * nozzle)
        if width < layer:
            raise InputError(f"line_width_mm ({width:g} mm) must be at least the layer height ({layer:g} mm): a "
                             "bead is wider than it is tall", parameter="line_width_mm")
        closing = in_range("closing_radius_mm", self.closing_radius_mm, 0.0, 1.0)
        for name, value in (("nozzle_mm", nozzle), ("layer_mm", layer), ("line_width_mm", width),
                            ("closing_radius_mm", closing)):
            object.__setattr__(self, name, value)

    def as_dict(self) -> dict:
        return asdict(self)

    @property
    def smallest_feature_mm(self) -> float:
        """The narrowest part of a layer this printer makes (mm): one line (narrower parts are removed)."""
        return self.line_width_mm

    def describe(self) -> str:
        return (f"{self.name} (FDM: {self.nozzle_mm:g} mm nozzle, {self.line_width_mm:g} mm lines, "
                f"{self.layer_mm:g} mm layers){_origin(self)}")


@dataclass(frozen=True)
class SlaProfile:
    """A resin (SLA/MSLA) printer and setting (lengths in mm)."""

    name: str
    pixel_mm: float  # XY pixel of the LCD (or projector) on the build plate
    layer_mm: float  # layer height
    bleed_mm: float  # standard deviation of the light's lateral bleed (Gaussian)
    source: str = "custom profile"
    kind: str = "sla"
    chosen_by: str = field(default="", compare=False)  # where a default printer came from (ROUGHNESS_PRINTER, ...)

    def __post_init__(self) -> None:
        for name, low, high in (("pixel_mm", 0.005, 1.0), ("layer_mm", 0.005, 1.0), ("bleed_mm", 0.0, 1.0)):
            object.__setattr__(self, name, in_range(name, getattr(self, name), low, high))

    def as_dict(self) -> dict:
        return asdict(self)

    @property
    def smallest_feature_mm(self) -> float:
        """The narrowest part of a layer this printer makes (mm): two LCD pixels, or the width the light bleed
        closes (about 4 standard deviations: a gap or ridge narrower than that does not reach half the dose)."""
        return max(2 * self.pixel_mm, 4 * self.bleed_mm)

    def describe(self) -> str:
        return (f"{self.name} (SLA: {1e3 * self.pixel_mm:g} um pixels, {self.layer_mm:g} mm layers, "
                f"{1e3 * self.bleed_mm:g} um light bleed){_origin(self)}")


def _origin(profile: FdmProfile | SlaProfile) -> str:
    """`` (from ROUGHNESS_PRINTER)`` for a profile chosen by a project default, else nothing."""
    return f" (from {profile.chosen_by})" if profile.chosen_by else ""


PrintProfile = FdmProfile | SlaProfile
KINDS = {"fdm": FdmProfile, "sla": SlaProfile}

_PRUSA = "PrusaSlicer 2.x defaults for a 0.4 mm nozzle (extrusion width 0.45 mm, slice_closing_radius 0.049 mm)"
PROFILES: dict[str, PrintProfile] = {p.name: p for p in (
    FdmProfile("fdm-0.4-0.2", 0.4, 0.2, 0.45, 0.049, f"{_PRUSA}; 0.20mm QUALITY layers; bead shape: nophead 2014"),
    FdmProfile("fdm-0.4-0.1", 0.4, 0.1, 0.45, 0.049, f"{_PRUSA}; 0.10mm DETAIL layers; bead shape: nophead 2014"),
    SlaProfile("msla-35um", 0.035, 0.05, 0.02, "Anycubic Photon Mono 4K specification (XY 35 um, Z 50 um); "
               "light bleed: estimate (Mrazek 2022)"),
    SlaProfile("sla1s-47um", 0.04725, 0.05, 0.02, "Original Prusa SL1S (PrusaSlicer profile: 120.96 mm / 2560 "
               "pixels; 0.05 Normal layers); light bleed: estimate (Mrazek 2022)"),
)}


PRINTER_ENV = "ROUGHNESS_PRINTER"  # the project's default printer: a profile name, a JSON profile file or "none"
CONFIG_NAME = "roughness.toml"  # in the current folder: ``printer = "fdm-0.4-0.2"``
NO_PRINTER = "none"  # --printer none / ROUGHNESS_PRINTER=none: judge the digital texture


@dataclass(frozen=True)
class PrinterChoice:
    """The printer a command uses and where it was chosen (``spec`` None: no printer)."""

    spec: str | None
    chosen_by: str  # "--printer", "ROUGHNESS_PRINTER", the config file's path, or "" (nothing chose one)
    base: Path | None = None  # a config file's folder: a relative profile path is read from there


def user_config() -> Path:
    """The user's config file: $XDG_CONFIG_HOME/roughness/config.toml (default ~/.config/roughness/config.toml)."""
    import os

    home = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(home) / "roughness" / "config.toml"


def choose_printer(flag: str | None = None) -> PrinterChoice:
    """The printer by precedence: ``flag`` (--printer) > $ROUGHNESS_PRINTER > ./roughness.toml > the user's
    config file (``user_config``); ``none`` at any level switches printing off (and stops the search)."""
    import os

    if flag:
        return PrinterChoice(None if flag.lower() == NO_PRINTER else flag, "--printer")
    env = os.environ.get(PRINTER_ENV, "").strip()
    if env:
        return PrinterChoice(None if env.lower() == NO_PRINTER else env, PRINTER_ENV)
    for path in (Path(CONFIG_NAME), user_config()):
        if path.is_file():
            spec = _config_printer(path)
            if spec is not None:
                return PrinterChoice(None if spec.lower() == NO_PRINTER else spec, str(path), path.parent)
    return PrinterChoice(None, "")


def _config_printer(path: Path) -> str | None:
    """The ``printer`` of a TOML config file (None if it sets none); InputError if the file is not a config."""
    import tomllib

    if path.stat().st_size > MAX_PROFILE_BYTES:
        raise InputError(f"config file {path}: {path.stat().st_size:,} bytes, above {MAX_PROFILE_BYTES:,} (a config "
                         "is a few lines of TOML)", parameter="printer")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise InputError(f"config file {path} is not valid TOML: {err}", parameter="printer") from None
    unknown = sorted(set(data) - {"printer"})
    if unknown:
        raise InputError(f"config file {path}: unknown key(s) {', '.join(unknown)}; it may set printer (a profile "
                         f"name, a JSON profile file or \"none\")", parameter="printer")
    spec = data.get("printer")
    if spec is not None and (not isinstance(spec, str) or not spec.strip()):
        raise InputError(f"config file {path}: printer must be a profile name, a JSON profile file or \"none\", got "
                         f"{spec!r}", parameter="printer")
    return None if spec is None else spec.strip()


def chosen_profile(choice: PrinterChoice) -> PrintProfile | None:
    """The profile of a ``PrinterChoice`` (None: no printer), marked with where a default came from; InputError
    naming the source if the name or file is not a profile."""
    if choice.spec is None:
        return None
    spec = choice.spec
    if choice.base is not None and spec not in PROFILES and not Path(spec).is_absolute():
        spec = str(choice.base / spec)
    try:
        profile = printer_profile(spec)
    except InputError as err:
        if choice.chosen_by == "--printer":
            raise
        raise InputError(f"{err} (the default printer, from {choice.chosen_by}; --printer none switches it off)",
                         parameter="printer") from None
    return profile if choice.chosen_by == "--printer" else replace(profile, chosen_by=choice.chosen_by)


@dataclass(frozen=True)
class PrintResult:
    """The expected printed surface of a heightmap and what the model did to it."""

    heightmap: Heightmap
    profile: PrintProfile
    steps: tuple[str, ...]  # each transformation, in order, in words
    notes: tuple[str, ...]  # what the model could not resolve at this pixel size, and similar warnings

    def as_dict(self) -> dict:
        return {"printer": self.profile.as_dict(), "steps": list(self.steps), "notes": list(self.notes)}


def printer_profile(spec: str) -> PrintProfile:
    """The profile named ``spec`` (``PROFILES``), or read from a JSON file of that path; InputError otherwise."""
    if spec in PROFILES:
        return PROFILES[spec]
    path = Path(spec)
    if not path.is_file():
        raise InputError(f"unknown printer {spec!r}: neither a profile name ({', '.join(PROFILES)}) nor a JSON "
                         "profile file", parameter="printer")
    return load_profile(path)


def load_profile(path: str | Path) -> PrintProfile:
    """A custom profile from a JSON object: ``kind`` ("fdm" or "sla"), ``name`` and the kind's fields (mm).

    FDM: nozzle_mm, layer_mm, and optionally line_width_mm (default 1.125 x nozzle, PrusaSlicer's automatic
    width) and closing_radius_mm (default 0.049, PrusaSlicer's). SLA: pixel_mm, layer_mm, bleed_mm.
    Unknown fields, missing fields and values that are not finite numbers in range are refused.
    """
    path = Path(path)
    if path.stat().st_size > MAX_PROFILE_BYTES:
        raise InputError(f"printer profile {path}: {path.stat().st_size:,} bytes, above {MAX_PROFILE_BYTES:,} "
                         "(a profile is a few lines of JSON)", parameter="printer")
    try:
        data = json.loads(path.read_text(encoding="utf-8"), parse_constant=_no_constant)
    except (ValueError, RecursionError) as err:  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        raise InputError(f"printer profile {path} is not valid JSON: {err}", parameter="printer") from None
    if not isinstance(data, dict):
        raise InputError(f"printer profile {path} must be a JSON object, got {type(data).__name__}",
                         parameter="printer")
    kind = data.get("kind")
    if not isinstance(kind, str) or kind not in KINDS:
        raise InputError(f"printer profile {path}: \"kind\" must be one of {', '.join(map(repr, KINDS))}, got {kind!r}",
                         parameter="printer")
    cls = KINDS[kind]
    allowed = {f.name for f in fields(cls)} - {"source", "chosen_by"}
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise InputError(f"printer profile {path}: unknown field(s) {', '.join(unknown)}; a {kind} profile has "
                         f"{', '.join(sorted(allowed))}", parameter="printer")
    values = dict(data)
    values.setdefault("name", path.stem)
    try:
        if kind == "fdm":
            _fdm_defaults(values)
        missing = sorted(allowed - set(values))
        if missing:
            raise InputError(f"missing field(s) {', '.join(missing)}")
        if not isinstance(values["name"], str) or not values["name"]:
            raise InputError("\"name\" must be a non-empty string")
        return cls(**values, source=f"custom profile {path.name}")
    except InputError as err:
        raise InputError(f"printer profile {path}: {err}", parameter="printer") from None


def _fdm_defaults(values: dict) -> None:
    """An FDM profile's defaults set in ``values``: the line width from the nozzle (checked first, so that a nozzle
    that is no number is named as such) and PrusaSlicer's gap closing radius."""
    if "nozzle_mm" in values:
        values.setdefault("line_width_mm", AUTO_WIDTH * real("nozzle_mm", values["nozzle_mm"]))
    values.setdefault("closing_radius_mm", 0.049)


def _no_constant(name: str) -> None:
    raise ValueError(f"{name} is not a number (JSON has no NaN or Infinity)")


def printed(heightmap: Heightmap, profile: PrintProfile, periodic: bool = False) -> PrintResult:
    """The expected printed surface of ``heightmap`` by ``profile`` (module docstring).

    ``periodic``: the map is one tile of a periodic texture (the filters wrap); otherwise its edges
    continue their edge values.
    """
    mode = "wrap" if periodic else "nearest"
    h = heightmap.heights
    base = float(h.min())
    relief = float(h.max()) - base
    layers = relief / profile.layer_mm
    check_size(f"print layers of the {relief:g} mm relief at {profile.layer_mm:g} mm", layers + 1, MAX_PRINT_LAYERS,
               "printer")
    _check_work(h.size, layers + 1, heightmap.pixel_mm, profile)
    notes = []
    if relief < 0.5 * profile.layer_mm:
        notes.append(f"the texture's relief {relief:.3g} mm is below half a {profile.layer_mm:g} mm layer: it prints "
                     "flat")
    if isinstance(profile, FdmProfile):
        out, steps = _fdm(h, base, heightmap.pixel_mm, profile, mode, notes)
    else:
        out, steps = _sla(h, base, heightmap.pixel_mm, profile, mode, notes)
    return PrintResult(Heightmap(out, heightmap.pixel_mm), profile, tuple(steps), tuple(notes))


def _quantised(h: np.ndarray, base: float, layer_mm: float) -> np.ndarray:
    """Heights rounded to whole layers above ``base`` (a layer prints where the model reaches its middle)."""
    return base + layer_mm * np.floor((h - base) / layer_mm + 0.5)


def _check_work(pixels: int, layers: float, pixel_mm: float, profile: PrintProfile) -> None:
    """InputError (parameter ``printer``) if printing a map of ``pixels`` with ``layers`` layers would filter more
    than MAX_LAYER_PIXELS layer-pixels or MAX_FILTER_TAPS pixel-taps (nothing is allocated to find out)."""
    if isinstance(profile, FdmProfile):
        per_layer = True  # the bead ends
        radii = [profile.closing_radius_mm / pixel_mm, profile.line_width_mm / pixel_mm / 2]
        taps = pixels * sum(2 * (2 * math.floor(r) + 1) for r in radii if r >= 1)  # two passes (min, max) per disk
        what = f"the {profile.line_width_mm:g} mm bead's disk filters on {pixels:,} pixels of {pixel_mm:g} mm"
    else:
        sigma_px = profile.bleed_mm / pixel_mm
        per_layer = sigma_px >= MIN_BLEED_PIXELS
        taps = pixels * layers * _gaussian_taps(sigma_px) if per_layer else 0
        what = f"the {1e3 * profile.bleed_mm:g} um light bleed on {pixels:,} pixels of {pixel_mm:g} mm, each layer"
    if per_layer:
        _check_print(f"layers x pixels the print filters ({layers:,.0f} layers of {pixels:,} pixels, each distinct "
                     "layer once)", layers * pixels, MAX_LAYER_PIXELS)
    _check_print(f"pixel-taps of {what}", taps, MAX_FILTER_TAPS)


def _check_print(what: str, count: float, limit: Limit) -> None:
    """``check_size`` for the print, naming ``printer`` and what would make the print smaller."""
    try:
        check_size(what, count, limit, "printer")
    except InputError as err:
        raise InputError(f"{err}: use a coarser or smaller map, or a profile with thicker layers or a narrower "
                         "bead", parameter="printer") from None


def _gaussian_taps(sigma_px: float) -> int:
    """Taps per pixel of scipy's Gaussian filter of ``sigma_px`` (its two 1-D kernels, truncated at 4 sigma)."""
    return 2 * (2 * int(4.0 * sigma_px + 0.5) + 1)


def _reach(radius_px: float) -> float:
    """``radius_px`` squared, widened by the pixel size's precision: a disk that reaches a pixel centre up to
    round-off (a 0.5 mm line on 0.0500001 mm pixels) reaches it."""
    return (radius_px * (1 + PIXEL_RTOL)) ** 2


def _disk_rows(radius_px: float) -> list[int]:
    """Half-widths (pixels) of the rows dy = 0, 1, ... of the disk of the pixels whose centres lie within
    ``radius_px`` of the centre pixel's."""
    r = int(math.floor(radius_px * (1 + PIXEL_RTOL)))
    return [math.isqrt(math.floor(_reach(radius_px) - dy * dy)) for dy in range(r + 1)]


def _disk_filter(h: np.ndarray, radius_px: float, mode: str, largest: bool) -> np.ndarray:
    """The largest (``largest``) or smallest value of ``h`` over the disk of ``radius_px`` around each pixel: scipy's
    grey dilation or erosion with that (flat, symmetric) footprint, as the extreme over the disk's rows of 1-D
    filters along x, each shifted by its row's dy. Memory a few maps, time a 1-D pass per row, whatever the disk."""
    from scipy import ndimage

    line_filter = ndimage.maximum_filter1d if largest else ndimage.minimum_filter1d
    extreme = np.maximum if largest else np.minimum
    rows = np.arange(h.shape[0])
    out = None
    for dy, half in enumerate(_disk_rows(radius_px)):
        line = line_filter(h, 2 * half + 1, axis=1, mode=mode)
        for shift in {dy, -dy}:
            index = (rows + shift) % len(rows) if mode == "wrap" else np.clip(rows + shift, 0, len(rows) - 1)
            out = line[index] if out is None else extreme(out, line[index], out=out)
    return out


def _rounded_edges(h: np.ndarray, base: float, layer_mm: float, pixel_mm: float, periodic: bool) -> np.ndarray:
    """Layered heights with each layer's edge rounded by the bead's semicircular end (radius half a layer).

    A pixel on top of layer k at horizontal distance d (mm) from that layer's edge lies lower by
    r - sqrt(r^2 - (r - d)^2) for d < r = layer / 2: down to the layer's middle at the edge itself.
    Each distinct layer is one distance transform (checked beforehand: MAX_LAYER_PIXELS).
    """
    from scipy import ndimage

    cap = layer_mm / 2
    levels = np.rint((h - base) / layer_mm).astype(np.int64)
    # Periodic: the wrapped neighbours within reach of the edge (beyond the cap the distance does not matter, and
    # one period holds every pixel). Else none: a pixel beyond the edge repeats an edge pixel, which is nearer.
    pad = min(int(math.ceil(cap / pixel_mm)) + 1, max(levels.shape)) if periodic else 0
    padded = np.pad(levels, pad, mode="wrap")
    inner = tuple(slice(pad, n + pad) for n in levels.shape)
    drop = np.zeros(levels.shape)
    for k in np.unique(levels[levels > 0]):
        layer = padded >= k
        if layer.all():  # the layer covers the map: it has no edge (and the transform no background to measure to)
            continue
        inside = ndimage.distance_transform_edt(layer)[inner]
        top = levels == k
        d = np.clip(inside[top] * pixel_mm - pixel_mm / 2, 0.0, cap)  # pixel centre to the edge between pixels
        drop[top] = cap - np.sqrt(cap**2 - (cap - d) ** 2)
    return h - drop


def _fdm(h: np.ndarray, base: float, pixel_mm: float, p: FdmProfile, mode: str, notes: list[str]) -> tuple:
    width_px = p.line_width_mm / pixel_mm
    if width_px < MIN_BEAD_PIXELS:
        raise InputError(f"the {p.line_width_mm:g} mm bead of printer {p.name} spans {width_px:.2f} pixels of "
                         f"{pixel_mm:g} mm: the nozzle's rounding cannot be represented at this resolution (it needs "
                         f"at least {MIN_BEAD_PIXELS} pixels per bead); resample the heightmap to at most "
                         f"{p.line_width_mm / COARSE_BEAD_PIXELS:g} mm pixels", parameter="printer")
    if width_px < COARSE_BEAD_PIXELS:
        notes.append(f"the {p.line_width_mm:g} mm bead spans only {width_px:.1f} pixels: its rounding is resolved "
                     f"roughly (pixels of at most {p.line_width_mm / COARSE_BEAD_PIXELS:g} mm resolve it)")
    steps = []
    closing_px = p.closing_radius_mm / pixel_mm
    if closing_px >= 1:
        h = _disk_filter(_disk_filter(h, closing_px, mode, largest=True), closing_px, mode, largest=False)
        steps.append(f"slicer gap closing: cracks narrower than {2 * p.closing_radius_mm:g} mm filled")
    elif p.closing_radius_mm > 0:
        notes.append(f"the slicer's {p.closing_radius_mm:g} mm gap closing is below one {pixel_mm:g} mm pixel: "
                     "no effect at this resolution")
    h = _quantised(h, base, p.layer_mm)
    steps.append(f"layer quantisation: heights rounded to whole {p.layer_mm:g} mm layers above the lowest point")
    h = _disk_filter(_disk_filter(h, width_px / 2, mode, largest=False), width_px / 2, mode, largest=True)
    steps.append(f"bead width: parts of a layer narrower than the {p.line_width_mm:g} mm line removed (opening with "
                 "a disk of the line width)")
    out = _rounded_edges(h, base, p.layer_mm, pixel_mm, mode == "wrap")
    steps.append(f"bead ends: each layer's edge rounded along a quarter circle of radius {p.layer_mm / 2:g} mm")
    return out, steps


def _sla(h: np.ndarray, base: float, pixel_mm: float, p: SlaProfile, mode: str, notes: list[str]) -> tuple:
    from scipy import ndimage

    levels = np.floor((h - base) / p.layer_mm + 0.5).astype(np.int64)
    steps = [f"layer quantisation: heights rounded to whole {p.layer_mm:g} mm layers above the lowest point"]
    if p.pixel_mm > pixel_mm:  # each LCD pixel takes the layer count at its centre; each map pixel, its LCD pixel's
        levels = levels[np.ix_(_lcd_pixels(levels.shape[0], pixel_mm, p.pixel_mm),
                               _lcd_pixels(levels.shape[1], pixel_mm, p.pixel_mm))]
        steps.append(f"exposure on the printer's {1e3 * p.pixel_mm:g} um pixel grid")
    else:
        notes.append(f"the printer's {1e3 * p.pixel_mm:g} um pixel is not coarser than the map's {1e3 * pixel_mm:g} "
                     "um: its pixel grid has no effect at this resolution")
    sigma_px = p.bleed_mm / pixel_mm
    if sigma_px >= MIN_BLEED_PIXELS:
        cured = np.zeros(levels.shape, dtype=np.int64)
        below = 0
        for k in np.unique(levels[levels > 0]):  # layers below + 1 .. k expose one set: filtered once, counted each
            cured += (k - below) * (ndimage.gaussian_filter((levels >= k).astype(float), sigma_px, mode=mode) >= 0.5)
            below = k
        levels = cured
        steps.append(f"light bleed: each layer's exposure blurred by {1e3 * p.bleed_mm:g} um (Gaussian), cured "
                     "where it reaches half the dose")
    elif p.bleed_mm > 0:
        notes.append(f"the {1e3 * p.bleed_mm:g} um light bleed is below half a {1e3 * pixel_mm:g} um map pixel: no "
                     "effect at this resolution")
    return base + p.layer_mm * levels, steps


def _lcd_pixels(n: int, pixel_mm: float, lcd_mm: float) -> np.ndarray:
    """For each of ``n`` map pixels along an axis, the map pixel at the centre of the LCD pixel its centre lies in
    (LCD grid aligned with the map's origin)."""
    lcd = np.floor((np.arange(n) + 0.5) * pixel_mm / lcd_mm)
    return np.minimum(((lcd + 0.5) * lcd_mm / pixel_mm).astype(np.intp), n - 1)
