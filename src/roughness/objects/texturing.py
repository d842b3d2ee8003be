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
   region's border and on sharp edges (``sharp_edges``: a CAD part's edges, where the faces' normals turn by more
   than ``sharp_deg``) to full height (a smoothstep of the distance to the nearest vertex on them), so that they
   stay where they were: the untextured faces beside a border keep their shape, the long thin faces the refinement
   leaves there are not turned over, and the two faces of a sharp edge do not move into each other. The ramp is
   ``border_mm`` wide at a border and at a convex sharp edge; at a concave sharp edge it is at least
   ``ramps.concave_ramp_mm`` wide, so that the faces' displaced surfaces stay on their side of the plane bisecting the
   edge. Before refining, faces between sharp edges narrower than ``min_face_mm`` (engraving, small holes:
   ``sharp_edges.patches``) are taken out of the region and left as they are;
4. refused (InputError) where the texture is deeper than the surface's radius where it is concave: the offset
   surface folds where the depth exceeds the radius at which the normals converge (estimated on every textured
   edge from the normals at its ends: curvature = -(n_b - n_a).(b - a) / |b - a|^2, against the larger height at
   its ends);
5. displaced, then checked: no face turned over, a closed solid by an independent check (``roughness.surface.solid``:
   every edge shared by exactly two triangles, consistently wound, no zero-area triangle), no two faces crossing
   (``intersections``). Writing the mesh checks it again as the file holds it (``meshes.write_mesh``);
6. optionally (``decimate_mm``) decimated within a geometric tolerance, the distance measured and the result checked
   again, closed and not crossing itself (``decimate``).
