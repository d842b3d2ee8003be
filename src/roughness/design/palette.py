"""Palettes: K textures a fingertip tells apart pairwise (at least ``min_jnd`` JND of equivalent wavelength, FEM-verified).

From a family: the family's texture (``roughness texture list``; default the standard bumps at
lambda 1 mm) scaled by height (or lateral size) to K equivalent wavelengths spread evenly over the
range the scaling reaches, ``margin_jnd`` inside its ends; each member is tuned (``tune``: surrogate
search, FEM verification within ``tolerance_jnd``), so neighbours planned ``spacing`` JND apart end up
at least ``spacing - 2 tolerance`` apart. A palette that cannot fit (spacing below min_jnd + 2
tolerance) is refused with the number that fits.

From a folder of heightmaps: the surrogate places every candidate on the standard scale; the K whose
smallest pairwise distance is largest are chosen (spread over the range), the FEM verifies them, and
the choice is repeated with the FEM's answers where known until the chosen K are all FEM-verified.

Every distance reported is between FEM answers; ``verified`` says whether all pairs reach min_jnd.

With a printer (the evaluator's ``printer``): a family palette is chosen among the textures the printer can
make (``printable_palette``), not tuned to targets spread over the digital range. A printer maps a range of
digital heights to one print (whole layers; parts narrower than a line removed), so the printed V of a family
scaled by height is a staircase, flat below half a layer and not even rising over the first layers: a target
there is met by no factor (three members at height x 0.118, 0 JND apart). Instead, the family scaled by the
knob (and, if that cannot hold K, by both knobs on a grid) is printed; the candidates whose print is not flat
and keeps its V (the surrogate's printed equivalent wavelength within ``MAX_PRINT_LOSS_JND`` of the digital one)
are placed on the scale as printed (and only those whose neighbours on the grid print alike: no print at a
layer's threshold), and the K farthest apart are verified as printed, as for a folder. If no K
are ``min_jnd`` apart, it says how many fit and why, before anything is written.
"""
from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.checks import integer, positive
from roughness.core.errors import InputError
from roughness.core.figures import new_figure, save_figure
from roughness.core.provenance import Provenance
from roughness.core.reprs import short_repr, v_text
from roughness.perceptual_scale import LOG_JND, WEBER_FRACTION, jnd
from roughness.surface.heightmap import Heightmap

from .evaluation import Evaluator, Verified
from .look import look_distances
from .tune import FACTOR_RANGE, GRID, TOLERANCE_JND, scaled, target_of, tune

if TYPE_CHECKING:
    from matplotlib.figure import Figure

DEFAULT_FAMILY = "standard-1.0"
MARGIN_JND = 0.2  # targets stay this far inside the reachable range (room for the FEM's correction)
MAX_ROUNDS = 4  # folder mode: choose, verify, choose again with the FEM's answers
PALETTE_FILE = "palette.json"
MAX_PRINT_LOSS_JND = 1.0  # a printable candidate's print is within this of its digital texture (surrogate)
PRINT_GRID = {"height": 25, "lateral": 9}  # the printable candidates: factors per knob on the two-knob grid


@dataclass(frozen=True)
class Member:
    name: str
    heightmap: Heightmap
    fem: Verified
    surrogate_roughness: float
    recipe: dict  # how it was made: family, knob and factor, or the source file

    def __repr__(self) -> str:
        return short_repr(self, repr(self.name), v_text(self.fem.roughness, self.fem.roughness_stderr),
                          f"lambda {self.fem.equivalent_lambda_mm:.3f} mm", repr(self.heightmap))


