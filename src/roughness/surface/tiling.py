"""Can a small patch stand for a texture when tiled? Its size in feature lengths and its seams.

Tiling (``--tile``) repeats a patch as one period of a periodic texture. It answers for the
texture only if the patch holds several of its features and wraps without a seam: a patch
cut from a random texture has a step at each wrap, a line of artificial features repeated
every patch width. Both are measured from the patch itself:

- ``periods``: the patch's shorter side over its feature length (2 pi std(H) / RMS slope,
  ``Heightmap.feature_size_mm``; 1.3-1.7 lambda on the standard bump textures);
- ``seam``: the RMS height jump across the wrap over the RMS step between neighbouring pixels
  inside, the larger of the two axes (about 1 for a seamless tile, 5-15 for a cut patch).

The limits come from studies/small_scans.py (results/small_scans.md), measured with the
spectral engine on standard textures against the full 12 mm maps they came from.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError
from roughness.core.limits import HEIGHT_RTOL
from roughness.perceptual_scale import FLOOR_LAMBDA_MM

from .heightmap import Heightmap

MIN_PERIODS = 5.0  # below: worst error 0.9-2.6 JND; from 5 on at most 0.86 (studies/results/small_scans.md)
MAX_SEAM = 2.5  # seamless tiles measure 0.45-1.33, cut patches 3.9-13.8
FOOTPRINT_MM = 10.0  # the fingertip's skin footprint (SimConfig.width_mm), for messages
MIN_SIDE_MM = MIN_PERIODS * FLOOR_LAMBDA_MM  # 1 mm: narrower, a scan is too small to feel even tiled (check_touchable)


@dataclass(frozen=True)
class TileFit:
    """How a patch tiles: its shorter side (mm), feature length (mm), ``periods`` and ``seam`` (see module)."""

    side_mm: float
    feature_mm: float
    periods: float
    seam: float

    @property
    def seamless(self) -> bool:
        return self.seam <= MAX_SEAM

    def notes(self) -> list[str]:
        """What tiling this patch risks, in words (empty: nothing measured against it)."""
        out = []
        size = f"{self.side_mm:.2f} mm across, {self.periods:.1f} feature lengths of {self.feature_mm:.2f} mm"
        if self.periods < MIN_PERIODS and self.seamless:
            out.append(f"tiled patch {size}: exact for a periodic design's unit cell, but a patch of a random "
                       f"texture this small read up to 2.1 JND off its full map (fewer than {MIN_PERIODS:g} feature "
                       "lengths; studies/results/small_scans.md)")
        if not self.seamless and self.periods >= MIN_PERIODS:
            out.append(f"tiled patch is not periodic (its heights jump across the wrap {self.seam:.1f} times the step "
                       f"between pixels): seams every {self.side_mm:.2f} mm; at {MIN_PERIODS:g} feature lengths or "
                       "more such patches read within 0.9 JND of their full maps (studies/results/small_scans.md)")
        return out


def tile_fit(hm: Heightmap) -> TileFit:
    """The measures of ``hm`` as a tile (a flat patch: infinitely many periods, no seam).

    An axis along which the heights change by no more than their precision (HEIGHT_RTOL times the largest
    |height|: round-off, as along a grating's ridges) has no seam."""
    side = min(hm.size_mm)
    feature = hm.feature_size_mm()
    h = hm.heights
    resolution = HEIGHT_RTOL * float(np.abs(h).max())
    seams = []
    for axis in (0, 1):
        inside = np.diff(h, axis=axis)
        wrap = np.take(h, 0, axis=axis) - np.take(h, -1, axis=axis)
        step = math.sqrt(float(np.mean(inside**2)))
        seams.append(math.sqrt(float(np.mean(wrap**2))) / step if step > resolution else 0.0)
    return TileFit(side, feature, side / feature if math.isfinite(feature) else math.inf, max(seams))


def check_touchable(hm: Heightmap, source: str) -> None:
    """InputError for a map whose shorter side is below MIN_SIDE_MM (1 mm): too small to feel, even tiled.

    Tiled, a patch repeats every side, so its relief is either finer than the standard scale's floor wavelength
    (FLOOR_LAMBDA_MM, 0.2 mm: below it the scale places no texture and V is within a few times the engines' noise
    of zero) or holds fewer than MIN_PERIODS features of it, and such patches read up to 2.6 JND off the texture
    they were cut from. For maps whose units the file states (a scan): for others a tiny size is more likely a
    unit mistake, which roughness.surface.units names."""
    width, height = hm.size_mm
    if min(width, height) >= MIN_SIDE_MM:
        return
    raise InputError(
        f"{source}: the scan covers {width:.3g} mm x {height:.3g} mm; a fingertip footprint is {FOOTPRINT_MM:g} mm: "
        f"too small to feel, even tiled (a tiled patch narrower than {MIN_SIDE_MM:g} mm holds only relief finer than "
        f"the {FLOOR_LAMBDA_MM:g} mm the standard scale can feel, or fewer than {MIN_PERIODS:g} features, whose "
        "tiling misleads by up to 2.6 JND: studies/results/small_scans.md); its units are the file's. Scan an area "
        f"of at least {FOOTPRINT_MM:g} mm x {FOOTPRINT_MM:g} mm (or at least {MIN_SIDE_MM:g} mm of a periodic "
        "texture, and pass --tile)")


def check_tile(hm: Heightmap, source: str, footprint_mm: float) -> TileFit | None:
    """How ``hm`` tiles if it is smaller than the footprint (else None: tiling does not fill it); InputError
    (parameter ``tile``) for a patch both small and not periodic, whose tiling is measured to mislead."""
    if min(hm.size_mm) >= footprint_mm:
        return None
    fit = tile_fit(hm)
    if fit.periods < MIN_PERIODS and not fit.seamless:
        width, height = hm.size_mm
        raise InputError(
            f"{source}: the {width:.2f} mm x {height:.2f} mm patch is too small to tile: "
            f"{fit.periods:.1f} feature lengths of {fit.feature_mm:.2f} mm (fewer than {MIN_PERIODS:g}) and not "
            f"periodic (heights jump across the wrap {fit.seam:.1f} times the step between pixels, more than "
            f"{MAX_SEAM:g}); such patches read up to 2.6 JND off the full texture (studies/results/small_scans.md). "
            f"Scan at least {MIN_PERIODS * fit.feature_mm:.1f} mm, or make the patch a seamless tile",
            parameter="tile")
    return fit
