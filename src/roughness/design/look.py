"""How a texture looks: its heights rendered as a single-material print seen from above, and two regions compared.

Rendering (``render``): a matte (Lambertian) surface of one colour, albedo 1, seen from straight above, lit by
``AZIMUTHS`` lights at ``ELEVATION_DEG`` elevation spaced evenly around the compass, averaged. Each light is a
distant point source: a pixel facing it gets cos(angle to the light), a pixel facing away or in the cast shadow
of higher ground along the light's direction gets 0. Eight azimuths at 45 degrees stand for a plate held under
room light and turned in the hand: no direction is favoured, so what remains is what any light shows (steep
flanks darker than tops and floor, deep narrow valleys shaded out), not one light's highlights. There is no
ambient term: a pixel no light reaches is black. Beyond the map's edges the texture continues as its mirror image
(as the spectral engine extends it), so that a plate's rim is not lit as if nothing stood beside it.

Comparison (``compare``): the luminance of the pixels of region A (e.g. inside a shape) against region B
(outside): the Weber contrast of their mean luminance, (mean A - mean B) / mean B, and the Wasserstein-1
distance between their luminance distributions over mean B (the same units: a difference of means alone
gives |Weber|, a different texture of light and dark at the same mean gives more). ``difference`` is the larger
of the two, in units of ``THRESHOLD`` ("look JND"): 1 and above is taken as visible.

Assumption (the visibility threshold): ``THRESHOLD`` = 0.02, a 2% contrast. At a plate's viewing distance of
about 400 mm a shape 20-60 mm across subtends 3-9 degrees; its outline's contrast lies at 0.3-3 cycles/degree,
where human contrast sensitivity is about 50-200 (a threshold of 0.5-2%: Barten, "Contrast Sensitivity of the
Human Eye and Its Effects on Image Quality", SPIE 1999; Weber's fraction for luminance increments on large
fields, about 1-2%). The texture's own bumps (a few cycles/degree at 400 mm, contrast tens of %) mask the
shape, so the upper end is taken. It is an assumption of this measure, not a measurement of an observer.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import wasserstein_distance

from roughness.core.checks import in_range, integer
from roughness.core.errors import InputError
from roughness.core.reprs import short_repr
from roughness.surface.heightmap import Heightmap

ELEVATION_DEG = 45.0
AZIMUTHS = 8
THRESHOLD = 0.02  # contrast at which a region is taken as visible (module docstring: an assumption, with its source)
MIN_REGION_PIXELS = 16  # a region of fewer pixels has no luminance statistics to speak of


@dataclass(frozen=True)
class LookDifference:
    """How different region A looks from region B (dimensionless contrasts, and in units of ``THRESHOLD``)."""

    weber_contrast: float  # (mean luminance A - mean luminance B) / mean luminance B
    distribution_distance: float  # Wasserstein-1 distance of the luminance distributions / mean luminance B
    mean_a: float  # mean luminance (0..1) of region A
    mean_b: float
    threshold: float = THRESHOLD

    def __repr__(self) -> str:
        return short_repr(self, f"{self.difference:.2f} look JND", f"Weber {self.weber_contrast:+.4f}",
                          f"distribution {self.distribution_distance:.4f}", self.verdict)

    @property
    def difference(self) -> float:
        """The larger of |Weber contrast| and the distribution distance, in units of the threshold."""
        return max(abs(self.weber_contrast), self.distribution_distance) / self.threshold

    @property
    def verdict(self) -> str:
        return "visible" if self.difference >= 1 else "not visible"

    def as_dict(self) -> dict:
        return {"weber_contrast": self.weber_contrast, "distribution_distance": self.distribution_distance,
                "mean_luminance_a": self.mean_a, "mean_luminance_b": self.mean_b,
                "difference_look_jnd": self.difference, "threshold_contrast": self.threshold, "verdict": self.verdict,
                "definition": f"Lambertian single-material print seen from above, {AZIMUTHS} lights at "
                              f"{ELEVATION_DEG:g} deg elevation averaged, cast shadows; look JND = max(|Weber "
                              "contrast of mean luminance|, Wasserstein-1 of the luminance distributions / mean B) "
                              f"/ {self.threshold:g} (assumed visibility threshold)"}


def render(heightmap: Heightmap, elevation_deg: float = ELEVATION_DEG, azimuths: int = AZIMUTHS) -> np.ndarray:
    """Luminance (0..1, rows = y) of ``heightmap`` (mm) as a matte print seen from above, lit as the module says."""
    elevation = math.radians(in_range("elevation_deg", elevation_deg, 1.0, 90.0))
    azimuths = integer("azimuths", azimuths, minimum=1)
    h, pixel = heightmap.heights, heightmap.pixel_mm
    gy, gx = np.gradient(h, pixel)
    norm = np.sqrt(1 + gx**2 + gy**2)
    total = np.zeros(h.shape)
    for k in range(azimuths):
        azimuth = 2 * math.pi * k / azimuths
        lx, ly = math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth)
        lit = np.clip((-gx * lx - gy * ly + math.sin(elevation)) / norm, 0.0, None)
        total += lit * ~_shadowed(h, pixel, azimuth, math.tan(elevation))
    return total / azimuths


def _shadowed(h: np.ndarray, pixel_mm: float, azimuth: float, slope: float) -> np.ndarray:
    """Pixels in the cast shadow of higher ground toward the light (azimuth in radians, light rising at ``slope``):
    marched a pixel's length at a time (nearest pixel) until the ray clears the map's highest point."""
    dx, dy = math.cos(azimuth), math.sin(azimuth)
    steps = int(math.ceil(float(np.ptp(h)) / slope / pixel_mm))
    ny, nx = h.shape
    pad = steps + 1
    padded = np.pad(h, pad, mode="symmetric")  # the texture mirrored beyond the map's edges
    shadow = np.zeros(h.shape, dtype=bool)
    for s in range(1, steps + 1):
        i, j = pad + round(s * dy), pad + round(s * dx)
        shadow |= padded[i:i + ny, j:j + nx] > h + s * pixel_mm * slope
    return shadow


def compare(luminance: np.ndarray, region_a: np.ndarray, region_b: np.ndarray) -> LookDifference:
    """How region A (a boolean mask over ``luminance``) looks beside region B; InputError if either has fewer than
    ``MIN_REGION_PIXELS`` pixels or B is black."""
    for name, region in (("region_a", region_a), ("region_b", region_b)):
        if np.shape(region) != np.shape(luminance):
            raise InputError(f"{name} is {np.shape(region)}, the luminance {np.shape(luminance)}", parameter=name)
        if np.count_nonzero(region) < MIN_REGION_PIXELS:
            raise InputError(f"{name} has {np.count_nonzero(region)} pixels: at least {MIN_REGION_PIXELS} are needed "
                             "to compare how regions look", parameter=name)
    a, b = luminance[region_a], luminance[region_b]
    mean_a, mean_b = float(a.mean()), float(b.mean())
    if mean_b <= 0:
        raise InputError("region B is black under every light: no contrast is defined against it", parameter="region_b")
    return LookDifference((mean_a - mean_b) / mean_b, float(wasserstein_distance(a, b)) / mean_b, mean_a, mean_b)


def look_difference(a: Heightmap, b: Heightmap) -> LookDifference:
    """How texture ``a`` looks beside texture ``b`` (each rendered whole, on its own)."""
    both = np.concatenate([render(a).ravel(), render(b).ravel()])
    first = np.arange(both.size) < a.heights.size
    return compare(both, first, ~first)


def look_distances(heightmaps: Sequence[Heightmap]) -> np.ndarray:
    """(K, K) look difference (look JND) of texture i beside texture j, each rendered whole once; 0 on the diagonal."""
    lum = [render(hm).ravel() for hm in heightmaps]
    out = np.zeros((len(lum), len(lum)))
    for i, a in enumerate(lum):
        for j, b in enumerate(lum):
            if i != j:
                both = np.concatenate([a, b])
                first = np.arange(both.size) < a.size
                out[i, j] = compare(both, first, ~first).difference
    return out
