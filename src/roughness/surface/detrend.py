"""Shape and texture of one height map (a scan of a curved object), separated by a spectral low-pass.

The shape is what varies slower than the cut-off wavelength: a least-squares quadratic
(most of a cylinder's or sphere's sag) plus a Gaussian low-pass of the rest, whose gain is
1/2 at the cut-off wavelength (computed by FFT on the mirror-extended map, so the map's
edges do not ring). The texture is the map minus its shape. When no cut-off is given it is
``CUTOFF_WAVELENGTHS`` times the texture's dominant wavelength, the peak of the radially
averaged power spectrum of the quadratic-free map.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.core.limits import MAX_LENGTH_MM, MAX_WORKING_VALUES, check_size

from .cleanup import polynomial_fit
from .heightmap import Heightmap

METHODS = ("lowpass",)
# Default cut-off: this many dominant texture wavelengths. Measured at coarse fidelity on standard
# textures (lambda 0.75/1.0/1.25 mm, 12 mm maps): flat maps change V by at most 1.55% at 8, 0.50% at
# 12, 0.22% at 16; maps on cylinders of R = +-8 mm are recovered within 0.35% at 8, 1.56% at 12 and
# 2.42% at 16 (the longer cut-off leaves more of the shape beyond its quadratic fit). 12 keeps both
# within the targets (flat < 1%, curved < 5%).
CUTOFF_WAVELENGTHS = 12.0
LONGEST_TEXTURE_FRACTION = 0.25  # the texture's wavelength is sought below this fraction of the map's side
# Map-sized float arrays detrend holds at once (measured: the mirrored map, its spectrum and the 2-D FFT's
# intermediate are 4 each).
DETREND_MAPS = 14


@dataclass(frozen=True)
class Detrend:
    """How to separate shape and texture: ``method`` and its cut-off wavelength (mm; None: chosen from the map)."""

    method: str = "lowpass"
    cutoff_mm: float | None = None

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise InputError(f"detrend method must be one of {', '.join(METHODS)}; got {self.method!r}",
                             parameter="detrend")
        if self.cutoff_mm is not None:
            positive("cutoff_mm", self.cutoff_mm)


@dataclass(frozen=True)
class Separation:
    """What was removed: the cut-off (mm), whether it was chosen from the map, the texture's dominant
    wavelength (mm) and the removed shape's peak-to-valley height (mm)."""

    cutoff_mm: float
    chosen: bool
    texture_wavelength_mm: float
    shape_relief_mm: float

    def describe(self) -> str:
        how = (f"{CUTOFF_WAVELENGTHS:g} x the texture's dominant wavelength {self.texture_wavelength_mm:.3g} mm"
               if self.chosen else "given")
        return (f"removed the shape slower than {self.cutoff_mm:.3g} mm ({how}): "
                f"{self.shape_relief_mm:.3g} mm peak to valley")


def parse_detrend(text: str) -> Detrend:
    """``lowpass`` or ``lowpass:CUTOFF_MM`` as a ``Detrend``; InputError otherwise."""
    method, _, cutoff = text.partition(":")
    if method not in METHODS:
        raise InputError(f"expected lowpass or lowpass:CUTOFF_MM, got {text!r}", parameter="detrend")
    if not cutoff:
        return Detrend(method)
    try:
        value = float(cutoff)
    except ValueError:
        raise InputError(f"the cut-off in {text!r} must be a number of mm", parameter="detrend") from None
    if not (math.isfinite(value) and 0 < value <= MAX_LENGTH_MM):
        raise InputError(f"the cut-off in {text!r} must be a number of mm above 0 and at most {MAX_LENGTH_MM:g} "
                         "(MAX_LENGTH_MM)", parameter="detrend")
    return Detrend(method, value)


def detrend(heightmap: Heightmap, spec: Detrend = Detrend()) -> tuple[Heightmap, Separation]:
    """The texture of ``heightmap`` (its shape removed) and what was removed; its working arrays (DETREND_MAPS
    maps) are checked against MAX_WORKING_VALUES first."""
    heights = heightmap.heights
    check_size(f"values the low-pass holds at once ({DETREND_MAPS} maps of {heights.size:,} pixels)",
               DETREND_MAPS * heights.size, MAX_WORKING_VALUES, "detrend")
    p = heightmap.pixel_mm
    wavelength = dominant_wavelength_mm(heights - quadratic_fit(heights), p)
    cutoff = spec.cutoff_mm if spec.cutoff_mm is not None else CUTOFF_WAVELENGTHS * wavelength
    shape = lowpass(heights, p, cutoff)
    texture = heights - shape
    return Heightmap(texture - texture.min(), p), Separation(cutoff, spec.cutoff_mm is None, wavelength,
                                                              float(shape.max() - shape.min()))


def quadratic_fit(heights: np.ndarray) -> np.ndarray:
    """Least-squares quadratic surface in the pixel coordinates (cleanup.polynomial_fit of degree 2)."""
    return polynomial_fit(heights, 2)


def lowpass(heights: np.ndarray, pixel_mm: float, cutoff_mm: float) -> np.ndarray:
    """The part of ``heights`` slower than ``cutoff_mm`` (Gaussian gain 1/2 there) over a quadratic fit."""
    trend = quadratic_fit(heights)
    rest = heights - trend
    ny, nx = rest.shape
    mirrored = np.pad(rest, ((0, ny), (0, nx)), mode="symmetric")
    spectrum = np.fft.rfft2(mirrored)
    del mirrored
    for f in (np.fft.fftfreq(2 * ny, pixel_mm)[:, None], np.fft.rfftfreq(2 * nx, pixel_mm)[None, :]):
        spectrum *= np.exp(-math.log(2) * (f * cutoff_mm) ** 2)  # the Gaussian gain, separable: one axis at a time
    return trend + np.fft.irfft2(spectrum, s=(2 * ny, 2 * nx))[:ny, :nx]


def dominant_wavelength_mm(heights: np.ndarray, pixel_mm: float) -> float:
    """Wavelength (mm) at the peak of the radially averaged power spectrum, below a quarter of the map's side."""
    ny, nx = heights.shape
    side = min(nx, ny) * pixel_mm
    window = np.outer(np.hanning(ny), np.hanning(nx))
    power = np.abs(np.fft.rfft2((heights - heights.mean()) * window)) ** 2
    f = np.hypot(np.fft.fftfreq(ny, pixel_mm)[:, None], np.fft.rfftfreq(nx, pixel_mm)[None, :])
    ring = np.rint(f * side).astype(int)  # radial bins of width 1/side
    counts = np.bincount(ring.ravel())
    mean = np.bincount(ring.ravel(), power.ravel()) / np.maximum(counts, 1)
    first = math.ceil(1 / LONGEST_TEXTURE_FRACTION)
    if len(mean) <= first + 1 or not np.any(mean[first:] > 0):
        raise InputError("the height map has no texture to separate from its shape (no relief at wavelengths "
                         f"below {LONGEST_TEXTURE_FRACTION * side:.3g} mm); give the cut-off: lowpass:CUTOFF_MM",
                         parameter="detrend")
    peak = first + int(np.argmax(mean[first:]))
    return side / peak
