"""Put a texture on a mesh: refine the textured faces to the texture's pixel, displace them along smoothed vertex
normals by the mapping's heights, and check the result (closed, consistently wound, not folded, not crossing
itself).

Steps, each reported in ``TexturedMesh.notes``:

1. the faces of the region are refined to edges of at most ``edge_mm`` (default: sqrt(2) times the mapping's pixel
   on the surface, so that most edges are about one pixel; ``remesh``): untextured faces stay as they were except where they border textured ones;
2. vertex normals, area-weighted over the textured faces (``normals``; so a region's border moves along the
   region's normals, not tilted towards the untextured faces beside it), optionally smoothed over
   ``normal_radius_mm``;
3. the texture's heights at the vertices of textured faces (``mapping``), bumps outwards, ramped from 0 on the
   region's border to full height over ``border_mm`` (a smoothstep of the distance to the nearest border vertex),
   so the border stays where it was: the untextured faces beside it keep their shape, and the long thin faces the
   refinement leaves there are not turned over;
4. refused (InputError) if the texture is deeper than the surface's radius where it is concave: the offset
   surface folds where the depth exceeds the radius at which the normals converge (estimated on every textured
   edge from the normals at its ends: curvature = -(n_b - n_a).(b - a) / |b - a|^2);
5. displaced, then checked: no face turned over, a closed solid by an independent check (``roughness.surface.solid``:
   every edge shared by exactly two triangles, consistently wound, no zero-area triangle), no two faces crossing
   (``intersections``). Writing the mesh checks it again as the file holds it (``meshes.write_mesh``).
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from roughness.core.checks import length
from roughness.core.errors import InputError
from roughness.surface.stl import require_solid

from .intersections import folded_faces, self_intersections, triangles_cross
from .mapping import TextureMapping
from .meshes import require_closed
from .normals import face_normals, smoothed, vertex_normals
from .regions import Region
from .remesh import Refined, refine

DEFAULT_NORMAL_RADIUS_MM = 0.0
DEFAULT_BORDER_MM = 0.5
"""Heights ramp from 0 on a region's border to full height over this distance (mm)."""
"""Normals are area-weighted vertex normals, not smoothed further, unless asked."""
FLAT_CURVATURE = 1e-3
"""Curvatures (1/mm) below this (radii above 1 m) are taken as flat (rounding in the normals of a flat face)."""
NEEDLE_ASPECT = 20.0
"""A face longer than this many times its width is a needle: bisection leaves slivers of it
(docs/tutorials/textured-objects.md: a capsule's 80 x 1.2 mm faces refine to 489 triangles per mm^2 at a 0.3 mm
edge, an icosphere's to 56)."""
CHUNK = 500_000
"""Faces handled at once in the checks (their edges' vectors: tens of MB)."""


@dataclass
class TexturedMesh:
    """A textured mesh (``mesh``, a trimesh, mm) and what was done to make it. ``mean_height_mm`` is the
    area-weighted mean of the heights over the textured base faces, ``height_volume_mm3`` their integral: the
    volume the texture adds to first order (exact on flat faces; on a surface of radius R the offset adds a
    further fraction of about height / R)."""

    mesh: Any  # trimesh.Trimesh
    triangles_in: int
    triangles_out: int
    textured_faces_in: int
    textured_area_mm2: float
    edge_mm: float
    refinement_rounds: int
    normal_smoothing_rounds: int
    max_height_mm: float
    mean_height_mm: float
    height_volume_mm3: float
    min_concave_radius_mm: float
    volume_in_mm3: float
    volume_out_mm3: float
    intersection_pairs_tested: int | None
    notes: list[str] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)

    def as_dict(self) -> dict:
        """JSON-ready; ``min_concave_radius_mm`` is null where no textured part is concave (an infinite radius)."""
        out = {k: v for k, v in self.__dict__.items() if k != "mesh"}
        if not math.isfinite(self.min_concave_radius_mm):
            out["min_concave_radius_mm"] = None
        return out


