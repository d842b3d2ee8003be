"""How each part of a textured object feels: a roughness map over its surface, curvature included.

Evaluation points are spread over the textured region about ``spacing_mm`` apart. At each, the base
surface's principal curvatures at the footprint's scale (``curvature``) decide what answers:

- refused, with the reason, where the skin cannot rest (a concave radius below the footprint's half side
  or half diagonal), where the 10 mm footprint does not lie on the object (the object or the region is
  too small or too curved there: ``footprint.on_surface``), or where the curvature lies beyond the
  curvature study's measured range;
- otherwise the texture under the footprint, unrolled (``footprint.unrolled``), is judged by a flat engine
  (``spectral`` by default, or the ``surrogate``) and its V multiplied by the curvature study's measured
  correction (``correction``); where that correction is below ``NEGLIGIBLE`` (with its error) the flat V
  stands alone. ``curved="fem"`` runs the curved FEM instead of the correction where curvature is not
  negligible (cylinders and spheres only; seconds per point).

Without a mapping (``mapping=None``) the mesh is judged as it is, textured elsewhere: its own relief over its
smoothed base stands for the unrolled texture, and the base's curvature for the footprint's (``relief``).

Each V carries its uncertainty: the engine's (spectral: Monte Carlo standard error; surrogate: ensemble
spread) and the correction's error, in quadrature. V is placed on the engine's standard scale (equivalent
wavelength) and, given a reference texture, counted in JNDs from it.
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.core.limits import MAX_MAP_POSITIONS, check_size
from roughness.core.reprs import short_repr
from roughness.curvature_correction import correction, measured_ranges, restable
from roughness.perceptual_scale import jnd, load_scale
from roughness.surface.heightmap import Heightmap

from .curvature import FOOTPRINT_RADIUS_MM, SurfaceSamples, principal_curvatures
from .feel_budget import feel_budget
from .footprint import FOOTPRINT_MM, MAX_OFF_FRACTION, Placement, on_surface, unrolled
from .relief import MISSING_REASON, RELIEF_NOTE, MeshRelief, base_samples

ENGINES = ("spectral", "surrogate")
CURVED = ("correction", "fem")
BATCH_POINTS = 64  # footprints unrolled and judged at once (64 maps of 200 x 200 pixels: 20 MB)
NEGLIGIBLE = 0.01  # |correction - 1| + its error below this (1% of V, a twentieth of a JND): the flat V stands
CURVED_FEM_AXIS_RATIO = 0.1  # curved FEM: |k2| below this fraction of |k1| is a cylinder, |k1 - k2| a sphere


@dataclass(frozen=True)
class Reference:
    """A reference texture's flat V by the map's engine and its equivalent wavelength (mm)."""

    name: str
    roughness: float
    lambda_mm: float


@dataclass(frozen=True)
class RegionFeel:
    """One region's row: area (mm^2), points, refused fraction, V median and range, lambda and JND medians.

    Points whose V is below the standard scale's floor have no equivalent wavelength (``below_scale_fraction`` of
    the judged points): the lambda median is over the others (None if none); JNDs count them at the floor, so
    where they are the median's side, the JND median is a bound (``jnd_is_bound``: at least that far below)."""

    name: str
    area_mm2: float
    points: int
    refused_fraction: float
    roughness_median: float | None
    roughness_min: float | None
    roughness_max: float | None
    uncertainty_median: float | None
    lambda_median_mm: float | None
    jnd_median: float | None  # from the reference, if any
    below_scale_fraction: float = 0.0
    jnd_is_bound: bool = False

    def as_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass(frozen=True)
