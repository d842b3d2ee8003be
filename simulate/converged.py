"""Error-estimated FEM answers: every result beside a coarser one, and the ``converged`` ladder.

``estimated`` runs the requested level after the next coarser rung of the ladder
(``discretization.coarser_spacing``) and attaches the Richardson estimate of V's relative
discretization error. ``refine`` (fidelity ``converged``) climbs the ladder
``discretization.LADDER_MM`` from the coarsest rung until the estimate meets the tolerance,
or the finest rung is reached (a ``tolerance_not_met`` note). Each level starts its contact
loop from the coarser level's contact set, widened and mapped to its own contact face.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Protocol

import numpy as np
from scipy.spatial import cKDTree

from roughness.surface.heightmap import Heightmap

from .discretization import LADDER_MM, V_FLOOR, coarser_spacing, richardson, within
from .result import Level, Note, Result

if TYPE_CHECKING:
    from .config import SimConfig
    from .contact import ContactRound

# contact-face coordinates (n, 2) in mm -> starting contact set (n,) bool
InitialSet = Callable[[np.ndarray], np.ndarray]
# A finer level starts from the coarser contact set widened by one coarse cell (a superset):
# carried node by node (nearest node) it cost one more contact round and twice the CG
# iterations on three panel textures, since the loop adds nodes more slowly than it releases them.
CARRY_NEIGHBOURS = 4


class LevelSolver(Protocol):
    """What the ladder asks of a simulator (``model.Simulator``): its settings, one level's ``solve`` and the
    contact-face node coordinates (mm) of a resolved configuration's block."""

    config: SimConfig

    def solve(self, heightmap: Heightmap, centre_mm: tuple[float, float] | None = None, tile: bool = False,
              callback: Callable[[ContactRound], None] | None = None, initial: InitialSet | None = None,
              **overrides) -> Result: ...

    def face_xy(self, config: SimConfig) -> np.ndarray: ...


def contact_set_map(sim: LevelSolver, result: Result, neighbours: int = CARRY_NEIGHBOURS) -> InitialSet:
    """The contact set of ``result`` carried to another contact face: a point starts in contact
    when any of its ``neighbours`` nearest nodes of ``result``'s face was in contact."""
    in_contact = result.state.in_contact.copy()
    tree = cKDTree(sim.face_xy(result.config))
    return lambda points: in_contact[tree.query(points, k=neighbours)[1]].any(axis=1)


def _level(result: Result) -> Level:
    return Level(result.config.h_contact_mm, result.config.element, result.roughness,
                 result.discretization_error, result.iterations, result.seconds)


def _finish(levels: list[Result], start: float, notes: tuple[Note, ...] = ()) -> Result:
    """The last level's result with the ladder of ``levels``, their seconds since ``start`` and ``notes`` added."""
    result = levels[-1]
    return replace(result, ladder=[_level(r) for r in levels], notes=[*result.notes, *notes],
                   stage_seconds={**result.stage_seconds, "coarser_levels": sum(r.seconds for r in levels[:-1])},
                   seconds=time.perf_counter() - start)


def _estimate(result: Result, coarse: Result) -> Result:
    """``result`` with the Richardson estimate of its V's relative error from the ``coarse`` level's."""
    return replace(result, discretization_error=richardson(result.roughness, coarse.roughness,
                                                           result.config.h_contact_mm, coarse.config.h_contact_mm))


def estimated(sim: LevelSolver, heightmap: Heightmap, centre_mm: tuple[float, float] | None, tile: bool,
              callback: Callable[[ContactRound], None] | None = None, **overrides) -> Result:
    """The requested level with its discretization-error estimate (``converged``: ``refine``)."""
    config = replace(sim.config, **overrides)
    if config.fidelity == "converged":
        return refine(sim, heightmap, centre_mm, tile, callback, **overrides)
    start = time.perf_counter()
    h = config.spacing_mm(heightmap)
    coarse = sim.solve(heightmap, centre_mm, tile, **{**overrides, "h_contact_mm": coarser_spacing(h)})
    result = sim.solve(heightmap, centre_mm, tile, callback, initial=contact_set_map(sim, coarse),
                       **{**overrides, "h_contact_mm": h})
    return _finish([coarse, _estimate(result, coarse)], start)


def refine(sim: LevelSolver, heightmap: Heightmap, centre_mm: tuple[float, float] | None, tile: bool,
           callback: Callable[[ContactRound], None] | None = None, **overrides) -> Result:
    """Climb the ladder until V's estimated relative error is below the configured tolerance."""
    start = time.perf_counter()
    tolerance = replace(sim.config, **overrides).tolerance
    levels: list[Result] = []
    for h in LADDER_MM:
        initial = contact_set_map(sim, levels[-1]) if levels else None
        result = sim.solve(heightmap, centre_mm, tile, callback, initial=initial, **{**overrides, "h_contact_mm": h})
        result = _estimate(result, levels[-1]) if levels else result
        levels.append(result)
        if result.discretization_error is not None and within(result.roughness, result.discretization_error,
                                                               tolerance):
            return _finish(levels, start)
    return _finish(levels, start, (Note(
        "tolerance_not_met", f"estimated discretization error {100 * result.discretization_error:.1f}% of V "
        f"exceeds the tolerance ({100 * tolerance:g}% of max(V, {V_FLOOR:g})) at the finest level (h = {h} mm)",
        unusual=True),))
