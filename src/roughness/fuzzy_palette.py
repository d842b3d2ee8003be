"""K fuzzy skin settings that feel clearly different (for grips that must be told apart), as ``palette`` does for
textures: at least ``min_jnd`` JND of equivalent wavelength apart, verified by the spectral engine over several walls.

As ``design.palette``'s family palettes: one knob (thickness or point distance, the other settings fixed) is scanned
over its range (``fuzzy_tune.scan``), K equivalent wavelengths are spread evenly over what it reaches, ``MARGIN_JND``
inside its ends, and each member is tuned to its wavelength (``fuzzy_tune.tune_fuzzy_skin``, within
``tolerance_jnd``), so neighbours planned ``spacing`` JND apart end up at least ``spacing - 2 tolerance`` apart. A
palette that cannot fit (spacing below min_jnd + 2 tolerance) is refused with the number that fits.

Every distance is between verified means over the draws (the same seeds for every member); each comes with its
standard error, and one print of a setting differs from the next by the spread between walls (``draw_jnd``).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from roughness.core.checks import integer, positive
from roughness.core.errors import InputError
from roughness.design.palette import MARGIN_JND
from roughness.design.tune import TOLERANCE_JND
from roughness.fuzzy_tune import DRAWS, ENGINE, FuzzyTune, equivalent_lambda, lambda_target, scan, tune_fuzzy_skin
from roughness.perceptual_scale import WEBER_FRACTION, jnd, load_scale
from roughness.surface.fuzzy_skin import FuzzySkin
from roughness.surface.printing import FdmProfile


@dataclass(frozen=True)
class FuzzyPalette:
    """K tuned settings, smoothest first, and their pairwise distances (JND of the verified means)."""

    members: tuple[FuzzyTune, ...]
    min_jnd: float
    knob: str
    notes: tuple[str, ...] = field(default=())

    @property
    def lambdas_mm(self) -> list[float]:
        return [equivalent_lambda(m.feel) for m in self.members]

    @property
    def distances_jnd(self) -> np.ndarray:
        """(K, K) signed distances, row rougher than column when positive."""
        lam = self.lambdas_mm
        return np.array([[jnd(a, b) for b in lam] for a in lam])

    @property
    def neighbours(self) -> list[tuple[float, float]]:
        """Each neighbouring pair's distance (JND) and its standard error (the two means')."""
        d = self.distances_jnd
        return [(float(d[i + 1, i]), math.hypot(a.jnd_stderr, b.jnd_stderr))
                for i, (a, b) in enumerate(zip(self.members, self.members[1:]))]

    @property
    def closest_jnd(self) -> float:
        d = np.abs(self.distances_jnd)
        return float(d[np.triu_indices(len(d), 1)].min())

    @property
    def verified(self) -> bool:
        return self.closest_jnd >= self.min_jnd

    def summary(self) -> dict:
        return {"knob": self.knob, "k": len(self.members), "min_jnd": self.min_jnd, "engine": ENGINE,
                "closest_pair_jnd": self.closest_jnd, "verified": self.verified,
                "neighbours": [{"jnd": d, "jnd_stderr": se} for d, se in self.neighbours],
                "distances_jnd": np.round(self.distances_jnd, 4).tolist(), "notes": list(self.notes),
                "members": [m.summary() for m in self.members]}

    def lines(self) -> list[str]:
        """The palette in words: a line per member, then each neighbour pair's distance."""
        out = [f"grip {i + 1}: {m.knob.replace('-', ' ')} {m.value_mm:.3f} mm ({m.skin.describe()}): V "
               f"{m.feel.roughness:.4f}, lambda {lam:.3f} mm ± {m.jnd_stderr:.2f} JND (mean of "
               f"{len(m.feel.predictions)} walls; one print ± {m.draw_jnd or 0:.2f} JND)"
               for i, (m, lam) in enumerate(zip(self.members, self.lambdas_mm))]
        out += [f"grips {i + 1}-{i + 2}: {d:.2f} ± {se:.2f} JND apart" for i, (d, se) in enumerate(self.neighbours)]
        out.append(f"closest pair {self.closest_jnd:.2f} JND ({ENGINE}; asked >= {self.min_jnd:g}): "
                   + ("verified" if self.verified else "NOT verified"))
        return out


def fuzzy_palette(k: int, skin: FuzzySkin, knob: str = "thickness", min_jnd: float = 2.0,
                  printer: FdmProfile | str = "fdm-0.4-0.2", tune_range: tuple[float, float] | None = None,
                  tolerance_jnd: float = TOLERANCE_JND, seed: int = 0, draws: int = DRAWS, tile_mm: float = 12.0,
                  pixel_mm: float = 0.05, radius_mm: float | None = None,
                  progress: Callable[[str], None] | None = None) -> FuzzyPalette:
    """``k`` settings of ``knob`` (the rest of ``skin`` fixed) at least ``min_jnd`` apart (module docstring), on a
    cylinder of signed ``radius_mm`` if given."""
    k, min_jnd = integer("k", k, 2), positive("min_jnd", min_jnd)
    tolerance_jnd = positive("tolerance_jnd", tolerance_jnd)
    grid = scan(skin, knob, printer, tune_range, seed, draws, tile_mm, pixel_mm, radius_mm, progress)
    lo, hi = grid.reach_lambda_mm
    lo = max(lo, load_scale(ENGINE).floor_lambda_mm)  # below the floor a texture is not felt
    span = jnd(hi, lo) - 2 * MARGIN_JND
    need = min_jnd + 2 * tolerance_jnd
    if span < need * (k - 1):
        room = max(1, int(span // need) + 1) if span > 0 else 1
        raise InputError(f"{k} settings do not fit {min_jnd:g} JND apart: {knob} over its range reaches lambda "
                         f"{lo:.3f}..{hi:.3f} mm ({span + 2 * MARGIN_JND:.1f} JND; {span:.1f} usable), room for "
                         f"{room} at {need:g} JND planned spacing (min_jnd + 2 x tolerance)", parameter="k")
    spacing = span / (k - 1)
    members = []
    for i in range(k):
        lam = lo * (1 + WEBER_FRACTION) ** (MARGIN_JND + i * spacing)
        members.append(tune_fuzzy_skin(skin, lambda_target(lam), knob, printer, tune_range, tolerance_jnd,
                                       seed=seed, draws=draws, tile_mm=tile_mm, pixel_mm=pixel_mm,
                                       radius_mm=radius_mm, grid=grid))
        if progress:
            progress(f"grip {i + 1}/{k}: {knob} {members[-1].value_mm:.3f} mm, {members[-1].jnd_error:+.2f} JND "
                     f"from lambda {lam:.3f} mm")
    notes = tuple(dict.fromkeys(n for m in members for n in m.notes))
    off = [str(i + 1) for i, m in enumerate(members) if m.feel.placement is None or not m.feel.placement.on_scale]
    if off:
        notes += (f"grip(s) {', '.join(off)} lie off the standard scale's measured range: their equivalent lambda "
                  "is extrapolated (the distances to them are less sure than their standard errors say)",)
    return FuzzyPalette(tuple(members), min_jnd, knob, notes)