class FeelMap:
    """The roughness map of a textured object: one entry per evaluation point (arrays of length n)."""

    points: np.ndarray  # (n, 3) mm
    normals: np.ndarray  # (n, 3)
    k1: np.ndarray  # principal curvatures (1/mm, convex positive), at the footprint's scale
    k2: np.ndarray
    roughness: np.ndarray  # V on the object (nan where refused)
    uncertainty: np.ndarray  # of V: engine and correction, in quadrature (nan where refused)
    flat_roughness: np.ndarray  # the flat engine's V of the unrolled texture (nan where not computed)
    method: tuple[str, ...]  # "flat", "corrected", "fem" or "refused"
    reasons: tuple[str, ...]  # why refused, or the correction applied ("" for flat)
    in_region: np.ndarray  # (regions, n) bool: which regions each point lies in (regions may overlap)
    region_names: tuple[str, ...]
    region_areas_mm2: tuple[float, ...]
    engine: str
    curved: str
    spacing_mm: float
    scale: object = field(repr=False)  # the engine's StandardScale
    reference: Reference | None = None
    seconds: float = 0.0
    notes: tuple[str, ...] = ()  # what the map chose: spacings widened to the budget, a mesh's own relief judged

    def __repr__(self) -> str:
        ok = ~np.isnan(self.roughness)
        v = (f"V {np.nanmin(self.roughness):.4g}..{np.nanmax(self.roughness):.4g} (median "
             f"{np.nanmedian(self.roughness):.4g})" if ok.any() else "no V")
        return short_repr(self, f"{len(self.points)} points {self.spacing_mm:g} mm apart", v,
                          f"{self.method.count('corrected') + self.method.count('fem')} curved",
                          f"{self.method.count('refused')} refused", self.engine,
                          f"reference {self.reference.name}" if self.reference else "")

    @property
    def below_scale(self) -> np.ndarray:
        """Points judged with a V below the standard scale's floor (no equivalent wavelength)."""
        return np.array([math.isfinite(v) and v < self.scale.floor for v in self.roughness], dtype=bool)

    @property
    def lambdas_mm(self) -> np.ndarray:
        """Equivalent wavelength (mm) of each V on the engine's standard scale (nan where refused or below it)."""
        return np.where(self.below_scale, np.nan, self._floored_lambdas_mm())

    def _floored_lambdas_mm(self) -> np.ndarray:
        return np.array([self.scale.floored_lambda(v) if math.isfinite(v) else np.nan for v in self.roughness])

    @property
    def jnd(self) -> np.ndarray | None:
        """JNDs of each point from the reference (positive: rougher), or None without one; a V below the scale is
        counted at its floor (the distance is then a bound: at least that far below)."""
        if self.reference is None:
            return None
        return np.array([jnd(lam, self.reference.lambda_mm) if math.isfinite(lam) else np.nan
                         for lam in self._floored_lambdas_mm()])

    def table(self) -> tuple[RegionFeel, ...]:
        """One row per region."""
        lams, jnds, below = self.lambdas_mm, self.jnd, self.below_scale
        rows = []
        for i, (name, area) in enumerate(zip(self.region_names, self.region_areas_mm2)):
            mine = self.in_region[i]
            ok = mine & ~np.isnan(self.roughness)
            v = self.roughness[ok]

            def median(values) -> float | None:
                return float(np.median(values)) if len(values) else None

            placed = ok & ~below
            below_fraction = float(below[ok].mean()) if ok.any() else 0.0
            rows.append(RegionFeel(name, area, int(mine.sum()), float(1 - ok.sum() / mine.sum()) if mine.any() else 0.0,
                                   median(v), float(v.min()) if len(v) else None, float(v.max()) if len(v) else None,
                                   median(self.uncertainty[ok]), median(lams[placed]),
                                   None if jnds is None else median(jnds[ok]), below_fraction,
                                   jnds is not None and below_fraction >= 0.5))
        return tuple(rows)

    def refusals(self) -> dict[str, int]:
        """Each distinct reason for refusing, with how many points it refused."""
        counts: dict[str, int] = {}
        for method, why in zip(self.method, self.reasons):
            if method == "refused":
                counts[why] = counts.get(why, 0) + 1
        return counts

    def as_dict(self) -> dict:
        """JSON-ready: the table, the refusals and every point."""
        jnd = self.jnd
        return {"engine": self.engine, "curved": self.curved, "spacing_mm": self.spacing_mm,
                "seconds": self.seconds, "map_notes": list(self.notes),
                "reference": None if self.reference is None else self.reference.__dict__,
                "regions": [row.as_dict() for row in self.table()],
                "refusals": [{"reason": why, "points": n} for why, n in self.refusals().items()],
                "points": [{"xyz_mm": p.tolist(), "k1_per_mm": float(a), "k2_per_mm": float(b),
                            "roughness": _num(v), "uncertainty": _num(u), "flat_roughness": _num(f),
                            "method": m, "reason": r,
                            "regions": [name for name, inside in zip(self.region_names, g) if inside],
                            **({} if jnd is None else {"jnd": _num(j)})}
                           for p, a, b, v, u, f, m, r, g, j in zip(
                               self.points, self.k1, self.k2, self.roughness, self.uncertainty, self.flat_roughness,
                               self.method, self.reasons, self.in_region.T, jnd if jnd is not None else self.k1)]}


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def evaluation_points(samples: SurfaceSamples, in_region: np.ndarray, spacing_mm: float) -> np.ndarray:
    """Indices of samples about ``spacing_mm`` apart over the region: per cube of that side, the sample nearest
    its centre."""
    idx = np.nonzero(in_region[samples.faces])[0]
    if len(idx) == 0:
        raise InputError("the region holds no surface: nothing to map", parameter="regions")
    pts = samples.points[idx]
    cells = np.floor(pts / spacing_mm)
    distance = np.linalg.norm(pts - (cells + 0.5) * spacing_mm, axis=1)
    order = np.lexsort((distance, *cells.T[::-1]))
    _, first = np.unique(cells[order], axis=0, return_index=True)
    return np.sort(idx[order[first]])