@dataclass(frozen=True)
class _Input:
    """The checked input of texture_mesh: the mesh as arrays (mm), the faces to texture and the settings (mm)."""

    vertices: np.ndarray
    faces: np.ndarray
    selected: np.ndarray  # bool per face: the region's
    edge_mm: float
    normal_radius_mm: float
    border_mm: float


@dataclass(frozen=True)
class _Relief:
    """The displacement of the refined mesh: ``where`` (indices of the vertices of textured faces) move by
    ``heights`` (mm, ramped at the border) along their normals; ``moving`` flags those vertices."""

    moving: np.ndarray  # bool per vertex
    where: np.ndarray
    heights: np.ndarray
    depth_mm: float  # the largest height


def texture_mesh(mesh, mapping: TextureMapping, region: Region = Region(), edge_mm: float | None = None,
                 normal_radius_mm: float = DEFAULT_NORMAL_RADIUS_MM, check_intersections: bool = True,
                 progress: Callable[[str], object] | None = None,
                 border_mm: float = DEFAULT_BORDER_MM,
                 meter: Callable[[str], Callable[[float], object]] | None = None) -> TexturedMesh:
    """``mesh`` (a closed trimesh, mm) with ``mapping``'s texture on the faces of ``region`` (module docstring).

    ``edge_mm``: longest edge of a textured face (default: sqrt(2) times the mapping's ``pixel_mm``, so that the
    right triangles bisection makes have legs of about one pixel); ``normal_radius_mm``: smooth
    the displacement's normals over about this radius (0: area-weighted vertex normals only);
    ``check_intersections``: test the result for faces crossing each other (the slow part of large meshes);
    ``progress``: called with a line as each step ends (its time in ``TexturedMesh.seconds``); ``border_mm``: the
    heights ramp from 0 on the region's border to full height over this distance (0: no ramp, the border moves);
    ``meter``: given a step's name ("refine", "self-intersection check"), the callback to which that step reports
    the fraction of its work done (``progress.StageMeter.stage``).
    """
    clock = _Clock(progress, meter)
    given = _checked_input(mesh, mapping, region, edge_mm, normal_radius_mm, border_mm)
    notes = _input_notes(given, mapping, region)
    volume_in = signed_volume(given.vertices, given.faces)
    refined = _refined(given, clock, notes)
    normals, rounds = _normals(refined, given, clock, notes)
    relief = _relief(refined, mapping, normals, given.border_mm, clock, notes)
    concave = min_concave_radius(refined.vertices, refined.faces[refined.textured], normals)
    clock.step("concave radius")
    _require_shallower(concave, relief.depth_mm, notes)
    displaced = refined.vertices.copy()
    displaced[relief.where] += relief.heights[:, None] * normals[relief.where]
    del normals
    _check_displaced(refined, displaced, clock, notes)
    tested = None
    if check_intersections:
        tested = _check_crossings(refined, displaced, relief, clock, notes)
    else:
        notes.append("self-intersection NOT checked (asked not to)")
    import trimesh

    area, volume = _area_and_volume(refined, relief)
    return TexturedMesh(trimesh.Trimesh(displaced, refined.faces, process=False, validate=False), len(given.faces),
                        len(refined.faces), int(given.selected.sum()), area, given.edge_mm, refined.rounds, rounds,
                        relief.depth_mm, volume / area, volume, concave.radius_mm, volume_in,
                        signed_volume(displaced, refined.faces), tested, notes, clock.seconds)


def _checked_input(mesh, mapping: TextureMapping, region: Region, edge_mm: float | None, normal_radius_mm: float,
                   border_mm: float) -> _Input:
    """texture_mesh's input as arrays, checked (InputError naming the parameter at fault)."""
    require_closed(mesh, "the mesh")
    edge = length("edge_mm", math.sqrt(2) * mapping.pixel_mm if edge_mm is None else edge_mm)
    radius = length("normal_radius_mm", normal_radius_mm, zero=True)
    border = length("border_mm", border_mm, zero=True)
    selected = np.asarray(region.faces(mesh), dtype=bool)
    if not selected.any():
        raise InputError(f"the region ({region.describe()}) selects no face of the mesh", parameter="region")
    return _Input(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64), selected, edge,
                  radius, border)


