"""A textured mesh decimated for a slicer within a stated geometric tolerance (mm), the error measured, not trusted.

The decimator is ``fast_simplification`` (quadric edge collapse, MIT licence; its default aggressiveness, 7): it
reaches a triangle count, not an error bound, and it can fold two faces onto each other (a fin: ``without_fins``
removes them). So the count is searched and every candidate is judged by measurement:

1. halve the triangles (1/2, 1/4, ... of the full mesh, down to ``MIN_KEPT``) until a candidate fails the screen,
   then bisect (geometric mean of the counts) ``BISECTIONS`` times between the last that passed (or the full mesh)
   and the first that failed. The screen: the candidate is a closed solid by the independent check (``roughness.surface.solid``, as
   the 3MF will hold it), and its two-sided distance from the full surface (``surface_distance``), measured on a
   random ``SCREEN_SAMPLES`` of the samples each way, is within the tolerance less the file's rounding
   (``threemf.ROUNDING_MM``, 0.00009 mm, reserved so that the written file holds the tolerance; an STL's float32
   rounds less on parts under 500 mm) (a subset's maximum is a lower bound of the whole's, so a failure is certain);
2. the candidates that passed, fewest triangles first, are verified until one holds: the distance measured on every
   sample, and no two faces crossing (``intersections.self_intersections``, every pair tested);
3. if a candidate with fewer triangles passed the screen but not the verification (the screen's random subset can
   miss the few places where the error is largest: a knob's candidate screened at 0.0099 mm measured 0.0164), the
   count is bisected ``BISECTIONS`` times more between it and the one that held (or the full mesh, if none held),
   each candidate screened and then verified.

The surfaces are sampled about as densely as the full mesh's vertices (``spacing_mm``: ``SPACING_PERCENTILE`` of
its triangles' longest edges): the full mesh at its vertices, where the texture's heights are (its few larger
triangles on a grid as fine), the decimated mesh's triangles on a grid as fine. The measured maximum is what is reported and held
to the tolerance; ``SurfaceDistance.covering_mm`` says how far apart the samples are.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.surface.solid import SolidCheck, check_solid

from .intersections import self_intersections
from .surface_distance import SurfaceDistance, TriangleSurface, longest_edges, samples, surface_distance
from .threemf import ROUNDING_MM

MIN_KEPT = 1 / 1024
"""The search does not go below this fraction of the full mesh's triangles."""
BISECTIONS = 3
"""Bisection steps between the last count that passed the screen and the first that failed (each halves the gap
in log(count): the result is within a factor of 2^(1/8), 9%, of the fewest triangles that pass)."""
SPACING_PERCENTILE = 99.0
"""The samples' spacing is this percentile of the full mesh's longest edges (its textured triangles' size; not the
largest, which a few large untextured faces would set)."""
SCREEN_SAMPLES = 200_000
"""Samples each way (at most) in the screen."""


@dataclass(frozen=True)
class Attempt:
    """One candidate of the search: its triangles, the distance measured (mm; None if not measured), how much was
    measured ("screen" or "all"), and the verdict ("" if it held, else why not)."""

    triangles: int
    distance_mm: float | None
    measured: str
    failed: str

    def as_dict(self) -> dict:
        return {"triangles": self.triangles, "distance_mm": self.distance_mm, "measured": self.measured,
                "failed": self.failed}


