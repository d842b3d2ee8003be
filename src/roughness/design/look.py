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
(outside), three ways, each in units of its threshold ("look JND"); ``difference`` is the largest, and 1 and
above is taken as visible:

* the Weber contrast of their mean luminance, (mean A - mean B) / mean B, over ``THRESHOLD``;
* the Wasserstein-1 distance between their luminance distributions over mean B (the same units: a difference of
  means alone gives |Weber|, a different mix of light and dark at the same mean gives more), over ``THRESHOLD``;
* the texture of light and dark, band by band: the luminance filtered by a difference of Gaussians (sigma and
  2 sigma, ``BAND_SIGMAS_MM``, octaves from the bumps' flanks to their spacing), its RMS over each region divided
  by mean B (the band's contrast, c_A and c_B), and |c_A - c_B| over the contrast-discrimination threshold
  sqrt(THRESHOLD^2 + (CONTRAST_FRACTION c_B)^2). This is what the two above cannot see: the same bumps laid
  closer together, or scaled as a whole, have the same luminance histogram but move contrast from one band to
  the next.

Assumption (the visibility threshold): ``THRESHOLD`` = 0.02, a 2% contrast. At a plate's viewing distance of
about 400 mm a shape 20-60 mm across subtends 3-9 degrees; its outline's contrast lies at 0.3-3 cycles/degree,
where human contrast sensitivity is about 50-200 (a threshold of 0.5-2%: Barten, "Contrast Sensitivity of the
Human Eye and Its Effects on Image Quality", SPIE 1999; Weber's fraction for luminance increments on large
fields, about 1-2%). The texture's own bumps (a few cycles/degree at 400 mm, contrast tens of %) mask the
shape, so the upper end is taken. It is an assumption of this measure, not a measurement of an observer.
Contrast discrimination above threshold follows Weber's law for contrast: an increment is seen at about 10-20% of
the contrast already there (Legge and Foley, "Contrast masking in human vision", JOSA 70, 1980); ``CONTRAST_FRACTION``
takes 15%, an assumption in the same way.

Display (``photograph``): luminance is linear in light; shown as a grey picture at its linear values, a plate's
mostly dark relief lands in the screen's darkest codes, where differences the eye would see on the plate vanish.
Pictures of the look are therefore shown as a photograph would record them: white at the plate's brightest
(99.5th percentile) pixels, sRGB-like gamma 1/2.2.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import in_range, integer, positive
from roughness.core.errors import InputError
from roughness.core.reprs import short_repr
from roughness.surface.heightmap import Heightmap

ELEVATION_DEG = 45.0
AZIMUTHS = 8
THRESHOLD = 0.02  # contrast at which a region is taken as visible (module docstring: an assumption, with its source)
CONTRAST_FRACTION = 0.15  # a band's contrast is told apart when it changes by this fraction of itself (an assumption)
BAND_SIGMAS_MM = (0.1, 0.2, 0.4, 0.8)  # difference-of-Gaussian bands (sigma, 2 sigma), mm
DISPLAY_GAMMA = 2.2
DISPLAY_WHITE_PERCENTILE = 99.5
MIN_REGION_PIXELS = 16  # a region of fewer pixels has no luminance statistics to speak of
BAND_MM = 1.0  # regions are compared this far from their borders, clear of the shadows one casts on the other
RENDERING = (f"Lambertian single-material print seen from above, {AZIMUTHS} lights at {ELEVATION_DEG:g} deg elevation "
             "averaged, cast shadows")  # how every luminance here is made, in the words of the JSON's definitions


@dataclass(frozen=True)
class LookDifference:
    """How different region A looks from region B (dimensionless contrasts, and in units of ``THRESHOLD``)."""

    weber_contrast: float  # (mean luminance A - mean luminance B) / mean luminance B
    distribution_distance: float  # Wasserstein-1 distance of the luminance distributions / mean luminance B
    mean_a: float  # mean luminance (0..1) of region A
    mean_b: float
    band_contrasts_a: tuple[float, ...]  # RMS of each band (BAND_SIGMAS_MM) over region A / mean luminance B
    band_contrasts_b: tuple[float, ...]
    threshold: float = THRESHOLD

    def __repr__(self) -> str:
        return short_repr(self, f"{self.difference:.2f} look JND", f"Weber {self.weber_contrast:+.4f}",
                          f"distribution {self.distribution_distance:.4f}", f"texture {self.texture_difference:.2f}",
                          self.verdict)

    @property
    def texture_difference(self) -> float:
        """The largest band's contrast difference over its discrimination threshold (look JND)."""
        return max((abs(a - b) / np.hypot(self.threshold, CONTRAST_FRACTION * b)
                    for a, b in zip(self.band_contrasts_a, self.band_contrasts_b, strict=True)), default=0.0)

    @property
    def difference(self) -> float:
        """The largest of |Weber contrast| and the distribution distance over the threshold, and the texture
        difference (look JND)."""
        return max(max(abs(self.weber_contrast), self.distribution_distance) / self.threshold,
                   self.texture_difference)

    @property
    def verdict(self) -> str:
        return "visible" if self.difference >= 1 else "not visible"

    def as_dict(self) -> dict:
        return {"weber_contrast": self.weber_contrast, "distribution_distance": self.distribution_distance,
                "mean_luminance_a": self.mean_a, "mean_luminance_b": self.mean_b,
                "band_sigmas_mm": list(BAND_SIGMAS_MM), "band_contrasts_a": list(self.band_contrasts_a),
                "band_contrasts_b": list(self.band_contrasts_b), "texture_difference_look_jnd": self.texture_difference,
                "difference_look_jnd": self.difference, "threshold_contrast": self.threshold, "verdict": self.verdict,
                "definition": f"{RENDERING}; look JND = the largest of |Weber contrast of mean luminance| and the "
                              "Wasserstein-1 distance of the luminance distributions / mean B, over "
                              f"{self.threshold:g} (assumed visibility threshold), and each difference-of-Gaussian "
                              "band's contrast difference over sqrt(threshold^2 + "
                              f"({CONTRAST_FRACTION:g} x its contrast in B)^2)"}


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


@dataclass(frozen=True)
class RegionLook:
    """What the comparison needs of one region: its pixels' luminance (0..1) and each band's mean square
    (``BAND_SIGMAS_MM``; luminance units squared)."""

    luminance: np.ndarray
    band_power: tuple[float, ...]


def bands(luminance: np.ndarray, pixel_mm: float) -> list[np.ndarray]:
    """``luminance`` filtered by each difference-of-Gaussians band (``BAND_SIGMAS_MM``; mirrored at the edges)."""
    from scipy import ndimage  # not at import: predict renders looks without it (0.3 s)

    pixel_mm = positive("pixel_mm", pixel_mm)
    blurred = {s: ndimage.gaussian_filter(luminance, s / pixel_mm, mode="reflect")
               for s in sorted({*BAND_SIGMAS_MM, *(2 * s for s in BAND_SIGMAS_MM)})}
    return [blurred[s] - blurred[2 * s] for s in BAND_SIGMAS_MM]


def region_look(luminance: np.ndarray, region: np.ndarray, filtered: list[np.ndarray], name: str) -> RegionLook:
    """The look of ``region`` (a boolean mask over ``luminance``) with the ``filtered`` bands of the same image;
    InputError if it is the wrong shape or has fewer than ``MIN_REGION_PIXELS`` pixels."""
    if np.shape(region) != np.shape(luminance):
        raise InputError(f"{name} is {np.shape(region)}, the luminance {np.shape(luminance)}", parameter=name)
    if np.count_nonzero(region) < MIN_REGION_PIXELS:
        raise InputError(f"{name} has {np.count_nonzero(region)} pixels: at least {MIN_REGION_PIXELS} are needed "
                         "to compare how regions look", parameter=name)
    return RegionLook(luminance[region], tuple(float(np.mean(b[region] ** 2)) for b in filtered))


def whole_look(heightmap: Heightmap, luminance: np.ndarray | None = None) -> RegionLook:
    """The look of a whole texture, rendered on its own (``luminance``: its ``render``, if already made)."""
    luminance = render(heightmap) if luminance is None else luminance
    return region_look(luminance, np.ones(luminance.shape, dtype=bool), bands(luminance, heightmap.pixel_mm),
                       "texture")


def compare_looks(a: RegionLook, b: RegionLook) -> LookDifference:
    """How region ``a`` looks beside region ``b`` (module docstring); InputError if ``b`` is black."""
    mean_a, mean_b = float(a.luminance.mean()), float(b.luminance.mean())
    if mean_b <= 0:
        raise InputError("region B is black under every light: no contrast is defined against it", parameter="region_b")
    return LookDifference((mean_a - mean_b) / mean_b, float(wasserstein_distance(a.luminance, b.luminance)) / mean_b,
                          mean_a, mean_b, tuple(float(np.sqrt(p)) / mean_b for p in a.band_power),
                          tuple(float(np.sqrt(p)) / mean_b for p in b.band_power))


def compare(luminance: np.ndarray, region_a: np.ndarray, region_b: np.ndarray, pixel_mm: float) -> LookDifference:
    """How region A (a boolean mask over ``luminance``, pixels ``pixel_mm`` mm) looks beside region B; InputError if
    either has fewer than ``MIN_REGION_PIXELS`` pixels or B is black."""
    filtered = bands(luminance, pixel_mm)
    return compare_looks(region_look(luminance, region_a, filtered, "region_a"),
                         region_look(luminance, region_b, filtered, "region_b"))


def look_difference(a: Heightmap, b: Heightmap) -> LookDifference:
    """How texture ``a`` looks beside texture ``b`` (each rendered whole, on its own)."""
    return compare_looks(whole_look(a), whole_look(b))


def look_distances(heightmaps: Sequence[Heightmap]) -> np.ndarray:
    """(K, K) look difference (look JND) of texture i beside texture j, each rendered whole once; 0 on the diagonal."""
    looks = [whole_look(hm) for hm in heightmaps]
    out = np.zeros((len(looks), len(looks)))
    for i, a in enumerate(looks):
        for j, b in enumerate(looks):
            if i != j:
                out[i, j] = compare_looks(a, b).difference
    return out


def photograph(luminance: np.ndarray) -> np.ndarray:
    """``luminance`` as a photograph records it (module docstring, Display): 0..1, white at the
    ``DISPLAY_WHITE_PERCENTILE`` percentile, gamma 1/``DISPLAY_GAMMA``."""
    white = float(np.percentile(luminance, DISPLAY_WHITE_PERCENTILE))
    if white <= 0:
        return np.zeros_like(luminance)
    return np.clip(luminance / white, 0.0, 1.0) ** (1 / DISPLAY_GAMMA)



def wasserstein_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Wasserstein-1 distance between the empirical distributions of the values ``a`` and ``b``: the area between
    their cumulative distributions (``scipy.stats.wasserstein_distance``'s arithmetic, in numpy: importing
    scipy.stats takes about 0.6 s, more than a whole ``predict``)."""
    a, b = np.sort(np.ravel(a)), np.sort(np.ravel(b))
    values = np.sort(np.concatenate([a, b]), kind="mergesort")
    below_a = np.searchsorted(a, values[:-1], side="right") / a.size
    below_b = np.searchsorted(b, values[:-1], side="right") / b.size
    return float(np.sum(np.abs(below_a - below_b) * np.diff(values)))


@dataclass(frozen=True)
class TextureLook:
    """How one texture looks on its own: its rendered luminance's mean (0..1) and contrast (std / mean)."""

    mean_luminance: float
    contrast: float
    pixels: int  # rendered

    def __repr__(self) -> str:
        return short_repr(self, f"mean luminance {self.mean_luminance:.4f}", f"contrast {self.contrast:.4f}",
                          f"{self.pixels:,} pixels")

    def as_dict(self) -> dict:
        return {"mean_luminance": self.mean_luminance, "luminance_contrast": self.contrast, "pixels": self.pixels,
                "definition": f"{RENDERING}; luminance 0..1 (albedo 1: a flat surface gives the sine of the "
                              "elevation, 0.7071); contrast = std / mean of the luminance; rendered, so exact for these heights (no uncertainty of its "
                              "own). Two looks compare by the Weber contrast of their mean luminance, visible from "
                              f"about {THRESHOLD:g} (an assumed threshold: roughness.design.look)"}


def texture_look(heightmap: Heightmap, luminance: np.ndarray | None = None) -> TextureLook:
    """The mean luminance and contrast of ``heightmap`` (mm) rendered whole (``luminance``: its ``render``, if
    already made)."""
    luminance = render(heightmap) if luminance is None else luminance
    mean = float(luminance.mean())  # > 0: the highest pixel faces at least half the lights, unshadowed
    return TextureLook(mean, float(luminance.std()) / mean, int(luminance.size))


def region_interiors(labels: np.ndarray, pixel_mm: float, regions: int, band_mm: float = BAND_MM) -> list[np.ndarray]:
    """For each region 0..``regions``-1 of ``labels`` (an index per pixel; others, e.g. -1, belong to none): its
    pixels further than ``band_mm`` (mm) from every pixel not in it, where no other region's shadow or light falls."""
    from scipy import ndimage  # not at import: predict renders looks without it (0.3 s)

    band = band_mm / pixel_mm
    return [ndimage.distance_transform_edt(labels == k) > band for k in range(regions)]


@dataclass(frozen=True)
class RegionLooks:
    """How different each region of a plate looks beside each other one (``region_looks``)."""

    differences: tuple[tuple[LookDifference | None, ...], ...]  # [a][b]: region a beside region b; None: not measured
    unmeasured: tuple[str, ...] = ()  # why some pairs have no look difference

    def __repr__(self) -> str:
        d = self.matrix
        pairs = d[~np.eye(len(d), dtype=bool) & ~np.isnan(d)]
        return short_repr(self, f"{len(d)} regions", f"least {pairs.min():.2f} look JND" if pairs.size else "",
                          f"{len(self.unmeasured)} unmeasured" if self.unmeasured else "")

    @property
    def matrix(self) -> np.ndarray:
        """(K, K) look JND of region a beside region b: NaN where not measured, 0 on the diagonal."""
        d = np.array([[np.nan if x is None else x.difference for x in row] for row in self.differences], dtype=float)
        np.fill_diagonal(d, 0.0)
        return d


def region_looks(heightmap: Heightmap, labels: np.ndarray, names: Sequence[str], band_mm: float = BAND_MM
                 ) -> RegionLooks:
    """How each region 0..len(``names``)-1 of ``labels`` (an index per pixel of ``heightmap``, mm) looks beside each
    other one: the heightmap rendered whole, each region's pixels more than ``band_mm`` from its borders
    (``region_interiors``) compared (``compare``). A pair with a region too small for that, or black, is None and
    ``unmeasured`` says why, by the regions' ``names``."""
    luminance = render(heightmap)
    filtered = bands(luminance, heightmap.pixel_mm)
    interiors = region_interiors(labels, heightmap.pixel_mm, len(names), band_mm)
    looks, too_small = [], {}  # each region's look once (None: too small), and why not
    for k, (name, interior) in enumerate(zip(names, interiors, strict=True)):
        try:
            looks.append(region_look(luminance, interior, filtered, name))
        except InputError:
            looks.append(None)
            too_small[k] = (f"{name}: {np.count_nonzero(interior)} pixels lie more than {band_mm:g} mm inside its "
                            f"borders, fewer than the {MIN_REGION_PIXELS} needed to compare how it looks")
    rows, why = [], {}
    for a, look_a in enumerate(looks):
        row = []
        for b, look_b in enumerate(looks):
            if a == b or look_a is None or look_b is None:
                row.append(None)
                why.update(dict.fromkeys(too_small[k] for k in (a, b) if a != b and k in too_small))
                continue
            try:
                row.append(compare_looks(look_a, look_b))
            except InputError as err:  # region b black under every light
                row.append(None)
                why[f"{names[a]} beside {names[b]}: {err}"] = None
        rows.append(tuple(row))
    return RegionLooks(tuple(rows), tuple(why))
