"""The relief of a mesh as it is (textured elsewhere: Blender, a texturing tool, a slicer's bake) against its own base.

Base surface: the mesh smoothed by a Gaussian of width ``BASE_SIGMA_MM`` (1 mm; at least twice the points'
spacing). The mesh's faces are gathered into cubes of the spacing (0.4 mm; ``surface_cells``: exact sums of area and
area-weighted normal per cube, no random samples), and over the cubes within three widths, area-weighted, in two
passes: the normals are averaged (pass 1), then the positions and normals of the cubes whose pass-1 normals face the
same side (not the far side of a thin wall; pass 2). A relief of wavelength lambda keeps exp(-2 pi^2 sigma^2 /
lambda^2) of its amplitude in the base: under 1% for lambda <= 2 mm (the standard textures' bumps span 0.625-2.5 mm),
so the base's normals and curvature are the shape's; the base lies at the relief's mean height (a constant offset,
which no engine feels). The base's curvature at the footprint's scale is then fitted by ``curvature`` as on any mesh.

Heightfield: at a footprint placed on the base (``footprint.Placement``), every vertex of the mesh near it is
expressed in the footprint's coordinates: (u, v), the arc lengths of its foot point on the base surface that
``footprint.surface_grid`` walks, and h, its offset from that foot point along the base's normal; the mesh's faces are
then rasterised in (u, v) at ``ENGINE_PIXEL_MM`` (the engines' 0.05 mm pixel), keeping the highest surface over each
pixel (what a fingertip meets), within ``REACH_MM`` of the base.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.limits import MAX_MESH_TRIANGLES, check_size
from roughness.curvature_correction import FOOTPRINT_MM

from .curvature import SAMPLE_SPACING_MM, SurfaceSamples
from .footprint import MAX_OFF_FRACTION, Placement, footprint_axis, surface_grid
from .sampling import highest_surface

BASE_SIGMA_MM = 1.0
"""Width of the Gaussian that smooths the mesh into its base (mm; module docstring)."""
ENGINE_PIXEL_MM = 0.05
"""The heightfield's pixel: the engines' (``dataset.grid.PIXEL_MM``)."""
REACH_MM = 3.0
"""Surfaces farther than this from the base (mm, either side) are not the relief under the footprint (e.g. the far
wall of a thin part)."""
FOOT_ITERATIONS = 3
"""Newton steps finding a vertex's foot point on the base (each shrinks the error by about |h k|, under 0.2)."""
MAX_SLOPE = math.tan(math.radians(0.5))
"""A relief whose least-squares plane slopes more than this from the base is measured again on that plane."""


def base_sigma(spacing_mm: float) -> float:
    """The base's Gaussian width (mm) for cubes of side ``spacing_mm`` (``surface_cells``): BASE_SIGMA_MM, or twice
    the side if larger (at least about 50 cubes of a surface within it)."""
    return max(BASE_SIGMA_MM, 2 * spacing_mm)


def base_samples(mesh, spacing_mm: float = SAMPLE_SPACING_MM, sigma_mm: float | None = None,
                 chunk: int = 20_000) -> SurfaceSamples:
    """Points on the base surface of ``mesh`` (a trimesh, mm), about ``spacing_mm`` apart (``surface_cells``), with
    the base's normals: positions and normals smoothed by a Gaussian of ``sigma_mm`` (default ``base_sigma``) in two
    passes (module docstring), area-weighted. ``faces``: the mesh's face holding most of each point's cell, so
    regions select points as they select faces."""
    from scipy.sparse import csr_matrix
    from scipy.spatial import cKDTree

    cells = surface_cells(mesh, spacing_mm)
    sigma = sigma_mm if sigma_mm is not None else base_sigma(spacing_mm)
    tree = cKDTree(cells.points)
    rows, cols = [], []
    for begin in range(0, len(cells.points), chunk):
        near = tree.query_ball_point(cells.points[begin:begin + chunk], 3 * sigma)
        rows.append(np.repeat(np.arange(begin, begin + len(near)), [len(n) for n in near]))
        cols.append(np.concatenate([np.asarray(n, dtype=np.int64) for n in near]))
    i, j = np.concatenate(rows), np.concatenate(cols)
    weight = np.exp(-np.sum((cells.points[i] - cells.points[j]) ** 2, axis=1) / (2 * sigma**2))
    n = len(cells.points)
    first = _unit(csr_matrix((weight, (i, j)), shape=(n, n)) @ cells.normal_sums)
    same = np.einsum("ij,ij->i", first[i], first[j]) > 0
    smooth = csr_matrix((weight[same], (i[same], j[same])), shape=(n, n))
    points = (smooth @ (cells.areas[:, None] * cells.points)) / (smooth @ cells.areas)[:, None]
    return SurfaceSamples(points, _unit(smooth @ cells.normal_sums), cells.faces, cKDTree(points), spacing_mm)