@dataclass(frozen=True)
class Palette:
    members: tuple[Member, ...]  # ordered from smoothest to roughest (FEM)
    min_jnd: float
    distances_jnd: np.ndarray  # (K, K) signed FEM distances, row rougher than column when positive
    source: str
    notes: tuple[str, ...] = field(default=())
    printing: dict = field(default_factory=dict)  # --printer: the profile and each member's digital and printed V
    provenance: Provenance | None = None  # what verified it (``Evaluator.provenance``)
    forecast: dict = field(default_factory=dict)  # a digital palette: how each member would print (print_forecast)

    def __repr__(self) -> str:
        members = ", ".join(f"{m.name} V {m.fem.roughness:.4g}" for m in self.members)
        return short_repr(self, f"{len(self.members)} members [{members}]", f"closest pair {self.closest_jnd:.2f} JND",
                          f"min {self.min_jnd:g} JND", "verified" if self.verified else "NOT verified")

    @property
    def closest_jnd(self) -> float:
        d = np.abs(self.distances_jnd)
        return float(d[np.triu_indices(len(d), 1)].min()) if len(d) > 1 else math.inf

    @cached_property
    def look_differences(self) -> np.ndarray:
        """(K, K) how different member i looks beside member j (look JND, ``design.look``), beside the feel's
        ``distances_jnd``."""
        return look_distances([m.heightmap for m in self.members])

    @property
    def verified(self) -> bool:
        return self.closest_jnd >= self.min_jnd

    def summary(self) -> dict:
        return {"source": self.source, "k": len(self.members), "min_jnd": self.min_jnd,
                "closest_pair_jnd": self.closest_jnd, "verified": self.verified,
                "members": [{"name": m.name, "fem_roughness": m.fem.roughness,
                             "fem_roughness_stderr": m.fem.roughness_stderr,
                             "equivalent_lambda_mm": m.fem.equivalent_lambda_mm, "on_scale": m.fem.on_scale,
                             "surrogate_roughness": m.surrogate_roughness, "recipe": m.recipe} for m in self.members],
                "distances_jnd": np.round(self.distances_jnd, 4).tolist(),
                "look_differences": np.round(self.look_differences, 3).tolist(), "notes": list(self.notes),
                **({"printing": self.printing} if self.printing else {}),
                **({"print_forecast": self.forecast} if self.forecast else {}),
                **({"provenance": self.provenance.as_dict()} if self.provenance else {})}


def _distances(members: list[Member]) -> np.ndarray:
    lam = [m.fem.equivalent_lambda_mm for m in members]
    return np.array([[jnd(a, b) for b in lam] for a in lam])


def _check(k: int, min_jnd: float) -> tuple[int, float]:
    return integer("k", k, minimum=2), positive("min_jnd", min_jnd)


