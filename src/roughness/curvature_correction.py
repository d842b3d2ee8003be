"""The curvature study's measured correction of a flat V for a curved base, with its error.

``studies/curvature.py`` measured, with the FEM, V of the standard textures (lambda 0.75, 1.0, 1.25 mm,
3 realisations each, heights along the normal) on cylinders and spheres of radius 3 to 40 mm, convex and
concave, against the same textures flat. Its tables (``studies/results/curvature_default.json`` for
cylinders, ``curvature_sphere.json`` for spheres) are condensed into ``models/curvature_correction.json``
(``python studies/curvature_correction.py`` rewrites it): per base and signed curvature 1/R (1/mm, convex
positive) the relative difference of V, mean over the textures, and its error, the largest distance of any
texture's or realisation's measured difference (min and max over realisations) from that mean.

``correction(k1, k2)`` answers for principal curvatures k1, k2 (1/mm, convex positive): both interpolated
linearly in 1/R between the measured radii (0 at 1/R = 0). A cylinder is (k, 0); a sphere (k, k); an
elliptic base (same signs) is counted as a sphere of the smaller curvature plus a cylinder of the
difference, a saddle as two cylinders, their differences and errors added (not measured: said in the note).
Curvatures beyond the measured range are refused with a reason, as are bases the skin cannot rest on.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.models import MODELS_DIR
from roughness.surrogate.patch import FOOTPRINT_MM  # the skin footprint's side (mm)

TABLE_PATH = MODELS_DIR / "curvature_correction.json"
NEARLY = 0.1  # a second principal curvature below this fraction of the first: called a cylinder (or a sphere)
STUDY_RESULTS = {"cylinder": "studies/results/curvature_default.json", "sphere": "studies/results/curvature_sphere.json"}


@dataclass(frozen=True)
class Correction:
    """V on the curved base = flat V x ``factor``, with a relative error ``error`` (of the factor)."""

    factor: float
    error: float
    note: str


@dataclass(frozen=True)
class BaseTable:
    """One base's measured differences: signed 1/R (1/mm, rising), mean relative difference, its error."""

    base: str
    curvature_per_mm: tuple[float, ...]
    difference: tuple[float, ...]
    error: tuple[float, ...]

    def at(self, k: float) -> tuple[float, float]:
        """(relative difference, error) at signed curvature ``k`` (1/mm), linear in 1/R; ValueError outside."""
        ks = np.asarray(self.curvature_per_mm)
        if not ks[0] - 1e-12 <= k <= ks[-1] + 1e-12:
            raise ValueError(k)
        return float(np.interp(k, ks, self.difference)), float(np.interp(k, ks, self.error))

    @property
    def radii_text(self) -> str:
        """The measured range in words: ``convex radius down to 3 mm, concave down to 6 mm``."""
        return (f"convex radius down to {1 / self.curvature_per_mm[-1]:g} mm, concave down to "
                f"{-1 / self.curvature_per_mm[0]:g} mm")


def table_from_study(results: dict) -> BaseTable:
    """One base's table from a ``studies/curvature.py`` results file (heights along the normal)."""
    rows: dict[float, list[dict]] = {}
    for row in results["differences"]:
        if row.get("texture_along", "normal") == "normal" and "relative_difference" in row:
            rows.setdefault(row["curvature_per_mm"], []).append(row)
    ks, means, errors = [0.0], [0.0], [0.0]
    for k, group in sorted(rows.items()):
        mean = float(np.mean([r["relative_difference"] for r in group]))
        spread = max(max(abs(r["relative_max"] - mean), abs(r["relative_min"] - mean)) for r in group)
        ks.append(k), means.append(mean), errors.append(spread)
    order = np.argsort(ks)
    return BaseTable(results["base"], tuple(float(ks[i]) for i in order), tuple(means[i] for i in order),
                     tuple(errors[i] for i in order))


@lru_cache(maxsize=4)
def load_tables(path: str | Path = TABLE_PATH) -> dict[str, BaseTable]:
    """The shipped tables, by base."""
    data = json.loads(Path(path).read_text())
    return {base: BaseTable(base, tuple(t["curvature_per_mm"]), tuple(t["difference"]), tuple(t["error"]))
            for base, t in data["bases"].items()}


