"""Curved bases: a cylinder or sphere of signed radius R (mm) under the texture.

R > 0 is convex toward the finger (crest at the block centre), R < 0 concave (trough at
the centre). Block coordinates (mm): x, y from the footprint centre, z up; the base height
is 0 at the centre. A cylinder's ``axis`` is the direction it is straight along (``x``: it
curves in y). Beyond a convex base's silhouette (|distance| >= R) the base falls away as a
steep wall (``WALL_SLOPE``), untextured.

The texture rides on the base in one of two ways (``texture_along``):

- ``normal``: the texture is wrapped onto the base without stretching along its arc (a
  cylinder unrolls; a sphere uses the azimuthal equidistant map) and each height is laid
  off along the base normal, as a print or mould of a textured object has it. The skin
  presses along z, so the surface it meets is the upper envelope of that offset surface
  (``normal_relief``); valleys (the texture's lowest point in the footprint) lie on the base.
- ``z``: heights are added to the base along z at the same (x, y) (a height map draped
  vertically; what a scan of a curved object records).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

SHAPES = ("flat", "cylinder", "sphere")
AXES = ("x", "y")
TEXTURE_ALONG = ("normal", "z")
FAR_BELOW_MM = 1.0e3  # height (mm, below the crest) standing for "no surface here"
WALL_SLOPE = 10.0  # slope of the wall standing for a base's side beyond its silhouette (84 degrees)
SAMPLES_PER_PIXEL = 4  # arc-length samples per texture pixel when tracing the normal-offset surface
SLIDE_MARGIN_MM = 1.0  # the relief is tabulated this far beyond the footprint (for sliding contact nodes)
QUERY_CHUNK = 4096  # relief points traced at once (bounds memory)


@dataclass(frozen=True)
class BaseShape:
    """The untextured base under the skin: ``kind`` (flat, cylinder, sphere), signed ``radius_mm``, cylinder ``axis``."""

    kind: str = "flat"
    radius_mm: float = math.inf
    axis: str = "x"

    @property
    def flat(self) -> bool:
        return self.kind == "flat"

    @property
    def convex(self) -> bool:
        return self.radius_mm > 0

    def describe(self) -> str:
        if self.flat:
            return "flat base"
        side = "convex" if self.convex else "concave"
        along = f" along {self.axis}" if self.kind == "cylinder" else ""
        return f"{side} {self.kind}{along} of radius {abs(self.radius_mm):g} mm"

    def distance(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Signed distance (mm) from the crest across the curvature, and its unit direction (ex, ey) in xy."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        if self.kind == "sphere":
            rho = np.hypot(x, y)
            safe = np.where(rho > 0, rho, 1.0)
            return rho, np.where(rho > 0, x / safe, 1.0), np.where(rho > 0, y / safe, 0.0)
        if self.axis == "x":
            return y, np.zeros_like(y), np.ones_like(y)
        return x, np.ones_like(x), np.zeros_like(x)

    def height(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Base height (mm) at block (x, y), 0 at the centre; a steep wall beyond the silhouette (``profile``)."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        if self.flat:
            return np.zeros_like(x)
        rho, _, _ = self.distance(x, y)
        return profile(self.radius_mm, rho)

    def half_span_mm(self, width_mm: float) -> float:
        """Largest distance from the crest (mm) inside a square footprint of side ``width_mm``."""
        return width_mm / 2 * (math.sqrt(2) if self.kind == "sphere" else 1.0)

    def top_mm(self, width_mm: float) -> float:
        """Highest base point (mm) over the footprint: the crest (0) or a concave base's rim."""
        if self.flat or self.convex:
            return 0.0
        return float(profile(self.radius_mm, np.array(self.half_span_mm(width_mm))))

    def unrolled_half_mm(self, width_mm: float) -> float:
        """Half-side (mm) of the texture square a footprint of side ``width_mm`` reads when wrapped on the base."""
        if self.flat:
            return width_mm / 2
        r = abs(self.radius_mm)
        span = self.half_span_mm(width_mm)
        arc = r * math.asin(min(1.0, span / r))
        return max(width_mm / 2, arc / math.sqrt(2) if self.kind == "sphere" else arc)


