"""How well V predicts the perceptual embedding (the paper's Figs. 17 and 18).

Pearson R and Spearman rho of V against the 1-D coordinate, for all stimuli and without the excluded
ones (the paper: R = 0.91, 0.965 without its five least homogeneous textures); the classical
measures (Ra, P90, GLCM) beside it; and the re-fit over the pair sampling (d, r), computing V again
from the stored fluctuation fields with the FEM's own pair sampling, and over force (new FEM runs,
cached).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import pearsonr, spearmanr

from roughness.core.errors import InputError
from roughness.simulate.variation import PairSampling, variation

from .values import StimulusValue


@dataclass(frozen=True)
class Correlation:
    pearson: float
    spearman: float
    n: int

    def as_dict(self) -> dict:
        return {"pearson": _finite(self.pearson), "spearman": _finite(self.spearman), "n": self.n}


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def r_text(x: float | None) -> str:
    """A correlation as shown in text and plot titles: three decimals, or "undefined" (None or NaN: a constant
    variable, or fewer than three stimuli)."""
    return "undefined" if x is None or not math.isfinite(x) else f"{x:.3f}"


def correlate(x: np.ndarray, y: np.ndarray) -> Correlation:
    """Pearson and Spearman of two equal-length arrays (NaN when either is constant or n < 3)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if len(x) < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return Correlation(float("nan"), float("nan"), len(x))
    return Correlation(float(pearsonr(x, y)[0]), float(spearmanr(x, y)[0]), len(x))


@dataclass
class SamplingFit:
    """R of V(d, r) against the embedding over a grid of pair distances d and disk radii r (mm)."""

    distances_mm: np.ndarray
    radii_mm: np.ndarray
    pearson: np.ndarray  # (len(distances), len(radii)); NaN where the disks do not fit the window
    spearman: np.ndarray

    def as_dict(self) -> dict:
        best = np.unravel_index(np.nanargmax(self.pearson), self.pearson.shape) if np.any(
            np.isfinite(self.pearson)) else None
        return {"distances_mm": self.distances_mm.tolist(), "radii_mm": self.radii_mm.tolist(),
                "pearson": [[_finite(v) for v in row] for row in self.pearson],
                "spearman": [[_finite(v) for v in row] for row in self.spearman],
                "best": None if best is None else {"distance_mm": float(self.distances_mm[best[0]]),
                                                   "radius_mm": float(self.radii_mm[best[1]]),
                                                   "pearson": float(self.pearson[best])},
                "share_above_0.85": float(np.mean(self.pearson[np.isfinite(self.pearson)] > 0.85))
                if np.any(np.isfinite(self.pearson)) else None}


def sampling_fit(values: Sequence[StimulusValue], coordinate: np.ndarray, distances_mm: Sequence[float],
                 radii_mm: Sequence[float], window_mm: float, pairs: int, seed: int) -> SamplingFit:
    """Recompute V of every stimulus from its fluctuation field for each (d, r) and correlate."""
    if any(v.fluctuation is None for v in values):
        raise InputError("the re-fit over (d, r) needs fluctuation fields: use a FEM engine", parameter="engine")
    d_grid, r_grid = np.asarray(distances_mm, dtype=float), np.asarray(radii_mm, dtype=float)
    pearson = np.full((len(d_grid), len(r_grid)), np.nan)
    spearman = np.full_like(pearson, np.nan)
    for i, d in enumerate(d_grid):
        for j, r in enumerate(r_grid):
            if window_mm / 2 - d / 2 - r <= 0:
                continue  # the disk pair does not fit in the sampling window
            sampling = PairSampling(window_mm, float(d), float(r), pairs, seed)
            v = [variation(s.fluctuation, s.grid_axis_mm, sampling)[0] for s in values]
            c = correlate(v, coordinate)
            pearson[i, j], spearman[i, j] = c.pearson, c.spearman
    return SamplingFit(d_grid, r_grid, pearson, spearman)


@dataclass
class Fit:
    """V against the embedding for one set of stimuli."""

    stimuli: tuple[str, ...]
    coordinate: np.ndarray
    low: np.ndarray
    high: np.ndarray
    values: list[StimulusValue]
    included: np.ndarray  # bool: not excluded
    measures: dict[str, np.ndarray] = field(default_factory=dict)  # classical measures per stimulus
    sampling: SamplingFit | None = None
    forces: dict[float, np.ndarray] = field(default_factory=dict)  # force (N) -> V per stimulus

    @property
    def roughness(self) -> np.ndarray:
        return np.array([v.roughness for v in self.values])

    def correlations(self) -> dict:
        keep = self.included
        out = {"V": {"all": correlate(self.roughness, self.coordinate).as_dict(),
                     "included": correlate(self.roughness[keep], self.coordinate[keep]).as_dict()}}
        for name, m in self.measures.items():
            out[name] = {"all": correlate(m, self.coordinate).as_dict(),
                         "included": correlate(m[keep], self.coordinate[keep]).as_dict()}
        return out

    def force_correlations(self) -> dict:
        keep = self.included
        return {f"{force:g}": correlate(v[keep], self.coordinate[keep]).as_dict()
                for force, v in sorted(self.forces.items())}


def homogeneity_spreads(stimuli: Sequence, heightmaps: Sequence, engine: str = "surrogate") -> np.ndarray:
    """Spread in JNDs of every stimulus (larger = less homogeneous): the stimuli table's
    ``homogeneity`` column where given, else ``roughness.design.homogeneity`` (V over windows of the
    map with ``engine``)."""
    missing = [i for i, s in enumerate(stimuli) if s.homogeneity is None]
    spreads = np.array([np.nan if s.homogeneity is None else s.homogeneity for s in stimuli], dtype=float)
    if missing:
        from roughness.design.homogeneity import homogeneity  # lazy: the design tools load the engines
        for i in missing:
            spreads[i] = float(homogeneity(heightmaps[i], engine=engine).spread_jnd)
    return spreads


def least_homogeneous(ids: Sequence[str], spreads: np.ndarray, count: int) -> list[str]:
    """The ``count`` ids with the largest spread (ties: table order)."""
    return [ids[i] for i in np.argsort(-np.asarray(spreads, dtype=float), kind="stable")[:count]]


def classical_measures(heightmaps: Sequence) -> dict[str, np.ndarray]:
    """The classical roughness measures of roughness.classical on every stimulus's footprint."""
    from roughness.classical import MEASURES, footprint

    patches = [footprint(hm) for hm in heightmaps]
    return {name: np.array([f(p) for p in patches]) for name, f in MEASURES.items()}