def measured_ranges(path: str | Path = TABLE_PATH) -> str:
    """The radii the study measured, per base, in words."""
    return "; ".join(f"{t.base}s: {t.radii_text}" for t in load_tables(str(path)).values())


def restable(k1: float, k2: float, footprint_mm: float = FOOTPRINT_MM) -> str:
    """Why the skin's square footprint cannot rest on a base of principal curvatures k1, k2 (1/mm; empty if it
    can): a concave radius along a principal direction must exceed half the side (the edge), along the diagonal
    (normal curvature (k1 + k2) / 2) half the diagonal (the corner), as ``simulate.curved`` requires."""
    half, corner = footprint_mm / 2, footprint_mm / math.sqrt(2)
    worst = min(k1, k2)
    if worst < 0 and -1 / worst <= half:
        return (f"concave radius {-1 / worst:.3g} mm: the {footprint_mm:g} mm skin footprint cannot rest in it "
                f"(its edge lies {half:g} mm from the centre; the concave radius must exceed {half:g} mm)")
    diagonal = (k1 + k2) / 2
    if diagonal < 0 and -1 / diagonal <= corner:
        return (f"concave radius {-1 / diagonal:.3g} mm along the footprint's diagonal: the {footprint_mm:g} mm "
                f"skin footprint cannot rest in it (its corner lies {corner:.3g} mm from the centre)")
    return ""


def correction(k1: float, k2: float = 0.0, path: str | Path = TABLE_PATH) -> Correction:
    """The measured correction for a base of principal curvatures ``k1``, ``k2`` (1/mm, convex positive).

    InputError (``parameter="curvature_mm"``) where the skin cannot rest or the curvature lies beyond the
    study's measured range."""
    why = restable(k1, k2)
    if why:
        raise InputError(why, parameter="curvature_mm")
    tables = load_tables(str(path))
    small, large = sorted((k1, k2), key=abs)
    try:
        if small * large >= 0:  # a sphere of the smaller curvature plus a cylinder of the difference
            d1, e1 = tables["sphere"].at(small)
            d2, e2 = tables["cylinder"].at(large - small)
        else:  # a saddle: two cylinders
            d1, e1 = tables["cylinder"].at(k1)
            d2, e2 = tables["cylinder"].at(k2)
        diff, error = d1 + d2, e1 + e2
    except ValueError:
        raise InputError(f"principal radii {_radius(k1)} and {_radius(k2)} mm lie beyond the curvature study's "
                         f"measured range ({measured_ranges(path)}): too curved for the 10 mm footprint's model; the curved FEM "
                         "answers for cylinders and spheres (engine fem)", parameter="curvature_mm") from None
    note = (f"curved base ({_kind(k1, k2)}): flat V x {1 + diff:.3f} ± {error:.3f}, the curvature study's measured "
            "difference (studies/results/curvature*.md)")
    return Correction(1 + diff, error, note)


def for_base(radius_mm: float, base: str) -> Correction:
    """The correction for ``predict --curvature-mm``: a cylinder or sphere of signed radius (mm, convex > 0)."""
    k = 1 / radius_mm
    return correction(k, k if base == "sphere" else 0.0)


def _kind(k1: float, k2: float) -> str:
    """The base in words: flat, a cylinder, a sphere (the other radius within ``NEARLY`` said alongside), or
    principal radii and how they were counted."""
    small, large = sorted((k1, k2), key=abs)
    if large == 0:
        return "a flat base"
    if abs(small) <= NEARLY * abs(large):
        other = f" (other principal radius {_radius(small)} mm)" if small else ""
        return f"a {_side(large)} cylinder of radius {1 / abs(large):.3g} mm{other}"
    if abs(large - small) <= NEARLY * abs(large):
        other = f" (principal radii {1 / k1:.3g} and {1 / k2:.3g} mm)" if large != small else ""
        return f"a {_side(large)} sphere of radius {2 / abs(k1 + k2):.3g} mm{other}"
    how = "a sphere plus a cylinder" if small * large > 0 else "two cylinders"
    return f"principal radii {1 / k1:.3g} and {1 / k2:.3g} mm, counted as {how}: not measured"


def _side(k: float) -> str:
    return "convex" if k > 0 else "concave"


def _radius(k: float) -> str:
    return "inf" if k == 0 else f"{1 / k:.3g}"