FLAT = BaseShape()


def profile(radius_mm: float, rho: np.ndarray) -> np.ndarray:
    """Height (mm) of a circle of signed radius through 0 at distance ``rho``; beyond it a wall of ``WALL_SLOPE``.

    The wall stands for the circle's vertical side (down on a convex base, up on a concave one):
    steep enough that the skin does not reach down it, and finite, so that a contact node taken
    in at its deformed position is never held at a height it could not reach.
    """
    r = abs(radius_mm)
    beyond = np.maximum(np.abs(rho) - r, 0.0)
    sag = r - np.sqrt(np.maximum(r * r - rho * rho, 0.0)) + WALL_SLOPE * beyond
    return np.maximum(-sag if radius_mm > 0 else sag, -FAR_BELOW_MM)


def require_restable(shape: BaseShape, width_mm: float) -> None:
    """InputError if the skin footprint cannot rest on the base (a concave base narrower than the footprint)."""
    if shape.flat or shape.convex:
        return
    span = shape.half_span_mm(width_mm)
    if abs(shape.radius_mm) <= span:
        where = "corner" if shape.kind == "sphere" else "edge"
        raise InputError(
            f"a concave {shape.kind} of radius {abs(shape.radius_mm):g} mm is narrower than the {width_mm:g} mm skin "
            f"footprint (its {where} lies {span:.3g} mm from the centre): the skin cannot rest in it; the concave "
            f"radius must exceed {span:.3g} mm", parameter="curvature_mm")


