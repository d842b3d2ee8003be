"""The spectral skin engine: the FEM's roughness model with the skin as an infinite elastic layer.

A texture's footprint (``width_mm`` square, at the heightmap's own pixel size) is mirror-extended
across its edges (the ``mirror`` basis of ``modes``: no jump at the seams), the layer is pressed onto it at the flat state's pressure
(``flat_state``: by default the FEM block's at its centre), contact is solved on the pixel grid
(``contact``), and the strain at the receptor depth follows per Fourier mode (``modes``). The
texture's strain is added to the flat state's strain (the untextured skin's), lambda3 is taken, the
flat lambda3 subtracted, and V sampled as in the FEM (``simulate.variation``). No mesh: the only
discretization is the pixel.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from roughness.core.errors import InputError
from roughness.core.hashing import digest
from roughness.core.reprs import short_repr, v_text
from roughness.surface.heightmap import Heightmap

from ..config import DEEP_INDENTATION_TISSUES, MAX_INDENTATION_TISSUES, SimConfig
from ..variation import PairSampling, variation
from .contact import ContactState, solve_contact
from .flat_state import FlatState, block_flat_state
from .layer import Tissue
from .modes import GridKey, modes

ENGINE_VERSION = 2  # bump when a change alters results (keys cached spectral results)
FLAT_STATES = ("layer", "block")
PRESSURES = ("flat", "mean")
MIN_FOOTPRINT_PIXELS = 10  # the footprint must span at least this many pixels across
MAX_FOOTPRINT_PIXELS = 1024  # and at most this many


def identity(config: SimConfig) -> str:
    """What spectral results with ``config`` depend on, as the result cache and provenance records name it:
    ``spectral-`` and a digest of the configuration with the engine's version."""
    return "spectral-" + digest({**config.as_dict(), "engine_version": ENGINE_VERSION})


@dataclass(frozen=True)
class SpectralResult:
    """Roughness of one texture from the spectral engine (mm, MPa, s).

    ``fluctuation``/``lambda3``: fields on ``grid_axis_mm`` (pixel grid, centred on the footprint)
    over the sampling window; ``converged``: the contact conditions hold (``message`` otherwise).
    """

    roughness: float
    roughness_stderr: float
    contact_fraction: float
    indentation_mm: float
    converged: bool
    message: str
    iterations: int
    seconds: float
    fluctuation: np.ndarray = field(repr=False)
    lambda3: np.ndarray = field(repr=False)
    grid_axis_mm: np.ndarray = field(repr=False)
    flat_state: FlatState = field(repr=False)
    contact: ContactState = field(repr=False)
    notes: list[str] = field(default_factory=list)
    # what a dataset stores of every result (dataset.schema.RESULT_ATTRS): no mesh, so no discretization
    # error estimate, no nodes left unresolved by a converged solve and no ladder of levels
    discretization_error: float | None = None
    ladder: list = field(default_factory=list)

    def __repr__(self) -> str:
        return short_repr(self, v_text(self.roughness, self.roughness_stderr), "spectral",
                          "converged" if self.converged else f"NOT converged ({self.message})",
                          f"contact {self.contact_fraction:.2f}", f"indentation {self.indentation_mm:.3g} mm",
                          f"{self.seconds:.3f} s", f"{len(self.notes)} note(s)" if self.notes else "")

    @property
    def unresolved_nodes(self) -> int:
        return 0 if self.converged else -1

    @property
    def cycled(self) -> bool:
        return "cycled" in self.message

    @property
    def contact_history(self) -> list[int]:
        return [int(self.contact.in_contact.sum())]


def tissue_of(config: SimConfig) -> Tissue:
    return Tissue(config.tissue_mm, config.young_mpa, config.poisson)