@dataclass(frozen=True)
class SurfaceCells:
    """A mesh's surface gathered into cubes of a side (mm): per cube holding surface, its area (mm^2), the
    area-weighted centroid of its faces (mm), the area-weighted sum of their unit normals (mm^2) and the mesh's face
    holding most of it."""

    points: np.ndarray
    areas: np.ndarray
    normal_sums: np.ndarray
    faces: np.ndarray


def surface_cells(mesh, side_mm: float) -> SurfaceCells:
    """``mesh`` (a trimesh, mm) gathered into cubes of ``side_mm``: its faces, those with an edge longer than the side
    split first (a CAD export's faces span the part), each counted in the cube of its centroid. Sums over the faces:
    exact areas and normals, not random samples."""
    import trimesh

    triangles = np.asarray(mesh.triangles)
    longest = np.linalg.norm(triangles - np.roll(triangles, 1, axis=1), axis=2).max(axis=1)
    rounds = np.ceil(np.log2(np.maximum(longest / side_mm, 1.0)))  # each splits a face in 4
    check_size(f"faces of the mesh split to {side_mm:g} mm edges", float((4.0**rounds).sum()), MAX_MESH_TRIANGLES,
               "mesh")
    vertices, faces, index = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, side_mm,
                                                              max_iter=int(rounds.max()) + 2, return_index=True)
    corners = vertices[faces]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    areas = np.linalg.norm(cross, axis=1) / 2
    centres = corners.mean(axis=1)
    keys, cell = np.unique(np.floor(centres / side_mm).astype(np.int64), axis=0, return_inverse=True)
    cell = cell.ravel()
    count = len(keys)
    area = np.bincount(cell, areas, count)
    keep = area > 0
    points = np.stack([np.bincount(cell, areas * centres[:, k], count) for k in range(3)], axis=1)
    normal_sums = np.stack([np.bincount(cell, cross[:, k] / 2, count) for k in range(3)], axis=1)
    order = np.lexsort((areas, cell))  # per cell, its largest face last
    last = np.r_[cell[order][1:] != cell[order][:-1], True]
    largest = np.empty(count, dtype=np.int64)
    largest[cell[order][last]] = index[order][last]
    return SurfaceCells((points[keep] / area[keep, None]), area[keep], normal_sums[keep], largest[keep])


@dataclass(frozen=True)
class BaseFaces:
    """A mesh's faces with its base's normals (``face_normals``: the nearest base sample's, per face), for selecting
    faces by the direction they face (``regions.Region``: a cone) on a textured mesh, whose own face normals follow
    the relief."""

    faces: np.ndarray
    face_normals: np.ndarray
    triangles_center: np.ndarray

    @classmethod
    def of(cls, mesh, samples: SurfaceSamples | None = None) -> BaseFaces:
        """``mesh``'s faces with the normals of its base (``samples``: default ``base_samples(mesh)``)."""
        samples = samples or base_samples(mesh)
        centres = np.asarray(mesh.triangles_center)
        return cls(np.asarray(mesh.faces), samples.normals[samples.tree.query(centres)[1]], centres)


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.maximum(np.linalg.norm(vectors, axis=1, keepdims=True), 1e-300)