def base_surface(shape: BaseShape, width_mm: float):
    """The untextured base's height (mm) relative to the undeformed skin face (its top over the footprint)."""
    z0 = shape.top_mm(width_mm)

    def surface(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return shape.height(x, y) - z0

    return surface


def textured_surface(heightmap: Heightmap, centre_mm: tuple[float, float], shape: BaseShape, along: str,
                     width_mm: float, periodic: bool):
    """(surface, z0): the textured base's height (mm) relative to the undeformed skin face, and that face's height.

    ``surface(x, y)`` takes block coordinates (mm); z0 is the highest tabulated point over the footprint.
    """
    cx, cy = centre_mm
    if along == "normal" and not periodic and not heightmap.covers(2 * shape.unrolled_half_mm(width_mm), centre_mm):
        side = 2 * shape.unrolled_half_mm(width_mm)
        raise InputError(f"wrapped on the {shape.describe()}, the {width_mm:g} mm skin footprint reads a {side:.3g} mm "
                         f"square of texture around ({cx:.2f}, {cy:.2f}) mm, beyond the heightmap's "
                         f"{heightmap.size_mm[0]:.2f} mm x {heightmap.size_mm[1]:.2f} mm; pass tile=True for a "
                         "periodic texture, or lay heights along z (texture_along=\"z\")", parameter="curvature_mm")
    p = heightmap.pixel_mm
    # Tabulation grid: the heightmap's own pixel centres, in block coordinates, over the footprint and a margin.
    half = width_mm / 2 + SLIDE_MARGIN_MM
    cols = np.arange(math.floor((cx - half) / p - 0.5), math.ceil((cx + half) / p - 0.5) + 1)
    rows = np.arange(math.floor((cy - half) / p - 0.5), math.ceil((cy + half) / p - 0.5) + 1)
    gx = (cols + 0.5) * p - cx
    gy = (rows + 0.5) * p - cy
    x, y = np.meshgrid(gx, gy)
    base = shape.height(x, y)
    if along == "normal":
        relief = normal_relief(heightmap, centre_mm, shape, x, y, periodic) - base
    else:
        relief = heightmap.sample(cx + x, cy + y, periodic=periodic)
        relief = relief - relief.min()
    relief = np.where(np.abs(shape.distance(x, y)[0]) < abs(shape.radius_mm), relief, 0.0)  # none on the wall
    inside = (np.abs(x) <= width_mm / 2 + 1e-9) & (np.abs(y) <= width_mm / 2 + 1e-9)
    z0 = float((base + relief)[inside].max())
    table = Heightmap(relief, p)
    x_first, y_first = gx[0] - p / 2, gy[0] - p / 2

    def surface(qx: np.ndarray, qy: np.ndarray) -> np.ndarray:
        height = np.maximum(shape.height(qx, qy) + table.sample(qx - x_first, qy - y_first), -FAR_BELOW_MM)
        return height - z0

    return surface, z0


def normal_relief(heightmap: Heightmap, centre_mm: tuple[float, float], shape: BaseShape, x: np.ndarray,
                  y: np.ndarray, periodic: bool) -> np.ndarray:
    """Height (mm) at block (x, y) of the upper envelope of the texture laid off along the base normal.

    Each point's section through the base's axis (cylinder) or centre (sphere) holds every
    texture point that can land on it, so the envelope is traced per point along that section:
    texture samples at arc lengths around the point's own, offset radially, and the highest
    crossing of the traced curve with the point's distance from the crest.
    """
    cx, cy = centre_mm
    r = shape.radius_mm
    rho, ex, ey = (a.ravel() for a in shape.distance(x, y))
    ox, oy = (np.zeros_like(rho), np.zeros_like(rho)) if shape.kind == "sphere" else (
        (x.ravel(), np.zeros_like(rho)) if shape.axis == "x" else (np.zeros_like(rho), y.ravel()))
    step = heightmap.pixel_mm / SAMPLES_PER_PIXEL
    t_max = abs(r) * math.pi / 2
    t0 = r * np.arcsin(np.clip(rho / r, -1.0, 1.0))  # arc length of the base point below (x, y)
    # The texture's lowest point under the footprint lies on the base.
    below = heightmap.sample(cx + ox + t0 * ex, cy + oy + t0 * ey, periodic)
    floor = float(below.min())
    # Where the traced section has no crossing (a convex base's silhouette), the height along z.
    fallback = profile(r, rho) + below - floor
    # Arc lengths whose texture can land on each point: a height h lands at (r + h) sin(t / r) = rho.
    lands = [r * np.arcsin(np.clip(rho / (r + h), -1.0, 1.0))
             for h in (float(heightmap.heights.min()) - floor, float(heightmap.heights.max()) - floor)]
    first = np.floor((np.minimum.reduce([t0, *lands]) - t0) / step).astype(int) - 2
    count = np.ceil((np.maximum.reduce([t0, *lands]) - t0) / step).astype(int) + 3 - first
    order = np.argsort(count, kind="stable")
    out = np.empty(rho.shape)
    for lo in range(0, len(rho), QUERY_CHUNK):
        sl = order[lo:lo + QUERY_CHUNK]
        k = first[sl, None] + np.arange(count[sl].max())[None, :]
        t = np.clip(t0[sl, None] + step * k, -t_max, t_max)
        h = heightmap.sample(cx + ox[sl, None] + t * ex[sl, None], cy + oy[sl, None] + t * ey[sl, None], periodic)
        radial = r + (h - floor)
        pr = radial * np.sin(t / r)
        pz = radial * np.cos(t / r) - r
        q = rho[sl, None]
        a, b = pr[:, :-1] - q, pr[:, 1:] - q
        cross = (a * b <= 0) & (a != b)
        w = np.where(cross, a / np.where(a != b, a - b, 1.0), 0.0)
        z = np.where(cross, pz[:, :-1] + w * (pz[:, 1:] - pz[:, :-1]), -np.inf)
        best = z.max(axis=1)
        out[sl] = np.where(np.isfinite(best), best, fallback[sl])
    return out.reshape(x.shape)