def layer_flat_state(config: SimConfig) -> FlatState:
    """The untextured infinite layer: uniaxial compression (3, 3) under the footprint's mean pressure (MPa)."""
    pressure = config.force_n / config.width_mm**2
    strain = np.zeros((3, 3))
    strain[2, 2] = -pressure / tissue_of(config).oedometric_mpa
    return FlatState(strain, pressure)


def footprint_heights(heightmap: Heightmap, width_mm: float, centre_mm: tuple[float, float],
                      tile: bool) -> tuple[np.ndarray, np.ndarray]:
    """Heights (n, n) at the pixel grid of the footprint centred at ``centre_mm`` and its axis (mm, from the centre)."""
    n = round(width_mm / heightmap.pixel_mm)
    if n < MIN_FOOTPRINT_PIXELS:
        raise InputError(f"the {width_mm:g} mm footprint spans only {n} pixels of {heightmap.pixel_mm:g} mm "
                         f"(at least {MIN_FOOTPRINT_PIXELS} needed): is the pixel size in mm?", parameter="pixel_mm")
    if n > MAX_FOOTPRINT_PIXELS:
        raise InputError(f"the {width_mm:g} mm footprint spans {n} pixels of {heightmap.pixel_mm:g} mm; the spectral "
                         f"engine solves at most {MAX_FOOTPRINT_PIXELS} across (pixels of "
                         f"{width_mm / MAX_FOOTPRINT_PIXELS:.3g} mm or more): resample the heightmap",
                         parameter="pixel_mm")
    axis = (np.arange(n) - (n - 1) / 2) * heightmap.pixel_mm
    cx, cy = centre_mm
    return heightmap.sample(cx + axis[None, :], cy + axis[:, None], periodic=tile), axis


def min_eigenvalue(xx: np.ndarray, yy: np.ndarray, zz: np.ndarray, xy: np.ndarray, xz: np.ndarray,
                   yz: np.ndarray) -> np.ndarray:
    """The smallest eigenvalue of symmetric 3 x 3 tensors given by their components (closed form,
    trigonometric: exact where the two larger eigenvalues coincide, as in the flat state)."""
    q = (xx + yy + zz) / 3
    off = xy**2 + xz**2 + yz**2
    p = np.sqrt(((xx - q) ** 2 + (yy - q) ** 2 + (zz - q) ** 2 + 2 * off) / 6)
    safe = np.where(p > 0, p, 1.0)
    bxx, byy, bzz = (xx - q) / safe, (yy - q) / safe, (zz - q) / safe
    bxy, bxz, byz = xy / safe, xz / safe, yz / safe
    det = bxx * (byy * bzz - byz**2) - bxy * (bxy * bzz - byz * bxz) + bxz * (bxy * byz - byy * bxz)
    phi = np.arccos(np.clip(det / 2, -1.0, 1.0)) / 3
    return np.where(p > 0, q + 2 * p * np.cos(phi + 2 * np.pi / 3), q)


def lambda3(strain: np.ndarray, flat: np.ndarray) -> np.ndarray:
    """lambda3 (the most negative principal strain) of the fields ``strain`` (6, ...) plus the flat state (3, 3)."""
    order = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
    return min_eigenvalue(*(strain[i] + flat[j] for i, j in enumerate(order)))


def fluctuation(lam3: np.ndarray, flat: np.ndarray) -> np.ndarray:
    """lambda3 less the flat state's (3, 3) own lambda3, by the same closed form (a flat texture: exactly 0)."""
    return lam3 - lambda3(np.zeros((6, 1, 1)), flat)