"""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from roughness.core.checks import length, positive
from roughness.core.errors import InputError
from roughness.surface.stl import require_solid

from .decimate import Decimated, decimate
from .intersections import folded_faces, self_intersections, triangles_cross
from .mapping import TextureMapping
from .meshes import require_closed
from .normals import face_normals, smoothed, vertex_normals
from .ramps import concave_ramp_mm, ramp
from .regions import Region
from .remesh import Refined, refine
from .sharp_edges import DEFAULT_SHARP_DEG, SharpEdges, patches, sharp_edges

DEFAULT_NORMAL_RADIUS_MM = 0.0
"""Normals are area-weighted vertex normals, not smoothed further, unless asked."""
DEFAULT_BORDER_MM = 0.5
"""Heights ramp from 0 on a region's border to full height over this distance (mm)."""
DEFAULT_MIN_FACE_MM = 2.0
"""Faces between sharp edges narrower than this (mm; twice the area over the perimeter: a strip's width) are left
untextured: the walls of an engraving or an embossing (up to about 1 mm deep) and of holes in thin parts. The ramps
at their edges (``border_mm``, wider at concave edges) would leave them little or no texture at full height, and a
fingertip (10 mm footprint) does not feel a texture on them apart from the faces around them."""
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
    further fraction of about height / R). ``sharp_edges_in``: sharp edges of the input among the textured faces;
    ``min_concave_radius_mm``: the smallest concave radius where the surface moves; ``fold_ratio``: the largest
    height over the concave radius there (the surface folds at 1)."""

    mesh: Any  # trimesh.Trimesh
    triangles_in: int
    triangles_out: int
    textured_faces_in: int
    textured_area_mm2: float
    sharp_edges_in: int
    edge_mm: float
    refinement_rounds: int
    normal_smoothing_rounds: int
    max_height_mm: float
    mean_height_mm: float
    height_volume_mm3: float
    min_concave_radius_mm: float
    fold_ratio: float
    volume_in_mm3: float
    volume_out_mm3: float
    intersection_pairs_tested: int | None
    notes: list[str] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)
    decimation: Decimated | None = None  # with ``decimate_mm``: how ``mesh`` was decimated from ``full_mesh``
    full_mesh: Any = None  # with ``decimate_mm``: the textured mesh before decimation (``triangles_out``)

    def as_dict(self) -> dict:
        """JSON-ready; ``min_concave_radius_mm`` is null where no textured part is concave (an infinite radius)."""
        out = {k: v for k, v in self.__dict__.items() if k not in ("mesh", "full_mesh", "decimation")}
        out["decimation"] = None if self.decimation is None else self.decimation.as_dict()
        if not math.isfinite(self.min_concave_radius_mm):
            out["min_concave_radius_mm"] = None
        return out


@dataclass(frozen=True)
class _Input:
    """The checked input of texture_mesh: the mesh as arrays (mm), the faces to texture and the settings (mm)."""

    vertices: np.ndarray
    faces: np.ndarray
    selected: np.ndarray  # bool per face: the region's, without its narrow faces
    edge_mm: float
    normal_radius_mm: float
    border_mm: float
    sharp: SharpEdges  # of the input, among the selected faces


@dataclass(frozen=True)
class _Relief:
    """The displacement of the refined mesh: ``where`` (indices of the vertices of textured faces) move by
    ``heights`` (mm, ramped at borders and sharp edges) along their normals; ``moving`` flags those vertices."""

    moving: np.ndarray  # bool per vertex
    where: np.ndarray
    heights: np.ndarray
    depth_mm: float  # the largest height

    def full_heights(self) -> np.ndarray:
        """The heights (mm) at every vertex of the refined mesh (0 where nothing moves)."""
        out = np.zeros(len(self.moving))
        out[self.where] = self.heights
        return out


def texture_mesh(mesh, mapping: TextureMapping, region: Region = Region(), edge_mm: float | None = None,
                 normal_radius_mm: float = DEFAULT_NORMAL_RADIUS_MM, check_intersections: bool = True,
                 progress: Callable[[str], object] | None = None,
                 border_mm: float = DEFAULT_BORDER_MM,
                 meter: Callable[[str], Callable[[float], object]] | None = None,
                 sharp_deg: float = DEFAULT_SHARP_DEG, min_face_mm: float = DEFAULT_MIN_FACE_MM,
                 decimate_mm: float | None = None) -> TexturedMesh:
    """``mesh`` (a closed trimesh, mm) with ``mapping``'s texture on the faces of ``region`` (module docstring).

    ``edge_mm``: longest edge of a textured face (default: sqrt(2) times the mapping's ``pixel_mm``, so that the
    right triangles bisection makes have legs of about one pixel); ``normal_radius_mm``: smooth
    the displacement's normals over about this radius (0: area-weighted vertex normals only);
    ``check_intersections``: test the result for faces crossing each other (the slow part of large meshes);
    ``progress``: called with a line as each step ends (its time in ``TexturedMesh.seconds``); ``border_mm``: the
    heights ramp from 0 on the region's border to full height over this distance (0: no ramp, the border moves);
    ``meter``: given a step's name ("refine", "self-intersection check"), the callback to which that step reports
    the fraction of its work done (``progress.StageMeter.stage``); ``sharp_deg``: edges whose faces' normals turn by
    more than this (degrees) are borders of the texture (180: none); ``min_face_mm``: faces between sharp edges
    narrower than this (mm) are left untextured (0: none); ``decimate_mm``: the result decimated to the fewest
    triangles whose surface is measured within this distance (mm) of the full one (``decimate``; step 6:
    ``TexturedMesh.mesh`` is the decimated mesh, ``full_mesh`` the full one).
    """
    if decimate_mm is not None:
        positive("decimate_mm", decimate_mm)
    clock = _Clock(progress, meter)
    given, notes = _checked_input(mesh, mapping, region, edge_mm, normal_radius_mm, border_mm, sharp_deg, min_face_mm)
    notes += _input_notes(given, mapping)
    volume_in = signed_volume(given.vertices, given.faces)
    refined = _refined(given, clock, notes)
    normals, rounds = _normals(refined, given, clock, notes)
    relief = _relief(refined, mapping, normals, given, clock, notes)
    concave = tightest_concave(refined.vertices, refined.faces[refined.textured], normals, relief.full_heights())
    clock.step("concave radius")
    _require_shallower(concave, notes)
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
    full = trimesh.Trimesh(displaced, refined.faces, process=False, validate=False)
    result = TexturedMesh(full, len(given.faces), len(refined.faces), int(given.selected.sum()), area,
                          given.sharp.count, given.edge_mm, refined.rounds, rounds, relief.depth_mm, volume / area,
                          volume, concave.radius_mm, concave.ratio, volume_in, signed_volume(displaced, refined.faces),
                          tested, notes, clock.seconds)
    if decimate_mm is None:
        return result
    found = decimate(displaced, refined.faces, decimate_mm, progress)
    clock.step("decimate", f"{found.triangles:,} triangles")
    return dataclasses.replace(result, mesh=trimesh.Trimesh(found.vertices, found.faces, process=False, validate=False),
                               decimation=found, full_mesh=full)


def _checked_input(mesh, mapping: TextureMapping, region: Region, edge_mm: float | None, normal_radius_mm: float,
                   border_mm: float, sharp_deg: float, min_face_mm: float) -> tuple[_Input, list[str]]:
    """texture_mesh's input as arrays, checked (InputError naming the parameter at fault), the region without its
    faces narrower than ``min_face_mm`` between sharp edges, and notes on the region."""
    require_closed(mesh, "the mesh")
    edge = length("edge_mm", math.sqrt(2) * mapping.pixel_mm if edge_mm is None else edge_mm)
    radius = length("normal_radius_mm", normal_radius_mm, zero=True)
    border = length("border_mm", border_mm, zero=True)
    narrow = length("min_face_mm", min_face_mm, zero=True)
    if not 0 < positive("sharp_deg", sharp_deg) <= 180:
        raise InputError(f"sharp_deg must be at most 180 degrees (no edge sharp), got {sharp_deg!r}",
                         parameter="sharp_deg")
    selected = np.asarray(region.faces(mesh), dtype=bool)
    if not selected.any():
        raise InputError(f"the region ({region.describe()}) selects no face of the mesh", parameter="region")
    vertices, faces = np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64)
    notes = [f"textured region: {region.describe()}: {int(selected.sum()):,} of {len(faces):,} faces"]
    found = patches(vertices, faces, selected, sharp_deg)
    small = np.flatnonzero(found.width_mm < narrow)
    if len(small) == len(found.area_mm2):
        raise InputError(f"every face of the region between sharp edges (turning by more than {sharp_deg:g} degrees) is "
                         f"narrower than {narrow:g} mm (widest {found.width_mm.max():.3g} mm): nothing is left to "
                         "texture; a smaller --min-face-mm textures narrow faces, a larger --sharp-deg joins faces "
                         "across their edges", parameter="min_face_mm")
    if len(small):
        selected &= ~np.isin(found.label, small)
        notes.append(f"{len(small):,} of {len(found.area_mm2):,} faces between sharp edges are narrower than {narrow:g} "
                     f"mm (twice the area over the perimeter; {found.area_mm2[small].sum():.1f} mm^2: engraving, small "
                     "holes, chamfers) and left untextured (--min-face-mm)")
    edges = sharp_edges(vertices, faces[selected], sharp_deg)
    notes.append(f"{edges.count:,} sharp edges (faces turning by more than {sharp_deg:g} degrees, --sharp-deg) in the "
                 f"region, {int(edges.concave.sum()):,} of them concave: the texture ramps to 0 at them"
                 if edges.count else f"no sharp edge (faces turning by more than {sharp_deg:g} degrees) in the region")
    return _Input(vertices, faces, selected, edge, radius, border, edges), notes


def _input_notes(given: _Input, mapping: TextureMapping) -> list[str]:
    """Notes on the input: the mapping's own notes, and needle-shaped textured faces."""
    notes = list(getattr(mapping, "notes", lambda: [])())
    needles = needle_faces(given.vertices, given.faces[given.selected], given.edge_mm)
    if needles:
        notes.append(f"{needles:,} textured faces of the input are needle-shaped (longer than {NEEDLE_ASPECT:g} times "
                     "their width): refining them leaves slivers, several times the triangles (and memory) a "
                     "well-shaped mesh needs; remeshing the input isotropically first (e.g. Blender's Remesh, "
                     "MeshLab's isotropic remeshing) avoids it")
    return notes


