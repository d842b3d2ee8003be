"""The texture under the skin's footprint on a curved surface, unrolled into a flat heightmap.

At a point of the base surface with principal curvatures k1, k2 along d1, d2 (``curvature``), the
footprint's square (side ``FOOTPRINT_MM``) is laid on the surface by arc length: the pixel (u, v) of the
heightmap (u along d1 = the map's x, v along d2 = y, from the centre) is the surface point reached by
walking u along d1 and v along d2. On a cylinder (k2 = 0) that walk is exact: a plane section along d1, a
straight line along d2; on a sphere (k1 = k2) the walk from the centre along the great circle towards
(u, v) is used, exact too. Elsewhere the separable walk is the second-order approximation. The mapping's
heights at those points (with their normals) are the unrolled texture.

``on_surface`` says how much of the footprint actually lies on the mesh (and on the textured region).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughness.curvature_correction import FOOTPRINT_MM
from roughness.surface.heightmap import Heightmap

CHECK_POINTS = 11  # per side: the footprint points checked against the mesh
OFF_SURFACE_MM = 0.3  # a footprint point this far from every surface sample is off the surface
MAX_OFF_FRACTION = 0.05  # footprints with more of their points off the surface (or region) are refused
SPHERICAL = 1e-3  # |k1 - k2| (1/mm) below which the sphere's walk is used


@dataclass(frozen=True)
class Placement:
    """Where a footprint lies: its centre, outward normal, principal curvatures (1/mm) and directions."""

    centre: np.ndarray
    normal: np.ndarray
    k1: float
    k2: float
    d1: np.ndarray
    d2: np.ndarray


def _arc(k: float, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Along a circle of curvature k (1/mm): tangent offset sin(ks)/k, drop (1 - cos ks)/k, cos ks, sin ks."""
    return s * np.sinc(k * s / np.pi), k * s**2 / 2 * np.sinc(k * s / (2 * np.pi)) ** 2, np.cos(k * s), np.sin(k * s)


def surface_grid(place: Placement, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Surface points and unit normals (..., 3) at arc-length offsets ``u`` (along d1), ``v`` (along d2) in mm."""
    n0, d1, d2 = place.normal, place.d1, place.d2
    if abs(place.k1 - place.k2) < SPHERICAL:  # a sphere: the great circle towards (u, v)
        k, s = (place.k1 + place.k2) / 2, np.hypot(u, v)
        safe = np.where(s > 0, s, 1.0)
        direction = (u / safe)[..., None] * d1 + (v / safe)[..., None] * d2
        along, drop, c, sn = _arc(k, s)
        points = place.centre + along[..., None] * direction - drop[..., None] * n0
        normals = c[..., None] * n0 + sn[..., None] * direction
        return points, normals
    a1, drop1, c1, s1 = _arc(place.k1, u)
    a2, drop2, c2, s2 = _arc(place.k2, v)
    points = place.centre + a1[..., None] * d1 + a2[..., None] * d2 - (drop1 + drop2)[..., None] * n0
    normals = (c1 * c2)[..., None] * n0 + (s1 * c2)[..., None] * d1 + (s2 * c1)[..., None] * d2
    return points, normals / np.linalg.norm(normals, axis=-1, keepdims=True)


def footprint_axis(pixel_mm: float, side_mm: float = FOOTPRINT_MM) -> np.ndarray:
    """Pixel centres (mm, from the footprint's centre) across at least ``side_mm``: the engines' round(side / pixel)
    pixels, two more at a time until they cover the side (the engines' footprint then stays on the pixel grid)."""
    n = max(int(round(side_mm / pixel_mm)), 1)
    while n * pixel_mm < side_mm:
        n += 2
    return (np.arange(n) - (n - 1) / 2) * pixel_mm


def unrolled(mapping, place: Placement, side_mm: float = FOOTPRINT_MM) -> Heightmap:
    """The texture under the footprint at ``place`` as a flat heightmap (x along d1, y along d2; mm)."""
    axis = footprint_axis(mapping.pixel_mm, side_mm)
    u, v = np.meshgrid(axis, axis)
    points, normals = surface_grid(place, u, v)
    heights = np.asarray(mapping.heights(points.reshape(-1, 3), normals.reshape(-1, 3)), float)
    return Heightmap(heights.reshape(u.shape), mapping.pixel_mm)


def on_surface(samples, place: Placement, in_region: np.ndarray | None = None,
               side_mm: float = FOOTPRINT_MM) -> tuple[float, float]:
    """Fractions of the footprint's check points (a ``CHECK_POINTS`` square grid) that lie off the mesh's
    surface (farther than ``OFF_SURFACE_MM`` from every sample, or facing away) and, of those on it, outside
    the region (``in_region``: a bool per mesh face)."""
    axis = np.linspace(-side_mm / 2, side_mm / 2, CHECK_POINTS)
    u, v = np.meshgrid(axis, axis)
    points, normals = surface_grid(place, u.ravel(), v.ravel())
    distance, nearest = samples.tree.query(points)
    facing = np.einsum("ij,ij->i", samples.normals[nearest], normals) > 0.5
    on = (distance <= max(OFF_SURFACE_MM, 1.5 * samples.spacing_mm)) & facing
    off_fraction = 1 - on.mean()
    if in_region is None or not on.any():
        return float(off_fraction), 0.0
    outside = ~in_region[samples.faces[nearest[on]]]
    return float(off_fraction), float(outside.mean())