@dataclass(frozen=True)
class MeshRelief:
    """The relief of ``mesh`` (a trimesh, mm) over its base: ``unrolled`` gives it under a footprint (module
    docstring). ``centres``: a KD-tree of the mesh's face centroids; ``reach_mm``: each face's farthest corner
    from its centroid (a CAD export's faces can span the whole part)."""

    mesh: object
    centres: object
    reach_mm: np.ndarray
    pixel_mm: float = ENGINE_PIXEL_MM

    @classmethod
    def of(cls, mesh, pixel_mm: float = ENGINE_PIXEL_MM) -> MeshRelief:
        from scipy.spatial import cKDTree

        centres = np.asarray(mesh.triangles_center)
        reach = np.linalg.norm(np.asarray(mesh.triangles) - centres[:, None, :], axis=2).max(axis=1)
        return cls(mesh, cKDTree(centres), reach, pixel_mm)

    def faces_near(self, point: np.ndarray, radius_mm: float) -> np.ndarray:
        """Indices of the faces with a point within about ``radius_mm`` of ``point`` (their bounding spheres)."""
        found = np.asarray(self.centres.query_ball_point(point, radius_mm + float(self.reach_mm.max())), dtype=int)
        distance = np.linalg.norm(self.centres.data[found] - point, axis=1)
        return found[distance <= radius_mm + self.reach_mm[found]]

    def unrolled(self, place: Placement, side_mm: float = FOOTPRINT_MM) -> Footprint:
        """The relief under the footprint at ``place`` (``Footprint``; x along d1, y along d2, as
        ``footprint.unrolled``). Where the relief's least-squares plane slopes by more than ``MAX_SLOPE`` from the
        base (the base's normal is an average of random samples: a few degrees off), the footprint is placed again
        on that plane, once, so that the offsets are measured along the normal of the surface the skin rests on."""
        axis = footprint_axis(self.pixel_mm, side_mm)
        heights, missing = self._heights(place, axis)
        if missing < 1:
            slope = quadric_fit(heights, axis)[1:3]
            if math.hypot(*slope) > MAX_SLOPE:
                place = levelled(place, *slope)
                heights, missing = self._heights(place, axis)
        if missing == 1:
            return Footprint(heights, self.pixel_mm, 1.0, place.k1, place.k2)
        relief, k1, k2 = without_quadric(heights, axis, place.k1, place.k2)
        return Footprint(relief, self.pixel_mm, missing, k1, k2)

    def _heights(self, place: Placement, axis: np.ndarray) -> tuple[np.ndarray, float]:
        """The mesh's highest surface over the footprint's pixels (``axis``: their centres along d1 and d2, mm),
        as offsets (mm) from the base walked at ``place``, and the fraction of pixels over no surface (filled with
        the lowest offset met; all zero if none is)."""
        n = len(axis)
        half = n * self.pixel_mm / 2
        faces = np.asarray(self.mesh.faces)[self.faces_near(place.centre, math.sqrt(2) * half + REACH_MM)]
        if len(faces) == 0:
            return np.zeros((n, n)), 1.0
        used, local = np.unique(faces, return_inverse=True)
        u, v, h = foot_points(place, np.asarray(self.mesh.vertices)[used])
        local = local.reshape(faces.shape)
        local = local[h[local].min(axis=1) >= -REACH_MM]
        heights = highest_surface(u, v, h, local, n, self.pixel_mm, REACH_MM)
        missing = ~np.isfinite(heights)
        if missing.all():
            return np.zeros((n, n)), 1.0
        heights[missing] = heights[~missing].min()
        return heights, float(missing.mean())