def _input_notes(given: _Input, mapping: TextureMapping, region: Region) -> list[str]:
    """Notes on the input: the region, the mapping's own notes, and needle-shaped textured faces."""
    notes = [f"textured region: {region.describe()}: {int(given.selected.sum()):,} of {len(given.faces):,} faces"]
    notes += list(getattr(mapping, "notes", lambda: [])())
    needles = needle_faces(given.vertices, given.faces[given.selected], given.edge_mm)
    if needles:
        notes.append(f"{needles:,} textured faces of the input are needle-shaped (longer than {NEEDLE_ASPECT:g} times "
                     "their width): refining them leaves slivers, several times the triangles (and memory) a "
                     "well-shaped mesh needs; remeshing the input isotropically first (e.g. Blender's Remesh, "
                     "MeshLab's isotropic remeshing) avoids it")
    return notes


def _refined(given: _Input, clock: _Clock, notes: list[str]) -> Refined:
    """The textured faces refined to edges of at most ``edge_mm`` (step 1; noted in ``notes``)."""
    refined = refine(given.vertices, given.faces, given.selected, given.edge_mm, clock.meter("refine"))
    clock.step("check input, refine", f"{len(refined.faces):,} triangles")
    notes.append(f"remeshed the textured faces to edges of at most {given.edge_mm:.4g} mm ({refined.rounds} rounds of "
                 f"edge splitting): {len(given.faces):,} -> {len(refined.faces):,} triangles; untextured faces kept "
                 "except where they border textured ones")
    return refined


def _normals(refined: Refined, given: _Input, clock: _Clock, notes: list[str]) -> tuple[np.ndarray, int]:
    """Unit vertex normals of the textured faces, area-weighted and smoothed over ``normal_radius_mm`` (step 2), and
    the smoothing rounds (noted in ``notes``)."""
    textured = refined.faces[refined.textured]
    normals = vertex_normals(refined.vertices, textured)
    normals, rounds = smoothed(normals, textured, given.normal_radius_mm, given.edge_mm)
    notes.append("displaced along area-weighted vertex normals of the textured faces" +
                 (f", smoothed over about {given.normal_radius_mm:g} mm ({rounds} rounds)" if rounds else ""))
    clock.step("normals", f"{len(refined.vertices):,} vertices")
    return normals, rounds


def _relief(refined: Refined, mapping: TextureMapping, normals: np.ndarray, border_mm: float, clock: _Clock,
            notes: list[str]) -> _Relief:
    """The mapping's heights (mm) at the vertices of textured faces, ramped over ``border_mm`` (step 3); InputError
    if the mapping gives other than one finite height per vertex."""
    moving = np.zeros(len(refined.vertices), dtype=bool)
    moving[refined.faces[refined.textured].ravel()] = True
    where = np.flatnonzero(moving)
    heights = np.asarray(mapping.heights(refined.vertices[where], normals[where]), dtype=float)
    if heights.shape != (len(where),) or not np.all(np.isfinite(heights)):
        raise InputError("the mapping gave heights that are not finite numbers (one per point)", parameter="mapping")
    ramped = border_ramp(refined.vertices, refined.faces, refined.textured, where, border_mm)
    if ramped is not None:
        heights *= ramped
        notes.append(f"heights ramp from 0 on the region's border to full over {border_mm:g} mm "
                     f"({int(np.count_nonzero(ramped < 1)):,} vertices within it)")
    clock.step("heights", f"{len(where):,} vertices")
    return _Relief(moving, where, heights, float(heights.max()))