@dataclass(frozen=True)
class Decimated:
    """The decimated mesh (``vertices`` (n, 3) mm, ``faces``), the tolerance asked (mm), the distance measured from
    the full surface (``distance``), the triangles before and after, the independent check it passed, the pairs of
    faces tested for crossings (none cross), and the search's candidates in the order tried."""

    vertices: np.ndarray
    faces: np.ndarray
    tolerance_mm: float
    distance: SurfaceDistance
    triangles_in: int
    check: SolidCheck
    crossing_pairs_tested: int
    attempts: tuple[Attempt, ...]

    @property
    def triangles(self) -> int:
        return len(self.faces)

    def line(self) -> str:
        """The result in one line."""
        d = self.distance
        return (f"decimated {self.triangles_in:,} -> {self.triangles:,} triangles ({self.triangles / self.triangles_in:.1%})"
                f" within {self.tolerance_mm:g} mm: measured distance from the full surface {d.max_mm:.4f} mm at most "
                f"(full to decimated {d.a_to_b_mm:.4f}, decimated to full {d.b_to_a_mm:.4f}; {d.samples:,} samples "
                f"at most {d.covering_mm:.3f} mm from any point; {len(self.attempts)} candidates tried); no two faces "
                f"cross ({self.crossing_pairs_tested:,} pairs tested)")

    def as_dict(self) -> dict:
        d = self.distance
        return {"tolerance_mm": self.tolerance_mm, "triangles_in": self.triangles_in, "triangles": self.triangles,
                "distance_mm": d.max_mm, "full_to_decimated_mm": d.a_to_b_mm, "decimated_to_full_mm": d.b_to_a_mm,
                "samples": d.samples, "sample_covering_mm": d.covering_mm, "worst_at_mm": list(d.where),
                "check": self.check.as_dict(), "crossing_pairs_tested": self.crossing_pairs_tested,
                "attempts": [a.as_dict() for a in self.attempts]}


def decimate(vertices: np.ndarray, faces: np.ndarray, tolerance_mm: float,
             progress: Callable[[str], object] | None = None, seed: int = 0) -> Decimated:
    """The fewest triangles the search finds (module docstring) whose surface lies within ``tolerance_mm`` (mm) of
    the full mesh (``vertices`` (n, 3) mm, ``faces``), measured; InputError (parameter ``decimate_mm``) if no
    candidate holds it. ``progress``: told each candidate's verdict."""
    tolerance_mm = positive("decimate_mm", tolerance_mm)
    if tolerance_mm <= ROUNDING_MM:
        raise InputError(f"no decimation holds {tolerance_mm:g} mm: a written 3MF rounds each vertex by up to "
                         f"{ROUNDING_MM:.5f} mm; allow a larger --decimate-mm (0.005 is well under a print's "
                         "resolution)", parameter="decimate_mm")
    vertices, faces = np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64)
    full = TriangleSurface(vertices, faces)
    spacing = float(np.percentile(longest_edges(vertices, faces), SPACING_PERCENTILE))
    search = _Search(full, spacing, tolerance_mm, np.random.default_rng(seed), progress)
    passed, failed = [], None
    count = len(faces) // 2
    while count >= max(4, len(faces) * MIN_KEPT):
        if search.screen(count):
            passed.append(count)
            count //= 2
        else:
            failed = count
            break
    if failed is not None:
        def screened(mid: int) -> bool:
            if search.screen(mid):
                passed.append(mid)
                return True
            return False

        _bisect(failed, passed[-1] if passed else len(faces), screened)
    found, failed_all = None, None
    for count in sorted(passed):
        found = search.verify(count)
        if found is not None:
            break
        failed_all = count
    held = [] if found is None else [found]
    if failed_all is not None:  # the screen let a count through that every sample refused: bisect, all measured
        def verified(mid: int) -> bool:
            better = search.verify(mid) if search.screen(mid) else None
            if better is not None:
                held.append(better)
            return better is not None

        _bisect(failed_all, len(faces) if found is None else count, verified)
    if not held:
        raise InputError(
            f"no decimation of the {len(faces):,} triangles holds the surface within {tolerance_mm:g} mm "
            f"(candidates: {'; '.join(a.failed for a in search.attempts)}): write the full mesh (no --decimate-mm) "
            "or allow a larger --decimate-mm", parameter="decimate_mm")
    return replace(held[-1], attempts=tuple(search.attempts))


def _bisect(lo: int, hi: int, holds: Callable[[int], bool]) -> None:
    """``BISECTIONS`` steps between a triangle count that fails (``lo``) and one that holds (``hi``), each at the
    geometric mean of the two, judged by ``holds``."""
    for _ in range(BISECTIONS):
        mid = int(round(math.sqrt(lo * hi)))
        if mid in (lo, hi):
            return
        if holds(mid):
            hi = mid
        else:
            lo = mid


