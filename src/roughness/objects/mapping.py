"""How a texture lies on a surface, without UVs: the texture's height at points of the base surface.

Every mapping answers one question, used both to displace the mesh (``texturing``) and to read back the
texture under a footprint (``feel``): the texture's height (mm, along the outward normal, as the flat
texture would print: bumps up) at points of the untextured base surface with their unit normals.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from roughness.core.checks import in_range, length
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap


class TextureMapping(Protocol):
    """A texture laid on a surface."""

    @property
    def pixel_mm(self) -> float:
        """The texture's pixel on the surface (mm): the resolution the mesh is refined to."""
        ...

    def heights(self, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """Heights (mm, >= 0, along the outward normal) at ``points`` (n, 3; mm) of the base surface with unit
        ``normals`` (n, 3); returns shape (n,)."""
        ...


# --- the mappings -------------------------------------------------------------------------------------------------
# Each looks the texture up as one periodic tile (bilinear, wrapped: ``Heightmap.sample(periodic=True)``), its
# heights shifted so that the lowest is 0 (bumps stand on the base surface). Where two projections meet (the
# triplanar axes, a cylinder's side and caps, a sphere's band and polar caps) the heights are blended over a stated
# angular width of the normal, so the displaced surface has no step there.

DEFAULT_BLEND_DEG = 20.0
"""Full angular width (degrees of the normal's direction) over which two projections are blended."""

CHUNK_POINTS = 1_000_000
"""Points looked up at once (a few arrays of this many floats: tens of MB)."""

BLEND_RANGE_DEG = (0.0, 60.0)


def tile_of(texture: Heightmap, stretch: float = 1.0) -> _Tile:
    """The texture as a periodic tile with its lowest point at 0, laterally scaled by ``stretch``."""
    return _Tile(texture, float(texture.heights.min()), stretch)


@dataclass(frozen=True)
class _Tile:
    texture: Heightmap
    floor_mm: float
    stretch: float

    @property
    def pixel_mm(self) -> float:
        return self.texture.pixel_mm * self.stretch

    @property
    def period_mm(self) -> tuple[float, float]:
        """(along u, along v) of one tile on the surface (mm)."""
        width, height = self.texture.size_mm
        return width * self.stretch, height * self.stretch

    def at(self, u_mm: np.ndarray, v_mm: np.ndarray) -> np.ndarray:
        """Heights (mm, >= 0) at surface coordinates (mm)."""
        return self.texture.sample(u_mm / self.stretch, v_mm / self.stretch, periodic=True) - self.floor_mm


def blend_weights(dominance: np.ndarray, blend_deg: float) -> np.ndarray:
    """Weight (0..1) of a projection whose dominance is ``dominance`` = |n_k| - max other |n_l|: 1 where it leads
    by more than the blend's half-width, 0 where it trails by more, linear in between (the two projections meeting
    at 45 degrees each get 1/2)."""
    half = math.sqrt(2.0) * math.sin(math.radians(blend_deg) / 2)
    if half == 0:
        return (dominance >= 0).astype(float)
    return np.clip((dominance + half) / (2 * half), 0.0, 1.0)


def _chunked(points: np.ndarray, normals: np.ndarray, one) -> np.ndarray:
    points, normals = _checked(points, normals)
    out = np.empty(len(points))
    for start in range(0, len(points), CHUNK_POINTS):
        stop = start + CHUNK_POINTS
        out[start:stop] = one(points[start:stop], normals[start:stop])
    return out


def _checked(points: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    points = np.asarray(points, dtype=float)
    normals = np.asarray(normals, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3 or normals.shape != points.shape:
        raise InputError(f"points and normals must both have shape (n, 3), got {points.shape} and {normals.shape}")
    return points, normals


def _blend_deg(blend_deg: float) -> float:
    return in_range("blend_deg", blend_deg, *BLEND_RANGE_DEG)


@dataclass(frozen=True)
class Triplanar:
    """The texture projected along x, y and z (for any shape); each point takes the projection along the axis its
    normal points most along, blended over ``blend_deg`` (full width, degrees) where two axes tie.

    Projection along x reads the tile at (y, z), along y at (x, z), along z at (x, y) (mm, the mesh's coordinates).
    """

    texture: Heightmap
    blend_deg: float = DEFAULT_BLEND_DEG

    def __post_init__(self) -> None:
        _blend_deg(self.blend_deg)

    @property
    def pixel_mm(self) -> float:
        return self.texture.pixel_mm

    def heights(self, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        tile = tile_of(self.texture)

        def one(p: np.ndarray, n: np.ndarray) -> np.ndarray:
            a = np.abs(n)
            total = np.zeros(len(p))
            weight = np.zeros(len(p))
            for k, (i, j) in enumerate(((1, 2), (0, 2), (0, 1))):
                w = blend_weights(a[:, k] - np.maximum(a[:, i], a[:, j]), self.blend_deg)
                lead = w > 0
                total[lead] += w[lead] * tile.at(p[lead, i], p[lead, j])
                weight += w
            return total / weight
        return _chunked(points, normals, one)

    def notes(self) -> list[str]:
        return [f"triplanar projection along x, y, z of the texture at its own size; seams blended over "
                f"{self.blend_deg:g} degrees of the normal's direction"]


@dataclass(frozen=True)
class Axis:
    """A line: a point on it (mm) and a unit direction."""

    point: tuple[float, float, float]
    direction: tuple[float, float, float]

    def frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(origin, e1, e2, axis): an orthonormal frame with the axis as third vector."""
        a = np.asarray(self.direction, dtype=float)
        helper = np.eye(3)[int(np.argmin(np.abs(a)))]
        e1 = np.cross(a, helper)
        e1 /= np.linalg.norm(e1)
        return np.asarray(self.point, dtype=float), e1, np.cross(a, e1), a


def axis_of(point: object, direction: object) -> Axis:
    """An Axis from a point and a direction (any length but zero), checked."""
    p = np.asarray(point, dtype=float).reshape(-1)
    d = np.asarray(direction, dtype=float).reshape(-1)
    if p.shape != (3,) or d.shape != (3,) or not (np.all(np.isfinite(p)) and np.all(np.isfinite(d))):
        raise InputError(f"an axis needs a finite point and direction of 3 numbers each, got {point!r}, {direction!r}",
                         parameter="axis")
    length = float(np.linalg.norm(d))
    if length == 0:
        raise InputError("the axis direction must not be zero", parameter="axis")
    return Axis(tuple(p), tuple(d / length))


def whole_tiles(circumference_mm: float, tile_mm: float) -> tuple[int, float]:
    """(tiles, stretch): the whole number of tiles around ``circumference_mm`` that needs the smallest lateral
    stretch of the tile (as a factor, its log closest to 0), and that stretch (circumference / (tiles * tile))."""
    ratio = circumference_mm / tile_mm
    candidates = [max(1, math.floor(ratio)), max(1, math.ceil(ratio))]
    tiles = min(candidates, key=lambda n: abs(math.log(ratio / n)))
    return tiles, ratio / tiles


@dataclass(frozen=True)
class Wrap:
    """The texture wrapped around an axis: a cylinder (``kind="cylinder"``: u = angle * radius, v = position along
    the axis) or a sphere (``"sphere"``: u = longitude * radius, v = latitude * radius, ``axis.point`` its centre).
    The tile is scaled laterally (both directions alike, so bumps keep their shape) by ``stretch`` so that exactly
    ``tiles`` tiles go around the circumference 2 pi ``radius_mm``: no seam where the wrap closes. Where the normal
    turns towards the axis (a knob's top, a sphere's poles) the texture is projected along the axis instead (the
    caps), blended over ``blend_deg`` as in Triplanar.
    """

    texture: Heightmap
    kind: str
    axis: Axis
    radius_mm: float
    tiles: int
    stretch: float
    blend_deg: float = DEFAULT_BLEND_DEG

    def __post_init__(self) -> None:
        _blend_deg(self.blend_deg)
        if self.kind not in ("cylinder", "sphere"):
            raise InputError(f"unknown wrap {self.kind!r}; valid: cylinder, sphere", parameter="mapping")

    @property
    def pixel_mm(self) -> float:
        return self.texture.pixel_mm * self.stretch

    def heights(self, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        tile = tile_of(self.texture, self.stretch)
        origin, e1, e2, a = self.axis.frame()

        def one(p: np.ndarray, n: np.ndarray) -> np.ndarray:
            r = p - origin
            x, y, z = r @ e1, r @ e2, r @ a
            along = np.abs(n @ a)
            across = np.sqrt(np.maximum(0.0, 1.0 - along**2))
            w_cap = blend_weights(along - across, self.blend_deg)
            u = np.arctan2(y, x) * self.radius_mm
            if self.kind == "cylinder":
                v = z
            else:
                v = np.arcsin(np.clip(z / np.maximum(np.sqrt(x * x + y * y + z * z), 1e-300), -1, 1)) * self.radius_mm
            out = np.zeros(len(p))
            side = w_cap < 1
            out[side] = (1 - w_cap[side]) * tile.at(u[side], v[side])
            cap = w_cap > 0
            out[cap] += w_cap[cap] * tile.at(x[cap], y[cap])
            return out
        return _chunked(points, normals, one)

    def notes(self) -> list[str]:
        point = ", ".join(f"{c + 0.0:.3f}" for c in self.axis.point)
        direction = ", ".join(f"{c:.3f}" for c in self.axis.direction)
        what = "axis" if self.kind == "cylinder" else "centre"
        width, _ = self.texture.size_mm
        return [f"{self.kind} wrap: {what} through ({point}) mm, direction ({direction}), radius {self.radius_mm:.3f} mm; "
                f"{self.tiles} whole tile(s) of {width:.3f} mm around the {2 * math.pi * self.radius_mm:.3f} mm "
                f"circumference: the texture is scaled laterally by {self.stretch:.4f} (pixel {self.pixel_mm:.4g} mm)",
                f"where the normal turns towards the axis the texture is projected along it (caps), blended over "
                f"{self.blend_deg:g} degrees"]


def wrap(texture: Heightmap, kind: str, axis: Axis, radius_mm: float, blend_deg: float = DEFAULT_BLEND_DEG) -> Wrap:
    """A Wrap of ``kind`` around ``axis`` with the whole number of tiles around 2 pi ``radius_mm`` that stretches
    the texture least."""
    radius = length("radius_mm", radius_mm)
    tiles, stretch = whole_tiles(2 * math.pi * radius, texture.size_mm[0])
    return Wrap(texture, kind, axis, radius, tiles, stretch, blend_deg)


@dataclass(frozen=True)
class UVMapping:
    """The texture laid by the mesh's own texture coordinates: a point takes the UV of the nearest point of the base
    mesh (``base``, a trimesh with per-vertex UVs), the tile is read at UV * ``uv_mm`` (mm per UV unit, periodic)."""

    texture: Heightmap
    base: Any  # trimesh.Trimesh with visual.uv
    uv_mm: float

    @property
    def pixel_mm(self) -> float:
        return self.texture.pixel_mm

    def heights(self, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        from trimesh.proximity import closest_point
        from trimesh.triangles import points_to_barycentric

        tile = tile_of(self.texture)
        uv = np.asarray(self.base.visual.uv, dtype=float)
        faces = np.asarray(self.base.faces)

        def one(p: np.ndarray, n: np.ndarray) -> np.ndarray:
            nearest, _, face = closest_point(self.base, p)
            bary = points_to_barycentric(self.base.triangles[face], nearest)
            at = np.einsum("ij,ijk->ik", bary, uv[faces[face]]) * self.uv_mm
            return tile.at(at[:, 0], at[:, 1])
        return _chunked(points, normals, one)

    def notes(self) -> list[str]:
        return [f"the mesh's UV coordinates, {self.uv_mm:.4g} mm per UV unit (the tile repeats every UV unit / "
                f"{self.texture.size_mm[0] / self.uv_mm:.4g}); UV seams show as seams in the texture"]