def _require_shallower(concave: Concave, depth_mm: float, notes: list[str]) -> None:
    """InputError if the texture is deeper than the surface's smallest concave radius (step 4; noted in ``notes``)."""
    if concave.radius_mm < depth_mm:
        x, y, z = concave.where
        raise InputError(f"the texture is {depth_mm:.3g} mm deep but the surface is concave with a radius of "
                         f"{concave.radius_mm:.3g} mm near ({x:.2f}, {y:.2f}, {z:.2f}) mm: displaced along its normals "
                         "it would fold into itself; use a shallower texture (--height-mm), smooth the normals over a "
                         "larger radius (--normal-radius-mm), or leave that part out of the region", parameter="mapping")
    if math.isfinite(concave.radius_mm):
        notes.append(f"smallest concave radius of the textured surface {concave.radius_mm:.3g} mm, above the "
                     f"texture's depth {depth_mm:.3g} mm")


def _check_displaced(refined: Refined, displaced: np.ndarray, clock: _Clock, notes: list[str]) -> None:
    """InputError if displacing turned a face over; SimulationError unless the result passes the independent check
    of a closed solid (``roughness.surface.solid``: watertight, manifold, consistently wound, no zero-area triangle;
    step 5; noted in ``notes``)."""
    v, f = refined.vertices, refined.faces
    folded = np.concatenate([folded_faces(face_normals(v, f[s:s + CHUNK]), displaced, f[s:s + CHUNK])
                             for s in range(0, len(f), CHUNK)])
    if folded.any():
        x, y, z = displaced[f[np.flatnonzero(folded)[0]]].mean(axis=0)
        raise InputError(f"displacing by the texture turns {int(folded.sum()):,} faces over (first near ({x:.2f}, "
                         f"{y:.2f}, {z:.2f}) mm): the texture is too deep for the mesh there; use a shallower texture, "
                         "smooth the normals (--normal-radius-mm) or a finer mesh", parameter="mapping")
    del folded
    notes.append("checked: no face turned over")
    notes.append(require_solid(displaced, f, "the textured mesh", np.float64).line())
    clock.step("displace, turned-face and closed checks")


def _check_crossings(refined: Refined, displaced: np.ndarray, relief: _Relief, clock: _Clock,
                     notes: list[str]) -> int:
    """InputError if two faces of the result cross (step 5); the pairs of faces tested (noted in ``notes``)."""
    f = refined.faces
    crossing = self_intersections(displaced, f, relief.moving[f].any(axis=1), clock.meter("self-intersection check"))
    if crossing.count:
        i, j = crossing.pairs.T
        before = triangles_cross(refined.vertices[f[i]], refined.vertices[f[j]])
        if before.any():  # the input crossed itself there already: no texture depth would help
            x, y, z = refined.vertices[f[i[before][0]]].mean(axis=0)
            raise InputError(f"the mesh crosses itself before any texture is applied: {int(before.sum()):,} pairs of "
                             f"faces intersect (first near ({x:.2f}, {y:.2f}, {z:.2f}) mm); repair it first (e.g. "
                             "in a slicer or MeshLab)", parameter="mesh")
        x, y, z = displaced[f[crossing.pairs[0, 0]]].mean(axis=0)
        raise InputError(f"the textured mesh crosses itself: {crossing.count:,} pairs of faces intersect (first "
                         f"near ({x:.2f}, {y:.2f}, {z:.2f}) mm): the texture is too deep where parts of the object "
                         "are close; use a shallower texture or leave that part out of the region",
                         parameter="mapping")
    clock.step("self-intersection check", f"{crossing.tested:,} pairs")
    notes.append(f"checked: no two faces cross ({crossing.tested:,} pairs of faces with overlapping boxes tested "
                 "exactly)")
    return crossing.tested


def needle_faces(vertices: np.ndarray, faces: np.ndarray, edge_mm: float) -> int:
    """How many of ``faces`` are needles: longer than NEEDLE_ASPECT times their width (height over the longest
    edge), their width above the target edge (so that refinement will cut them)."""
    count = 0
    for s in range(0, len(faces), CHUNK):
        tri = vertices[faces[s:s + CHUNK]]
        longest = np.linalg.norm(tri[:, [1, 2, 0]] - tri, axis=2).max(axis=1)
        width = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1) / np.maximum(longest,
                                                                                                            1e-300)
        count += int(np.count_nonzero((longest > NEEDLE_ASPECT * width) & (longest > edge_mm)))
    return count