class SpectralSimulator:
    """Roughness V by the spectral engine for a ``SimConfig`` (its mesh fields are not used).

    ``flat_state``: what the layer stands for (``flat_state`` module): ``block``, the FEM block's centre
    (its strain and contact pressure; the default) or ``layer``, the infinite layer itself (uniaxial
    strain under the footprint's mean pressure). ``pressure``: ``flat`` (the flat state's) or ``mean``
    (force / footprint area, whatever the flat state), for studies.
    """

    def __init__(self, config: SimConfig | None = None, flat_state: str = "block", pressure: str = "flat") -> None:
        if flat_state not in FLAT_STATES:
            raise InputError(f"flat_state must be one of {', '.join(FLAT_STATES)}, got {flat_state!r}",
                             parameter="flat_state")
        if pressure not in PRESSURES:
            raise InputError(f"pressure must be one of {', '.join(PRESSURES)}, got {pressure!r}", parameter="pressure")
        self.config = config or SimConfig()
        self.flat_state, self.pressure = flat_state, pressure

    def flat(self, config: SimConfig) -> FlatState:
        """The flat state: the strain the texture's is added to, and the mean pressure on the layer."""
        state = layer_flat_state(config) if self.flat_state == "layer" else block_flat_state(config)
        if self.pressure == "mean":
            return FlatState(state.strain, config.force_n / config.width_mm**2)
        return state

    def run(self, heightmap: Heightmap, centre_mm: tuple[float, float] | None = None, tile: bool = False,
            **overrides) -> SpectralResult:
        """V of ``heightmap`` under the footprint centred at ``centre_mm`` (default: the map's centre)."""
        start = time.perf_counter()
        config = replace(self.config, **overrides)
        if config.curvature_mm is not None:
            raise InputError("the spectral engine models a flat skin layer; curved bases need the FEM "
                             "(engine fem)", parameter="curvature_mm")
        centre = centre_mm or heightmap.centre_mm
        heightmap.require_footprint(config.width_mm, centre, tile)
        heights, axis = footprint_heights(heightmap, config.width_mm, centre, tile)
        grid = modes(GridKey(heights.shape, heightmap.pixel_mm, tissue_of(config), config.depth_mm, "mirror"))
        flat = self.flat(config)
        state = solve_contact(grid, heights, flat.pressure_mpa, config.contact == "frictionless")
        inside = np.abs(axis) <= config.window_mm / 2 + heightmap.pixel_mm
        strain = grid.strain(state.face)[:, inside][:, :, inside]
        lam3 = lambda3(strain, flat.strain)
        fluct = fluctuation(lam3, flat.strain)
        window_axis = axis[inside]
        pairs = PairSampling(config.window_mm, config.pair_distance_mm, config.disk_radius_mm, config.pairs,
                             config.seed)
        v, se = variation(fluct, window_axis, pairs)
        if not (math.isfinite(v) and np.all(np.isfinite(fluct))):
            raise InputError("the strain field is not finite", parameter="heightmap")
        contact_fraction = float(state.in_contact.mean())
        indentation = float(heights.max() + state.offset_mm)
        notes = _notes(config, indentation, state.success, state.message)
        return SpectralResult(v, se, contact_fraction, indentation, state.success, state.message, state.iterations,
                              time.perf_counter() - start, fluct, lam3, window_axis, flat, state, notes)


def _notes(config: SimConfig, indentation_mm: float, converged: bool, message: str) -> list[str]:
    """Remarks on the answer; InputError where linear elasticity cannot answer (as in the FEM)."""
    ratio = indentation_mm / config.tissue_mm
    if ratio > MAX_INDENTATION_TISSUES:
        raise InputError(
            f"the skin would be pushed {indentation_mm:.4g} mm into the texture, {ratio:.3g} times its "
            f"{config.tissue_mm:g} mm thickness (limit {MAX_INDENTATION_TISSUES:g}): linear elasticity cannot answer "
            "this; the features are taller than the skin can wrap, the force too large, or the heights not in mm",
            parameter="force_n")
    notes = []
    if ratio > 1:
        notes.append(f"indentation {indentation_mm:.2f} mm exceeds the {config.tissue_mm:g} mm tissue: linear "
                     "small-strain elasticity past its range (as in the paper's model)"
                     + (" (unusually deep)" if ratio > DEEP_INDENTATION_TISSUES else ""))
    if not converged:
        notes.append(message)
    return notes