def without_fins(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mesh without its fins: pairs of faces on the same three vertices, wound opposite ways (an edge collapse
    can fold two faces onto each other; they enclose nothing and leave their edges shared by four faces), and
    without the vertices no face uses then."""
    ordered = np.sort(faces, axis=1)
    _, inverse, counts = np.unique(ordered, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    twice = np.flatnonzero(counts[inverse] == 2)
    if not len(twice):
        return vertices, faces
    first = ordered[twice, 0]
    turns = np.argmax(faces[twice] == first[:, None], axis=1)  # each face rotated to start at its lowest vertex
    rotated = faces[twice][np.arange(len(twice))[:, None], (turns[:, None] + np.arange(3)) % 3]
    order = np.lexsort((twice, inverse[twice]))
    a, b = order[0::2], order[1::2]
    opposite = (rotated[a, 1] == rotated[b, 2]) & (rotated[a, 2] == rotated[b, 1])
    drop = np.zeros(len(faces), dtype=bool)
    drop[twice[a[opposite]]] = drop[twice[b[opposite]]] = True
    kept = faces[~drop]
    used = np.zeros(len(vertices), dtype=bool)
    used[kept.ravel()] = True
    index = np.cumsum(used) - 1
    return vertices[used], index[kept]


class _Search:
    """Candidates of the search: simplified, screened and verified against the ``full`` surface (module docstring)."""

    def __init__(self, full: TriangleSurface, spacing_mm: float, tolerance_mm: float, rng: np.random.Generator,
                 progress: Callable[[str], object] | None) -> None:
        self.full, self.spacing_mm, self.tolerance_mm, self.rng = full, spacing_mm, tolerance_mm, rng
        self.held_mm = tolerance_mm - ROUNDING_MM  # what the measured distance must stay within
        self.progress = progress
        self.attempts: list[Attempt] = []

    def _tell(self, attempt: Attempt) -> None:
        self.attempts.append(attempt)
        if self.progress is not None:
            verdict = attempt.failed or "holds"
            measured = "" if attempt.distance_mm is None else f", {attempt.distance_mm:.4f} mm ({attempt.measured})"
            self.progress(f"  decimate: {attempt.triangles:,} triangles{measured}: {verdict}")

    def _beyond(self, distance_mm: float) -> str:
        return f"{distance_mm:.4f} mm > {self.tolerance_mm:g} mm less the file's rounding ({self.held_mm:.5f} mm)"

    def _simplified(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        import fast_simplification

        v, f = fast_simplification.simplify(self.full.vertices, self.full.faces, target_count=count)
        return without_fins(np.asarray(v, dtype=float), np.asarray(f, dtype=np.int64))

    def screen(self, count: int) -> bool:
        """Whether the candidate of ``count`` triangles is closed and within the tolerance on a subset of samples."""
        v, f = self._simplified(count)
        check = check_solid(v, f, np.float64)
        if not check.closed:
            self._tell(Attempt(len(f), None, "", "not a closed solid: " + "; ".join(check.defects())))
            return False
        part = TriangleSurface(v, f)
        worst = 0.0
        for source, target in ((self.full, part), (part, self.full)):
            points, _ = samples(source.vertices, source.faces, self.spacing_mm)
            if len(points) > SCREEN_SAMPLES:
                points = points[self.rng.choice(len(points), SCREEN_SAMPLES, replace=False)]
            worst = max(worst, float(target.distances(points).max()))
        ok = worst <= self.held_mm
        self._tell(Attempt(len(f), worst, "screen", "" if ok else self._beyond(worst)))
        return ok

    def verify(self, count: int) -> Decimated | None:
        """The candidate of ``count`` triangles if every sample lies within the tolerance and no faces cross."""
        v, f = self._simplified(count)
        part = TriangleSurface(v, f)
        distance = surface_distance(self.full, part, self.spacing_mm)
        if distance.max_mm > self.held_mm:
            self._tell(Attempt(len(f), distance.max_mm, "all", self._beyond(distance.max_mm)))
            return None
        crossing = self_intersections(v, f)
        if crossing.count:
            self._tell(Attempt(len(f), distance.max_mm, "all", f"{crossing.count:,} pairs of faces cross"))
            return None
        self._tell(Attempt(len(f), distance.max_mm, "all", ""))
        return Decimated(v, f, self.tolerance_mm, distance, len(self.full.faces), check_solid(v, f, np.float64),
                         crossing.tested, tuple(self.attempts))