def family_palette(k: int, min_jnd: float = 2.0, family: str = DEFAULT_FAMILY, by: str = "height",
                   evaluator: Evaluator | None = None, tolerance_jnd: float = TOLERANCE_JND,
                   margin_jnd: float = MARGIN_JND, seed: int = 0, progress=None) -> Palette:
    """K tuned variants of a family's texture, evenly spread over its reachable range (module docstring)."""
    from roughness.dataset.catalogue import make_texture

    k, min_jnd = _check(k, min_jnd)
    evaluator = evaluator or Evaluator()
    base, recipe = make_texture(family, seed=seed)
    if by not in FACTOR_RANGE:
        raise InputError(f"unknown knob {by!r}; choose one of {', '.join(FACTOR_RANGE)}", parameter="by")
    if evaluator.printer is not None:
        palette = printable_palette(k, min_jnd, family, by, evaluator, seed, progress)
        if tolerance_jnd == TOLERANCE_JND:
            return palette
        return replace(palette, notes=(*palette.notes, f"tolerance_jnd {tolerance_jnd:g} is not used with a "
                                       "printer: no member is tuned to a target; each is one of the variants the "
                                       f"printer can make, verified >= {min_jnd:g} JND from the others as printed"))
    lo, hi = FACTOR_RANGE[by]
    v, _ = evaluator.surrogate([scaled(base, by, f) for f in np.geomspace(lo, hi, GRID)])
    lam_lo, lam_hi = evaluator.lambda_of(float(v.min())), evaluator.lambda_of(float(v.max()))
    span = jnd(lam_hi, lam_lo) - 2 * margin_jnd
    spacing = span / (k - 1)
    need = min_jnd + 2 * tolerance_jnd
    if spacing < need:
        fits = max(1, int(span // need) + 1)
        raise InputError(f"{k} textures do not fit {min_jnd:g} JND apart: {family} scaled by {by} reaches lambda "
                         f"{lam_lo:.3f}..{lam_hi:.3f} mm ({span + 2 * margin_jnd:.1f} JND; {span:.1f} JND usable), "
                         f"room for {fits} at {need:g} JND planned spacing (min_jnd + 2 x tolerance)", parameter="k")
    members = []
    for i in range(k):
        lam = lam_lo * (1 + WEBER_FRACTION) ** (margin_jnd + i * spacing)
        result = tune(base, target_of(evaluator, lambda_mm=lam), by, evaluator, tolerance_jnd=tolerance_jnd)
        members.append(Member(f"texture-{i + 1}", result.heightmap, result.achieved, result.surrogate_roughness,
                              {**recipe, "by": by, "factor": result.factor, "target_lambda_mm": lam}))
        if progress:
            progress(f"texture {i + 1}/{k}: {by} x {result.factor:.3f}, {evaluator.verifier} lambda "
                     f"{result.achieved.equivalent_lambda_mm:.3f} mm ({result.jnd_error:+.2f} JND from {lam:.3f})")
    return Palette(tuple(members), min_jnd, _distances(members), f"family {family} by {by}")


@dataclass(frozen=True)
class Printable:
    """Variants of a family scaled by (height, lateral) factors, each as the printer prints it: the surrogate's V
    printed and digital, and whether the print keeps its V (``kept``: not flat, within ``MAX_PRINT_LOSS_JND``)."""

    heightmaps: list[Heightmap]  # the digital designs
    factors: list[tuple[float, float]]  # (height, lateral)
    printed_lambda_mm: np.ndarray  # surrogate, as printed, on the standard scale
    digital_lambda_mm: np.ndarray
    kept: np.ndarray  # bool

    def positions(self) -> np.ndarray:
        """The kept candidates' printed equivalent wavelengths in JND steps (ln lambda / ln 1.19)."""
        return np.log(self.printed_lambda_mm[self.kept]) / LOG_JND


def variant(base: Heightmap, height: float, lateral: float = 1.0) -> Heightmap:
    """``base`` stretched laterally by ``lateral`` (if not 1), then its heights scaled by ``height``: a member of a
    printer-aware palette from its recipe's ``height_factor`` and ``lateral_factor``."""
    return scaled(scaled(base, "lateral", lateral), "height", height) if lateral != 1 else scaled(base, "height", height)


def printable_candidates(base: Heightmap, factors: list[tuple[float, float]], evaluator: Evaluator,
                         rows: int = 1) -> Printable:
    """``base`` scaled by each (height, lateral) factor pair (``rows`` rows of a grid, neighbours in a row one step
    apart), printed (``evaluator.printer``) and placed on the standard scale by the surrogate, printed and
    digital; kept if the print is not flat, keeps its V and its neighbours' (``_stable``)."""
    maps = [variant(base, height, lateral) for height, lateral in factors]
    v_printed, _ = evaluator.surrogate(maps)
    v_digital, _ = replace(evaluator, printer=None).surrogate(maps)
    floor = evaluator.scale.floor
    printed_lam = np.array([evaluator.lambda_of(v) for v in v_printed])
    digital_lam = np.array([evaluator.lambda_of(v) for v in v_digital])
    loss = np.abs(np.log(printed_lam / digital_lam)) / LOG_JND
    kept = (v_printed >= floor) & (v_digital >= floor) & (loss <= MAX_PRINT_LOSS_JND)
    return Printable(maps, factors, printed_lam, digital_lam, _stable(kept, printed_lam, rows))


def _stable(kept: np.ndarray, printed_lam: np.ndarray, rows: int) -> np.ndarray:
    """``kept`` where both neighbours along the grid's inner axis (``rows`` rows of factors) are kept too and print
    within ``MAX_PRINT_LOSS_JND`` of it: a print that jumps under a small change of the design (a layer more or
    less, a cap cut by the line) is not one to rely on (a region of a plate resampled to its pixels may print as
    the neighbour)."""
    k = kept.reshape(rows, -1)
    step = np.log(printed_lam.reshape(rows, -1)) / LOG_JND
    near = np.abs(np.diff(step, axis=1)) <= MAX_PRINT_LOSS_JND
    link = np.zeros_like(k)  # the link to the right neighbour: both kept and near
    link[:, :-1] = k[:, :-1] & k[:, 1:] & near
    stable = k.copy()
    stable[:, 1:] &= link[:, :-1]  # the left neighbour's link
    stable[:, :-1] &= link[:, :-1]  # its own link to the right
    stable[:, [0, -1]] = False  # an end has one neighbour only
    return stable.ravel()


def fits(positions: np.ndarray, min_jnd: float) -> int:
    """How many of ``positions`` (JND steps) can be chosen pairwise at least ``min_jnd`` apart (greedy, exact
    in 1-D)."""
    x = np.sort(positions)
    count, last = 0, -math.inf
    for value in x:
        if value - last >= min_jnd:
            count, last = count + 1, value
    return count


def _factor_grid(by: str, both: bool) -> list[tuple[float, float]]:
    """(height, lateral) factor pairs: the knob ``by`` over its range (GRID points), or both knobs on a grid."""
    if not both:
        return [(f, 1.0) if by == "height" else (1.0, f) for f in np.geomspace(*FACTOR_RANGE[by], GRID)]
    return [(float(h), float(lat)) for lat in np.geomspace(*FACTOR_RANGE["lateral"], PRINT_GRID["lateral"])
            for h in np.geomspace(*FACTOR_RANGE["height"], PRINT_GRID["height"])]


def printable_palette(k: int, min_jnd: float, family: str, by: str, evaluator: Evaluator, seed: int = 0,
                      progress=None) -> Palette:
    """K variants of a family that stay ``min_jnd`` apart as the evaluator's printer prints them (module
    docstring): scaled by ``by`` alone, or by both knobs where that cannot hold K; InputError (parameter ``k``)
    saying how many fit, and why, when no K do."""
    from roughness.dataset.catalogue import make_texture

    base, recipe = make_texture(family, seed=seed)
    notes: list[str] = []
    pool = printable_candidates(base, _factor_grid(by, False), evaluator)
    if fits(pool.positions(), min_jnd) < k:
        wide = printable_candidates(base, _factor_grid(by, True), evaluator, PRINT_GRID["lateral"])
        notes.append(f"{family} scaled by {by} alone holds {fits(pool.positions(), min_jnd)} printable textures "
                     f"{min_jnd:g} JND apart: the height and lateral size were both varied")
        pool = wide
    room = fits(pool.positions(), min_jnd)
    if room < k:
        raise InputError(_no_room(k, min_jnd, family, pool, room, evaluator), parameter="k")
    index = np.flatnonzero(pool.kept)
    candidates = [(f"candidate-{i}", pool.heightmaps[i]) for i in index]
    try:
        chosen = folder_palette(candidates, k, min_jnd, evaluator, progress=progress)
    except InputError as err:  # the verifier's prints are closer than the surrogate's
        raise InputError(f"{err} as printed by {evaluator.printer.name} ({evaluator.verifier}; the surrogate "
                         f"placed {room}): ask for fewer textures or a smaller min_jnd", parameter="k") from None
    members = []
    for n, m in enumerate(chosen.members):
        i = int(m.name.split("-")[1])  # the candidate-i name holds its index in the pool
        height, lateral = pool.factors[i]
        members.append(Member(f"texture-{n + 1}", m.heightmap, m.fem, m.surrogate_roughness,
                              {**recipe, "height_factor": height, "lateral_factor": lateral,
                               "printer": evaluator.printer.name,
                               "surrogate_printed_lambda_mm": float(pool.printed_lambda_mm[i]),
                               "surrogate_digital_lambda_mm": float(pool.digital_lambda_mm[i])}))
    notes.append(f"chosen among {len(index)} of {len(pool.factors)} variants whose print by "
                 f"{evaluator.printer.name} is not flat and keeps its V within {MAX_PRINT_LOSS_JND:g} JND, as do "
                 "its neighbours'")
    return Palette(tuple(members), min_jnd, _distances(members), f"family {family} as printed by "
                   f"{evaluator.printer.name}", tuple(notes))


def _no_room(k: int, min_jnd: float, family: str, pool: Printable, room: int, evaluator: Evaluator) -> str:
    """Why K printable textures do not fit ``min_jnd`` apart: the range the printer leaves, and how many fit."""
    printer = evaluator.printer
    why = (f"{printer.describe()} makes no part narrower than {printer.smallest_feature_mm:g} mm and rounds "
           f"heights to {printer.layer_mm:g} mm layers")
    if not pool.kept.any():
        return f"no variant of {family} keeps its V when printed: {why}"
    lam = pool.printed_lambda_mm[pool.kept]
    span = jnd(float(lam.max()), float(lam.min()))
    return (f"{k} textures do not fit {min_jnd:g} JND apart as printed: of {len(pool.factors)} variants of {family} "
            f"(height and lateral size), the {int(pool.kept.sum())} whose print keeps its V span lambda "
            f"{lam.min():.3f}..{lam.max():.3f} mm ({span:.1f} JND, surrogate) once printed ({why}): room for {room} "
            f"at {min_jnd:g} JND")


@dataclass(frozen=True)
class Forecast:
    """How one texture would print on one profile: the surrogate's V digital and printed, and the JNDs between
    their equivalent wavelengths (negative: the print feels smoother)."""

    profile: str
    digital_roughness: float
    printed_roughness: float
    jnd: float | None  # None: the digital or the printed V is below the standard scale's floor
    in_domain: bool  # the surrogate's training domain, for both
    notes: tuple[str, ...]  # what the print model could not resolve at the map's pixels

    def as_dict(self) -> dict:
        return {"digital_roughness": self.digital_roughness, "printed_roughness": self.printed_roughness,
                "jnd": self.jnd, "surrogate_in_domain": self.in_domain, "notes": list(self.notes)}

    def describe(self) -> str:
        """``fdm-0.4-0.2 V 0.0412 (-0.40 JND)`` (surrogate: no uncertainty of its own)."""
        change = "below the scale" if self.jnd is None else f"{self.jnd:+.2f} JND"
        return f"{self.profile} V {self.printed_roughness:.4f} ({change}{'' if self.in_domain else ', out of domain'})"


def print_forecast(members: Sequence[Member], evaluator: Evaluator, profiles: Sequence[str] | None = None
                   ) -> dict[str, dict[str, Forecast]]:
    """For each member (by name), how it would fare on each shipped profile (``PROFILES``, or ``profiles``): the
    surrogate's V of its print against its digital V, in JND. Members no profile can print at their pixel size
    get no entry for it."""
    from roughness.surface.printing import PROFILES, printed

    plain = replace(evaluator, printer=None)
    maps = [m.heightmap for m in members]
    v_digital, in_digital = plain.surrogate(maps)
    floor = plain.scale.floor
    out: dict[str, dict[str, Forecast]] = {m.name: {} for m in members}
    for name in profiles or list(PROFILES):
        for m, v0, ok0 in zip(members, v_digital, in_digital):
            try:
                result = printed(m.heightmap, PROFILES[name])
            except InputError:
                continue
            v, ok = plain.surrogate([result.heightmap])
            lost = jnd(plain.lambda_of(float(v[0])), plain.lambda_of(float(v0))) if min(v[0], v0) >= floor else None
            out[m.name][name] = Forecast(name, float(v0), float(v[0]), lost, bool(ok[0] and ok0), result.notes)
    return out


def widest_selection(positions: np.ndarray, k: int) -> tuple[list[int], float]:
    """Indices of k points (1-D) whose smallest gap is largest, spread from the lowest point up, and that gap."""
    order = np.argsort(positions)
    x = positions[order]

    def greedy(gap: float) -> list[int]:
        chosen = [0]
        for i in range(1, len(x)):
            if x[i] - x[chosen[-1]] >= gap:
                chosen.append(i)
        return chosen

    gaps = np.unique(np.abs(x[:, None] - x[None, :]))
    best, best_gap = [0], 0.0
    low, high = 0, len(gaps) - 1
    while low <= high:  # the largest gap at which the greedy walk still picks k points
        mid = (low + high) // 2
        picked = greedy(gaps[mid])
        if len(picked) >= k:
            best, best_gap, low = picked[:k], float(gaps[mid]), mid + 1
        else:
            high = mid - 1
    return [int(order[i]) for i in best], best_gap


def candidate_names(files: list[Path]) -> list[str]:
    """A member name per candidate file: its stem, or its whole file name where stems collide (tex.npy
    and tex.npz become "tex.npy" and "tex.npz"). Names are compared ignoring case, as the members are
    written as NAME.npz; InputError naming both files if two are still alike."""
    stems = Counter(f.stem.casefold() for f in files)
    names = [f.stem if stems[f.stem.casefold()] == 1 else f.name for f in files]
    clash = _clash(names)
    if clash:
        i, j = clash
        raise InputError(f"{files[i]} and {files[j]} would both be the palette member {names[j]!r} (one file "
                         f"{names[j]}.npz): rename one of them", parameter="candidates")
    return names


def _clash(names: list[str]) -> tuple[int, int] | None:
    """The first two members that would share a file NAME.npz (names alike ignoring case), if any."""
    first: dict[str, int] = {}
    for j, name in enumerate(names):
        i = first.setdefault(str(name).casefold(), j)
        if i != j:
            return i, j
    return None


def folder_palette(candidates: list[tuple[str, Heightmap]], k: int, min_jnd: float = 2.0,
                   evaluator: Evaluator | None = None, tile: bool = False, progress=None) -> Palette:
    """The k candidates farthest apart, FEM-verified (module docstring); their names must differ
    (``candidate_names``)."""
    if _clash([name for name, _ in candidates]):
        raise InputError("two candidates share a name (see candidate_names)", parameter="candidates")
    k, min_jnd = _check(k, min_jnd)
    if len(candidates) < k:
        raise InputError(f"{len(candidates)} candidate textures, fewer than k={k}", parameter="k")
    evaluator = evaluator or Evaluator()
    v_sur, _ = evaluator.surrogate([hm for _, hm in candidates], tile=tile)
    log_lam = np.log([evaluator.lambda_of(v) for v in v_sur]) / LOG_JND
    fem: dict[int, Verified] = {}
    for _ in range(MAX_ROUNDS):
        chosen, gap = widest_selection(log_lam, k)
        if gap < min_jnd:
            break
        todo = [i for i in chosen if i not in fem]
        if not todo:
            break
        for i in todo:
            fem[i] = evaluator.verify(candidates[i][1], tile=tile)
            log_lam[i] = math.log(fem[i].equivalent_lambda_mm) / LOG_JND
            if progress:
                progress(f"{evaluator.verifier} {candidates[i][0]}: V {fem[i].roughness:.4f}, "
                         f"lambda {fem[i].equivalent_lambda_mm:.3f} mm")
    chosen, gap = widest_selection(log_lam, k)
    if gap < min_jnd or any(i not in fem for i in chosen):
        raise InputError(f"no {k} of the {len(candidates)} textures are {min_jnd:g} JND apart: the best choice "
                         f"has its closest pair {gap:.2f} JND apart", parameter="min_jnd")
    chosen.sort(key=lambda i: fem[i].roughness)
    members = [Member(candidates[i][0], candidates[i][1], fem[i], float(v_sur[i]), {"file": candidates[i][0]})
               for i in chosen]
    return Palette(tuple(members), min_jnd, _distances(members), f"{len(candidates)} candidates")


def save_preview(palette: Palette, path: str | Path | None = None, overwrite: bool = True) -> Figure:
    """A sheet of each member's heightmap with its FEM V and equivalent wavelength; PNG to ``path`` if given.

    Returns
    -------
    matplotlib.figure.Figure
        The sheet (no pyplot: the backend is left as it was).
    """
    k = len(palette.members)
    fig = new_figure(figsize=(2.4 * k, 2.9))
    axes = fig.subplots(1, k, squeeze=False)
    for ax, m in zip(axes[0], palette.members):
        width, height = m.heightmap.size_mm
        ax.imshow(m.heightmap.heights, cmap="gray", extent=(0, width, height, 0))
        ax.set_title(f"{m.name}\nV {m.fem.roughness:.3f}, λ {m.fem.equivalent_lambda_mm:.2f} mm", fontsize=9)
        ax.set_xticks([]), ax.set_yticks([])
    fig.suptitle(f"closest pair {palette.closest_jnd:.2f} JND (FEM; asked >= {palette.min_jnd:g})", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, 100, overwrite)


def save_palette(palette: Palette, folder, stl: bool = False, base_mm: float | None = None,
                 overwrite: bool = True) -> None:
    """The folder: one NAME.npz per member (and NAME.stl plates if asked), palette.json, preview.png;
    unless ``overwrite``, none of them replaces an existing file."""
    import json

    from roughness.core.files import atomic_write
    from roughness.surface.io import save_heightmap

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for m in palette.members:
        save_heightmap(m.heightmap, folder / f"{m.name}.npz", overwrite=overwrite)
        if stl:
            save_heightmap(m.heightmap, folder / f"{m.name}.stl", base_mm=base_mm, overwrite=overwrite)
    save_preview(palette, folder / "preview.png", overwrite)
    text = json.dumps(palette.summary(), indent=1) + "\n"
    atomic_write(folder / PALETTE_FILE, lambda tmp: Path(tmp).write_text(text), overwrite)



def load_palette(folder) -> list[tuple[str, Heightmap, dict]]:
    """(name, heightmap, summary entry) of each member of a palette folder written by ``save_palette``;
    InputError if two members share a name (one file: a folder written before member names were unique)."""
    import json

    from roughness.surface.io import load_heightmap

    folder = Path(folder)
    path = folder / PALETTE_FILE
    if not path.is_file():
        raise InputError(f"{folder} is not a palette folder: it has no {PALETTE_FILE} (make one with roughness palette)",
                         parameter="palette")
    try:
        members = json.loads(path.read_text())["members"]
        clash = _clash([m["name"] for m in members])
        if clash:
            raise InputError(f"{path} lists two members named {members[clash[1]]['name']!r}, which share one file "
                             "(a palette written before member names were made unique): make the palette again",
                             parameter="palette")
        return [(m["name"], load_heightmap(folder / f"{m['name']}.npz"), m) for m in members]
    except (json.JSONDecodeError, KeyError, TypeError) as err:
        raise InputError(f"{path} is not a palette description: {err}", parameter="palette") from None