def _refined(given: _Input, clock: _Clock, notes: list[str]) -> Refined:
    """The textured faces refined to edges of at most ``edge_mm`` (step 1; noted in ``notes``)."""
    refined = refine(given.vertices, given.faces, given.selected, given.edge_mm, clock.meter("refine"),
                     given.sharp.ends)
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


def _relief(refined: Refined, mapping: TextureMapping, normals: np.ndarray, given: _Input, clock: _Clock,
            notes: list[str]) -> _Relief:
    """The mapping's heights (mm) at the vertices of textured faces, ramped at borders and sharp edges (step 3);
    InputError if the mapping gives other than one finite height per vertex."""
    moving = np.zeros(len(refined.vertices), dtype=bool)
    moving[refined.faces[refined.textured].ravel()] = True
    where = np.flatnonzero(moving)
    heights = np.asarray(mapping.heights(refined.vertices[where], normals[where]), dtype=float)
    if heights.shape != (len(where),) or not np.all(np.isfinite(heights)):
        raise InputError("the mapping gave heights that are not finite numbers (one per point)", parameter="mapping")
    heights *= _ramps(refined, where, float(heights.max()), given, notes)
    clock.step("heights", f"{len(where):,} vertices")
    return _Relief(moving, where, heights, float(heights.max()))


