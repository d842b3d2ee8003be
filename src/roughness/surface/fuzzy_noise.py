"""The noise of OrcaSlicer's fuzzy skin: Classic (uniform), Perlin, Billow, Ridged multifractal and Voronoi.

OrcaSlicer (src/libslic3r/Feature/FuzzySkin/FuzzySkin.cpp, ``get_noise_module``; SoftFever/OrcaSlicer commit
0051ba1662e1) displaces each fuzzy point by ``noise(x, y, slice_z) * fuzzy_skin_thickness``, with libnoise's
modules at frequency ``1 / fuzzy_skin_scale``: Perlin and Billow with ``fuzzy_skin_octaves`` and
``fuzzy_skin_persistence``, RidgedMulti with the octaves only, Voronoi with displacement 1 and no distance term;
Classic is a fresh uniform number in [-1, 1] per point. The fractal sums below follow libnoise 1.0's modules
(lacunarity 2; Billow: 2|n| - 1 per octave, + 0.5 at the end; RidgedMulti: offset 1, gain 2, octave weights
2^-k, result x 1.25 - 1; Voronoi: the value of the cell holding the nearest of the jittered seed points). The
gradient lattice is our own (Ken Perlin's improved noise, 12 edge gradients, a permutation drawn from ``seed``),
not libnoise's table: the same settings give statistically alike walls, not the slicer's exact numbers.
Only Classic is random in the slicers (a new wall at every slice); their coherent noises use a fixed seed.
"""
from __future__ import annotations

import numpy as np

NOISE_TYPES = ("classic", "perlin", "billow", "ridgedmulti", "voronoi")  # OrcaSlicer's fuzzy_skin_noise_type
LACUNARITY = 2.0  # libnoise's default frequency ratio of successive octaves
_EDGES = np.array([[1, 1, 0], [-1, 1, 0], [1, -1, 0], [-1, -1, 0], [1, 0, 1], [-1, 0, 1], [1, 0, -1], [-1, 0, -1],
                   [0, 1, 1], [0, -1, 1], [0, 1, -1], [0, -1, -1]], dtype=float)


class Lattice:
    """A seeded integer lattice: a hash of cells, unit-cube gradient noise and uniform cell values in [-1, 1]."""

    def __init__(self, seed: int) -> None:
        rng = np.random.default_rng(seed)
        self.perm = np.tile(rng.permutation(256), 2)
        self.values = rng.uniform(-1.0, 1.0, 256)

    def hash(self, i: np.ndarray, j: np.ndarray, k: np.ndarray) -> np.ndarray:
        p = self.perm
        return p[p[p[i & 255] + (j & 255)] + (k & 255)]

    def gradient(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Improved Perlin noise at points (lattice units): about [-1, 1], 0 on every lattice point."""
        cells = [np.floor(c).astype(np.int64) for c in (x, y, z)]
        frac = [c - f for c, f in zip((x, y, z), cells)]
        fade = [f * f * f * (f * (6 * f - 15) + 10) for f in frac]
        out = np.zeros(np.shape(x))
        for corner in range(8):
            d = [(corner >> axis) & 1 for axis in range(3)]
            g = _EDGES[self.hash(*(c + o for c, o in zip(cells, d))) % 12]
            dot = sum(g[..., a] * (frac[a] - d[a]) for a in range(3))
            weight = np.prod([fade[a] if d[a] else 1 - fade[a] for a in range(3)], axis=0)
            out += weight * dot
        return out

    def cell_value(self, i: np.ndarray, j: np.ndarray, k: np.ndarray) -> np.ndarray:
        return self.values[self.hash(i, j, k)]


def noise(kind: str, x: np.ndarray, y: np.ndarray, z: np.ndarray, scale_mm: float, octaves: int,
          persistence: float, seed: int, rng: np.random.Generator) -> np.ndarray:
    """The noise ``kind`` (NOISE_TYPES) at points (mm), before the thickness: Classic draws from ``rng``, the
    coherent noises are functions of position (at frequency 1 / ``scale_mm``) and ``seed``."""
    if kind == "classic":
        return rng.uniform(-1.0, 1.0, np.shape(x))
    x, y, z = (np.asarray(c, dtype=float) / scale_mm for c in (x, y, z))
    if kind == "voronoi":
        return _voronoi(Lattice(seed), x, y, z)
    total = np.zeros(x.shape)
    weight = np.ones(x.shape)
    for octave in range(octaves):
        f = LACUNARITY ** octave
        signal = Lattice(seed + octave).gradient(f * x, f * y, f * z)
        if kind == "perlin":
            total += signal * persistence ** octave
        elif kind == "billow":
            total += (2 * np.abs(signal) - 1) * persistence ** octave
        else:  # ridgedmulti
            signal = (1 - np.abs(signal)) ** 2 * weight
            weight = np.clip(2.0 * signal, 0.0, 1.0)
            total += signal * f ** -1.0
    if kind == "billow":
        return total + 0.5
    return total * 1.25 - 1.0 if kind == "ridgedmulti" else total


def _voronoi(lattice: Lattice, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The value (uniform in [-1, 1]) of the cell holding each point's nearest seed point; a cell's seed point
    lies within one cell of its corner, so the 5 x 5 x 5 cells around a point hold its nearest."""
    base = [np.floor(c).astype(np.int64) for c in (x, y, z)]
    best = np.full(x.shape, np.inf)
    nearest = [np.zeros(x.shape) for _ in range(3)]
    offsets = range(-2, 3)
    for di in offsets:
        for dj in offsets:
            for dk in offsets:
                cell = (base[0] + di, base[1] + dj, base[2] + dk)
                seed_point = [cell[a] + lattice.cell_value(cell[0] + 101 * a, cell[1], cell[2]) for a in range(3)]
                dist = sum((s - c) ** 2 for s, c in zip(seed_point, (x, y, z)))
                closer = dist < best
                best = np.where(closer, dist, best)
                for a in range(3):
                    nearest[a] = np.where(closer, seed_point[a], nearest[a])
    return lattice.cell_value(*(np.floor(n).astype(np.int64) for n in nearest))
