"""Reach a target feel with the change that looks least different: height and lateral scale mixed.

Scaling a bump texture's heights down makes it smoother and brighter (shorter flanks, less shadow); scaling it
laterally down (denser bumps) makes it smoother and darker (more flank per area). Between the two lies a mix
that reaches the same feel with far less change of look. The search: the pure lateral scale (``tune`` by
lateral), and for each lateral factor of ``LATERAL_FACTORS`` the height factor that reaches the target from there
(``tune`` by height), and once more halfway between the best of these and its neighbours; each result's look is
compared with the input's (``look.look_difference``) and the reached candidate that looks least different is kept.
Every candidate is reported, reached or not.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from roughness.core.errors import InputError
from roughness.core.reprs import short_repr
from roughness.surface.heightmap import Heightmap

from .evaluation import Evaluator
from .look import LookDifference, look_difference
from .tune import MAX_FEM, TOLERANCE_JND, Target, TuneResult, scaled, tune

LATERAL_FACTORS = (0.6, 0.7, 0.8, 0.85, 0.9, 1.0, 1.1, 1.25, 1.4)  # 1.0: height alone


@dataclass(frozen=True)
class LookCandidate:
    """One way to the target: lateral factor (None: lateral alone, not reached) then height factor (None: lateral
    alone, or not reached)."""

    lateral: float | None
    height: float | None
    result: TuneResult | None
    look: LookDifference | None
    note: str = ""

    @property
    def reached(self) -> bool:
        return self.result is not None and self.result.reached

    def as_dict(self) -> dict:
        r = self.result
        return {"lateral_factor": self.lateral, "height_factor": self.height, "reached": self.reached,
                "achieved_roughness": None if r is None else r.achieved.roughness,
                "achieved_roughness_stderr": None if r is None else r.achieved.roughness_stderr,
                "jnd_error": None if r is None else r.jnd_error,
                "look": None if self.look is None else self.look.as_dict(), "note": self.note}


@dataclass(frozen=True)
class KeptLook:
    """The candidates and the one kept (the reached candidate whose look differs least from the input's)."""

    candidates: tuple[LookCandidate, ...]
    best: int

    def __repr__(self) -> str:
        c = self.chosen
        return short_repr(self, f"lateral x {c.lateral:.3g}, height x {c.height or 1:.4g}",
                          f"look {c.look.difference:.2f} look JND", f"{len(self.candidates)} candidates")

    @property
    def chosen(self) -> LookCandidate:
        return self.candidates[self.best]

    @property
    def heightmap(self) -> Heightmap:
        return self.chosen.result.heightmap

    def summary(self) -> dict:
        return {"lateral_factor": self.chosen.lateral, "height_factor": self.chosen.height,
                "look_jnd": self.chosen.look.difference, "tune": self.chosen.result.summary(),
                "candidates": [c.as_dict() for c in self.candidates]}


def keep_look(heightmap: Heightmap, target: Target, evaluator: Evaluator | None = None, tile: bool = False,
              laterals: tuple[float, ...] = LATERAL_FACTORS, tolerance_jnd: float = TOLERANCE_JND,
              max_fem: int = MAX_FEM, progress: Callable[[str], None] | None = None) -> KeptLook:
    """The candidates of the module docstring for ``heightmap`` (mm) and ``target`` (each ``tune`` run with
    ``tolerance_jnd`` and ``max_fem``); InputError if none reaches it."""
    evaluator = evaluator or Evaluator()
    say = progress or (lambda _: None)
    settings = _Settings(evaluator, tile, tolerance_jnd, max_fem, say)
    candidates = [_candidate(heightmap, target, settings, lateral) for lateral in (None, *laterals)]
    grid = sorted(c.lateral for c in candidates[1:] if c.reached)
    if grid:  # one refinement: halfway to the grid's neighbours of the best
        best = min((c for c in candidates[1:] if c.reached), key=lambda c: c.look.difference).lateral
        at = grid.index(best)
        for other in grid[max(at - 1, 0):at] + grid[at + 1:at + 2]:
            candidates.append(_candidate(heightmap, target, settings, (best + other) / 2))
    reached = [i for i, c in enumerate(candidates) if c.reached]
    if not reached:
        raise InputError("no mix of lateral and height scale reaches the target: "
                         + "; ".join(f"lateral {'alone' if c.lateral is None else f'x {c.lateral:g}'}: "
                                     f"{c.note or 'not reached'}" for c in candidates), parameter=target.parameter)
    return KeptLook(tuple(candidates), min(reached, key=lambda i: candidates[i].look.difference))


@dataclass(frozen=True)
class _Settings:
    """How every candidate is tuned."""

    evaluator: Evaluator
    tile: bool
    tolerance_jnd: float
    max_fem: int
    say: Callable[[str], None]


def _candidate(heightmap: Heightmap, target: Target, settings: _Settings, lateral: float | None) -> LookCandidate:
    """Lateral scale alone (``lateral`` None), or lateral x ``lateral`` then height, tuned to ``target``."""
    s = settings
    try:
        if lateral is None:
            s.say("keep look: lateral scale alone")
            result = tune(heightmap, target, "lateral", s.evaluator, tolerance_jnd=s.tolerance_jnd, max_fem=s.max_fem,
                          tile=s.tile)
            lateral, height = result.factor, None
        else:
            s.say(f"keep look: lateral x {lateral:.4g}, then height")
            start = heightmap if lateral == 1 else scaled(heightmap, "lateral", lateral)
            result = tune(start, target, "height", s.evaluator, tolerance_jnd=s.tolerance_jnd, max_fem=s.max_fem,
                          tile=s.tile)
            height = result.factor
    except InputError as err:
        return LookCandidate(lateral, None, None, None, str(err))
    return LookCandidate(lateral, height, result, look_difference(result.heightmap, heightmap), "; ".join(result.notes))