def reference_of(name_or_map: str | Heightmap | Reference, engine: str, scale, model=None) -> Reference:
    """A reference texture (a name such as ``standard-1.0``, or a heightmap) judged flat by ``engine`` (``model``:
    the surrogate's, default the shipped one; a ``Reference`` as it is: e.g. a target)."""
    from roughness.prediction import predictions

    if isinstance(name_or_map, Reference):
        return name_or_map
    if isinstance(name_or_map, Heightmap):
        name, hm = "reference", name_or_map
    else:
        from roughness.dataset.catalogue import make_texture

        try:
            hm, _ = make_texture(name_or_map)
        except InputError as err:
            raise InputError(f"reference {name_or_map!r}: {err}", parameter="reference") from None
        name = name_or_map
    [p] = predictions([(name, hm)], engine=engine, model=model)  # a named texture, or a map checked as it was read
    return Reference(name, p.roughness, scale.floored_lambda(p.roughness))


def feel_map(mesh, mapping=None, regions: dict[str, np.ndarray] | None = None, spacing_mm: float | None = None,
             engine: str = "spectral", curved: str = "correction", reference: str | Heightmap | Reference | None = None,
             samples: SurfaceSamples | None = None,
             progress: Callable[[int, int], None] | None = None) -> FeelMap:
    """The roughness map of ``mesh`` (trimesh.Trimesh, mm; the untextured base) under ``mapping`` (a
    ``TextureMapping``; None: ``mesh`` as it is, its own relief over its smoothed base, ``relief``) over ``regions``
    (name -> bool per face; default: all of it), points about ``spacing_mm`` apart (default: 5 mm, wider for a
    large part: ``feel_budget``; module docstring). ``progress(done, total)`` is told after each batch of
    footprints."""
    start = time.perf_counter()
    if spacing_mm is not None:
        spacing_mm = positive("spacing_mm", spacing_mm)
    if engine not in ENGINES:
        raise InputError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}", parameter="engine")
    if curved not in CURVED:
        raise InputError(f"unknown curved-base method {curved!r}; choose one of {', '.join(CURVED)}",
                         parameter="curved")
    regions = _checked_regions(regions, len(mesh.faces))
    textured = np.logical_or.reduce(list(regions.values()))
    budget = feel_budget(float(mesh.area), float(mesh.area_faces[textured].sum()), spacing_mm, mapping is None)
    spacing_mm = budget.point_spacing_mm
    check_size(f"evaluation points {spacing_mm:g} mm apart over {mesh.area_faces[textured].sum():.4g} mm^2",
               mesh.area_faces[textured].sum() / spacing_mm**2, MAX_MAP_POSITIONS, "spacing_mm")
    relief = MeshRelief.of(mesh) if mapping is None else None
    samples = samples or (base_samples(mesh, budget.sample_spacing_mm) if relief
                          else SurfaceSamples.of(mesh, budget.sample_spacing_mm))
    chosen = evaluation_points(samples, textured, spacing_mm)
    names = tuple(regions)
    in_region = np.stack([regions[name][samples.faces[chosen]] for name in names])
    curv = principal_curvatures(samples, samples.points[chosen], samples.normals[chosen], FOOTPRINT_RADIUS_MM)
    model = _shipped_surrogate() if engine == "surrogate" else None  # loaded once for the whole map
    scale = load_scale("spectral" if model is None else model.fidelity)
    ref = None if reference is None else reference_of(reference, engine, scale, model)  # a bad name refused first
    n = len(chosen)
    places = [Placement(curv.points[i], curv.normals[i], curv.k1[i], curv.k2[i], curv.d1[i], curv.d2[i])
              for i in range(n)]
    decided = [_decide(samples, place, textured, curved) for place in places]
    method, reasons = [d.method for d in decided], [d.reason for d in decided]
    flat, flat_error = np.full(n, np.nan), np.full(n, np.nan)
    roughness, uncertainty = np.full(n, np.nan), np.full(n, np.nan)
    judged = [i for i in range(n) if method[i] != "refused"]
    for begin in range(0, len(judged), BATCH_POINTS):  # unrolled footprints held a batch at a time
        batch = judged[begin:begin + BATCH_POINTS]
        if relief:
            maps = _relief_maps(relief, samples, places, batch, textured, curved, decided, curv)
            for i in batch:
                method[i], reasons[i] = decided[i].method, decided[i].reason
        else:
            maps = {i: unrolled(mapping, places[i]) for i in batch}
        batch = list(maps)
        for i, notes in _judge_flat(maps, engine, model, flat, flat_error).items():  # e.g. the surrogate out of domain
            reasons[i] = "; ".join([*([reasons[i]] if reasons[i] else []), *notes])
        for i in batch:
            d = decided[i]
            if d.method == "fem":
                try:
                    roughness[i], uncertainty[i], reasons[i] = _curved_fem(maps[i], curv.k1[i], curv.k2[i])
                except InputError as err:
                    method[i], reasons[i] = "refused", str(err)
                continue
            roughness[i] = flat[i] * d.factor
            uncertainty[i] = math.hypot(d.factor * flat_error[i], flat[i] * d.error)
        if progress:
            progress(min(begin + BATCH_POINTS, len(judged)), len(judged))
    areas = tuple(float(mesh.area_faces[mask].sum()) for mask in regions.values())
    return FeelMap(curv.points, curv.normals, curv.k1, curv.k2, roughness, uncertainty, flat, tuple(method),
                   tuple(reasons), in_region, names, areas, engine, curved, spacing_mm,
                   scale, ref, time.perf_counter() - start, budget.notes + ((RELIEF_NOTE,) if relief else ()))