def _ramps(refined: Refined, where: np.ndarray, depth_mm: float, given: _Input, notes: list[str]) -> np.ndarray:
    """Factors in [0, 1] for the heights at vertices ``where`` (step 3): the smallest of the ramps from the region's
    border and convex sharp edges (over ``border_mm``) and from concave sharp edges (over ``concave_ramp_mm``, at
    least ``border_mm``); noted in ``notes``."""
    v, f, textured = refined.vertices, refined.faces, refined.textured
    factor = np.ones(len(where))
    in_region = np.zeros(len(v), dtype=bool)
    in_region[f[textured].ravel()] = True
    on_border = np.zeros(len(v), dtype=bool)
    on_border[f[~textured].ravel()] = True
    concave = np.zeros(len(v), dtype=bool)
    concave[refined.creases[given.sharp.concave[refined.crease_of]].ravel()] = True
    convex = np.zeros(len(v), dtype=bool)
    convex[refined.creases.ravel()] = True
    convex &= ~concave
    turn = given.sharp.sharpest_concave_deg()
    concave_mm = max(given.border_mm, concave_ramp_mm(depth_mm, turn)) if turn is not None else 0.0
    for anchors, width, what in ((on_border & in_region, given.border_mm, "the region's border"),
                                 (convex, given.border_mm, "convex sharp edges"),
                                 (concave, concave_mm, "concave sharp edges")):
        ramped = ramp(v, anchors, where, width)
        if ramped is not None:
            factor = np.minimum(factor, ramped)
            notes.append(f"heights ramp from 0 on {what} to full over {width:.3g} mm "
                         f"({int(np.count_nonzero(ramped < 1)):,} vertices within it)"
                         + (f": at least {concave_ramp_mm(depth_mm, turn):.3g} mm for a texture {depth_mm:.3g} mm "
                            f"deep where the faces turn by up to {turn:.0f} degrees" if anchors is concave else ""))
    return factor


def _require_shallower(concave: Concave, notes: list[str]) -> None:
    """InputError where the texture is deeper than the surface's concave radius (step 4; noted in ``notes``)."""
    if concave.ratio >= 1:
        x, y, z = concave.where
        raise InputError(f"the texture is {concave.depth_mm:.3g} mm deep near ({x:.2f}, {y:.2f}, {z:.2f}) mm, where the "
                         f"surface is concave with a radius of {concave.at_radius_mm:.3g} mm: displaced along its "
                         "normals it would fold into itself; use a shallower texture (--height-mm), make the crease "
                         "there a sharp edge the texture ramps down at (a smaller --sharp-deg), smooth the normals over "
                         "a larger radius (--normal-radius-mm), or leave that part out (--region)", parameter="mapping")
    if math.isfinite(concave.radius_mm):
        notes.append(f"concave parts: the texture comes closest to folding where it is {concave.depth_mm:.3g} mm deep on "
                     f"a radius of {concave.at_radius_mm:.3g} mm (depth / radius {concave.ratio:.2g}; it folds at 1); "
                     f"smallest concave radius where the surface moves {concave.radius_mm:.3g} mm")


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
                         "are close (a narrow slot or gap); use a shallower texture (--height-mm), or leave that part out "
                         "(--region, or a --min-face-mm above the width of the slot's faces)",
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
    """Where a displaced surface comes closest to folding: ``ratio`` the largest height over concave radius on an
    edge (it folds at 1), the height ``depth_mm`` and radius ``at_radius_mm`` there, ``where`` (mm); ``radius_mm``
    the smallest concave radius on an edge with a moving end (inf, ratio 0, the origin, if nowhere concave)."""

    radius_mm: float
    ratio: float = 0.0
    depth_mm: float = 0.0
    at_radius_mm: float = math.inf
    where: tuple[float, float, float] = (0.0, 0.0, 0.0)


def tightest_concave(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray, heights: np.ndarray) -> Concave:
    """The ``Concave`` of the faces' edges, curvature from the vertex ``normals`` at their ends (module docstring,
    step 4), against the larger of the ``heights`` (mm, per vertex) at their ends."""
    radius, worst = math.inf, Concave(math.inf)
    for start in range(0, len(faces), CHUNK):
        fs = faces[start:start + CHUNK]
        a, b = fs.ravel(), np.roll(fs, -1, axis=1).ravel()
        d = vertices[b] - vertices[a]
        curvature = -np.einsum("ij,ij->i", normals[b] - normals[a], d) / np.einsum("ij,ij->i", d, d)
        depth = np.maximum(heights[a], heights[b])
        concave = (curvature > FLAT_CURVATURE) & (depth > 0)
        if not concave.any():
            continue
        radius = min(radius, float(1 / curvature[concave].max()))
        ratio = np.where(concave, depth * curvature, 0.0)
        k = int(np.argmax(ratio))
        if ratio[k] > worst.ratio:
            x, y, z = (float(c) for c in (vertices[a[k]] + vertices[b[k]]) / 2)
            worst = Concave(math.inf, float(ratio[k]), float(depth[k]), float(1 / curvature[k]), (x, y, z))
    return Concave(radius, worst.ratio, worst.depth_mm, worst.at_radius_mm, worst.where)


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