def border_ramp(vertices: np.ndarray, faces: np.ndarray, textured: np.ndarray, where: np.ndarray,
                border_mm: float) -> np.ndarray | None:
    """Factors in [0, 1] for the heights at vertices ``where``: 0 on the border of the textured faces (vertices
    shared with untextured faces), a smoothstep of the distance to the nearest border vertex, 1 from ``border_mm``
    on; None if the region has no border (the whole closed mesh) or ``border_mm`` is 0."""
    if border_mm == 0 or textured.all():
        return None
    from scipy.spatial import cKDTree

    on_border = np.zeros(len(vertices), dtype=bool)
    on_border[faces[~textured].ravel()] = True
    in_region = np.zeros(len(vertices), dtype=bool)
    in_region[faces[textured].ravel()] = True
    border = np.flatnonzero(on_border & in_region)
    distance, _ = cKDTree(vertices[border]).query(vertices[where], distance_upper_bound=border_mm)
    t = np.clip(distance / border_mm, 0.0, 1.0)  # inf (beyond border_mm) -> 1
    return t * t * (3 - 2 * t)


class _Clock:
    """Times the steps of texture_mesh and tells ``progress`` as each ends; ``meter`` gives the long steps' progress
    callbacks."""

    def __init__(self, progress: Callable[[str], object] | None,
                 meter: Callable[[str], Callable[[float], object]] | None = None) -> None:
        self.progress, self._meter = progress, meter
        self.seconds: dict[str, float] = {}
        self.last = time.perf_counter()

    def meter(self, name: str) -> Callable[[float], object] | None:
        """The progress callback of the long step ``name`` (None without a meter)."""
        return None if self._meter is None else self._meter(name)

    def step(self, name: str, detail: str = "") -> None:
        now = time.perf_counter()
        self.seconds[name] = now - self.last
        self.last = now
        if self.progress is not None:
            self.progress(f"  {name}: {self.seconds[name]:.1f} s" + (f" ({detail})" if detail else ""))


@dataclass(frozen=True)
class Concave:
    """The smallest concave radius (mm) of a surface and where (inf, and the origin, if nowhere concave)."""

    radius_mm: float
    where: tuple[float, float, float]


def min_concave_radius(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray) -> Concave:
    """The smallest radius (mm) at which the vertex ``normals`` of the faces' edges converge outwards (module
    docstring, step 4)."""
    best, where = math.inf, (0.0, 0.0, 0.0)
    for start in range(0, len(faces), CHUNK):
        fs = faces[start:start + CHUNK]
        a, b = fs.ravel(), np.roll(fs, -1, axis=1).ravel()
        d = vertices[b] - vertices[a]
        curvature = -np.einsum("ij,ij->i", normals[b] - normals[a], d) / np.einsum("ij,ij->i", d, d)
        k = int(np.argmax(curvature))
        if curvature[k] > FLAT_CURVATURE and 1 / curvature[k] < best:
            best = float(1 / curvature[k])
            x, y, z = (float(c) for c in (vertices[a[k]] + vertices[b[k]]) / 2)
            where = (x, y, z)
    return Concave(best, where)


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Enclosed volume (mm^3) of a closed mesh, positive if wound outwards."""
    total = 0.0
    for start in range(0, len(faces), CHUNK):
        tri = vertices[faces[start:start + CHUNK]]
        total += float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum()) / 6
    return total


def _area_and_volume(refined: Refined, relief: _Relief) -> tuple[float, float]:
    """Area (mm^2) of the textured base faces and the integral (mm^3) over them of the heights, linear on each face."""
    heights = np.zeros(len(refined.vertices))
    heights[relief.where] = relief.heights
    faces = refined.faces[refined.textured]
    area = volume = 0.0
    for s in range(0, len(faces), CHUNK):
        f = faces[s:s + CHUNK]
        a = 0.5 * np.linalg.norm(face_normals(refined.vertices, f, unit=False), axis=1)
        area += float(a.sum())
        volume += float((a * heights[f].mean(axis=1)).sum())
    return area, volume