def _relief_maps(relief: MeshRelief, samples: SurfaceSamples, places: list[Placement], batch: list[int],
                 textured: np.ndarray, curved: str, decided: list[_Decision], curv) -> dict[int, Heightmap]:
    """The mesh's relief under the footprints of ``batch``; each point's curvature (``curv``) and verdict
    (``decided``) taken again with the base's quadric fitted to the relief; a footprint with too much of it over no
    surface is refused instead."""
    maps = {}
    for i in batch:
        found = relief.unrolled(places[i])
        if found.missing > MAX_OFF_FRACTION:
            decided[i] = _Decision("refused", MISSING_REASON)
            continue
        curv.k1[i], curv.k2[i] = found.k1, found.k2
        place = places[i]
        decided[i] = _decide(samples, Placement(place.centre, place.normal, found.k1, found.k2, place.d1, place.d2),
                             textured, curved)
        if decided[i].method != "refused":
            maps[i] = Heightmap(found.heights, found.pixel_mm)
    return maps


def _checked_regions(regions: dict[str, np.ndarray] | None, faces: int) -> dict[str, np.ndarray]:
    """Regions as bool face masks of the right length, none empty (default: the whole mesh, ``all``)."""
    if regions is None:
        return {"all": np.ones(faces, dtype=bool)}
    if not regions:
        raise InputError("no region given: name at least one, or leave regions out for the whole mesh",
                         parameter="regions")
    checked = {}
    for name, mask in regions.items():
        mask = np.asarray(mask)
        if mask.dtype != bool or mask.shape != (faces,):
            raise InputError(f"region {name!r} must be one bool per mesh face ({faces}), got {mask.dtype} "
                             f"{mask.shape}", parameter="regions")
        if not mask.any():
            raise InputError(f"region {name!r} holds no face of the mesh", parameter="regions")
        checked[name] = mask
    return checked


CANNOT_REST = (f"the skin cannot rest here: a concave radius below half the {FOOTPRINT_MM:g} mm footprint's side "
               f"({FOOTPRINT_MM / 2:g} mm) or, along its diagonal, below half its diagonal ({FOOTPRINT_MM / 2**0.5:.3g} mm)")