def levelled(place: Placement, slope_x: float, slope_y: float) -> Placement:
    """``place`` turned onto the plane h = slope_x x + slope_y y over it (x along d1, y along d2): the same centre
    and curvatures, the plane's normal, d1 along the plane's x."""
    normal = place.normal - slope_x * place.d1 - slope_y * place.d2
    normal /= np.linalg.norm(normal)
    d1 = place.d1 + slope_x * place.normal  # normal to the plane's normal
    d1 /= np.linalg.norm(d1)
    return Placement(place.centre, normal, place.k1, place.k2, d1, np.cross(normal, d1))


@dataclass(frozen=True)
class Footprint:
    """The relief under one footprint: ``heights`` (mm, over the base's quadric), the fraction of its pixels over
    which no surface lies (filled with the lowest height met), and the base's principal curvatures there (1/mm,
    convex positive: the placement's, with the quadric fitted to the relief added)."""

    heights: np.ndarray
    pixel_mm: float
    missing: float
    k1: float
    k2: float


def quadric_fit(heights: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Coefficients (a, b, c, d, e, f) of the least-squares quadric a + b x + c y + d x^2 + e x y + f y^2 of
    ``heights`` (n, n; mm) over the grid of ``axis`` (pixel centres, mm; x along columns)."""
    return np.linalg.lstsq(_quadric_terms(axis), heights.ravel(), rcond=None)[0]


def _quadric_terms(axis: np.ndarray) -> np.ndarray:
    x, y = np.meshgrid(axis, axis)
    x, y = x.ravel(), y.ravel()
    return np.stack([np.ones_like(x), x, y, x * x, x * y, y * y], axis=1)


def without_quadric(heights: np.ndarray, axis: np.ndarray, k1: float, k2: float) -> tuple[np.ndarray, float, float]:
    """``heights`` (n, n; mm over the base walked with curvatures ``k1`` along x, ``k2`` along y) less their
    least-squares quadric (``quadric_fit``), and the principal curvatures of the base with that quadric added: the
    eigenvalues of diag(k1, k2) - [[2d, e], [e, 2f]] (the walked base drops by k s^2 / 2 along the normal)."""
    coef = quadric_fit(heights, axis)
    shape = np.array([[k1 - 2 * coef[3], -coef[4]], [-coef[4], k2 - 2 * coef[5]]])
    low, high = np.linalg.eigvalsh(shape)
    return (heights.ravel() - _quadric_terms(axis) @ coef).reshape(heights.shape), float(high), float(low)


def foot_points(place: Placement, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For ``points`` (m, 3; mm) near the base surface at ``place``: the arc lengths (u along d1, v along d2; mm) of
    their foot points on it, as ``footprint.surface_grid`` walks them, and their offsets h (mm) along its normal there.
    Newton steps on u, v until the offset is normal to the surface."""
    r = points - place.centre
    u, v = r @ place.d1, r @ place.d2
    step = 1e-4  # mm: finite differences of the walk
    for _ in range(FOOT_ITERATIONS):
        p, _ = surface_grid(place, u, v)
        tu = (surface_grid(place, u + step, v)[0] - p) / step
        tv = (surface_grid(place, u, v + step)[0] - p) / step
        off = points - p
        u = u + np.einsum("ij,ij->i", off, tu) / np.einsum("ij,ij->i", tu, tu)
        v = v + np.einsum("ij,ij->i", off, tv) / np.einsum("ij,ij->i", tv, tv)
    p, normal = surface_grid(place, u, v)
    return u, v, np.einsum("ij,ij->i", points - p, normal)


MISSING_REASON = (f"more than {100 * MAX_OFF_FRACTION:g}% of the footprint meets no surface of the mesh within "
                  f"{REACH_MM:g} mm of its base (a hole, or an edge)")
RELIEF_NOTE = (f"the mesh judged as it is: its own relief over its base (the mesh smoothed by a Gaussian of "
               f"{BASE_SIGMA_MM:g} mm, at least twice the samples' spacing, each footprint's least-squares quadric "
               "added), sampled at the engines' pixel; on a plate and a cylinder textured by object texture it feels "
               "within 0.04 JND of its texture (tests/test_object_relief.py)")