OFF_OBJECT = (f"the {FOOTPRINT_MM:g} mm footprint does not lie on the object here (more than "
              f"{100 * MAX_OFF_FRACTION:g}% of it off the surface): the object is too small or too curved here for "
              "the model")
ON_BORDER = (f"the {FOOTPRINT_MM:g} mm footprint straddles the textured region's border (more than "
             f"{100 * MAX_OFF_FRACTION:g}% of it untextured): the region is too small here for the model")
def _refusal(samples: SurfaceSamples, place: Placement, textured: np.ndarray) -> str:
    """Why no V can be given at ``place`` for the geometry alone (empty if it can): one of the texts above,
    the same for every point refused for the same reason."""
    if restable(place.k1, place.k2, FOOTPRINT_MM):
        return CANNOT_REST
    off, outside = on_surface(samples, place, textured)
    if off > MAX_OFF_FRACTION:
        return OFF_OBJECT
    if outside > MAX_OFF_FRACTION:
        return ON_BORDER
    return ""


@dataclass(frozen=True)
class _Decision:
    """What answers at one point: ``method`` (flat, corrected, fem, refused), the reason or correction note, and the
    correction's factor and relative error."""

    method: str
    reason: str = ""
    factor: float = 1.0
    error: float = 0.0


def _decide(samples: SurfaceSamples, place: Placement, textured: np.ndarray, curved: str) -> _Decision:
    """The geometry's verdict at ``place`` (module docstring): refused and why, flat, corrected or curved FEM."""
    why = _refusal(samples, place, textured)
    if why:
        return _Decision("refused", why)
    try:
        fix = correction(place.k1, place.k2)
    except InputError:
        if curved == "fem":
            return _Decision("fem")
        return _Decision("refused", f"too curved: a principal radius beyond the curvature study's measured range "
                                    f"({measured_ranges()}); curved='fem' asks the curved FEM")
    if abs(fix.factor - 1) + fix.error < NEGLIGIBLE:
        return _Decision("flat")
    if curved == "fem":
        return _Decision("fem")
    return _Decision("corrected", fix.note, fix.factor, fix.error)


def _judge_flat(maps: dict[int, Heightmap], engine: str, model, flat: np.ndarray,
                flat_error: np.ndarray) -> dict[int, list[str]]:
    """The flat engine's V and its error for each unrolled footprint, written into ``flat``/``flat_error``; returns
    the engine's notes by point (the surrogate: why a footprint lies outside its domain)."""
    from roughness.prediction import predictions

    keys = list(maps)
    notes: dict[int, list[str]] = {}
    if not keys:
        return notes
    # footprints of the object's texture, checked (units included) as it was read: the engines only
    for i, p in zip(keys, predictions([(str(i), maps[i]) for i in keys], engine=engine, model=model)):
        flat[i] = p.roughness
        flat_error[i] = p.roughness_stderr if p.roughness_stderr is not None else (p.roughness_std or 0.0)
        if p.domain_notes:
            notes[i] = [f"{p.engine}: {note}" for note in p.domain_notes]
    return notes


def _curved_fem(hm: Heightmap, k1: float, k2: float) -> tuple[float, float, str]:
    """V, its Monte Carlo error and a note from the curved FEM, for a cylinder- or sphere-like base."""
    from roughness.prediction import CurvedBase, PredictOptions, predictions

    big, small = (k1, k2) if abs(k1) >= abs(k2) else (k2, k1)
    if abs(small) <= CURVED_FEM_AXIS_RATIO * abs(big):
        base, k = "cylinder", big
        axis = "y" if big == k1 else "x"  # the map's x runs along d1: a cylinder curving along d1 is straight along y
    elif abs(k1 - k2) <= CURVED_FEM_AXIS_RATIO * abs(big):
        base, k, axis = "sphere", (k1 + k2) / 2, "x"
    else:
        raise InputError(f"principal radii {1 / k1:.3g} and {1 / k2:.3g} mm: the curved FEM models cylinders and "
                         "spheres only", parameter="curved")
    [p] = predictions([("footprint", hm)], engine="fem", options=PredictOptions(curved=CurvedBase(1 / k, base, axis)))
    return p.roughness, p.roughness_stderr or 0.0, f"curved FEM on a {base} of radius {1 / k:.3g} mm"


def _shipped_surrogate():
    """The shipped surrogate (``SurrogateModel``); its training labels' fidelity names its standard scale."""
    from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel

    return SurrogateModel(DEFAULT_MODEL)
