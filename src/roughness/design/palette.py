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
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
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
from .tune import FACTOR_RANGE, GRID, TOLERANCE_JND, scaled, target_of, tune

if TYPE_CHECKING:
    from matplotlib.figure import Figure

DEFAULT_FAMILY = "standard-1.0"
MARGIN_JND = 0.2  # targets stay this far inside the reachable range (room for the FEM's correction)
MAX_ROUNDS = 4  # folder mode: choose, verify, choose again with the FEM's answers
PALETTE_FILE = "palette.json"


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

    def __repr__(self) -> str:
        members = ", ".join(f"{m.name} V {m.fem.roughness:.4g}" for m in self.members)
        return short_repr(self, f"{len(self.members)} members [{members}]", f"closest pair {self.closest_jnd:.2f} JND",
                          f"min {self.min_jnd:g} JND", "verified" if self.verified else "NOT verified")

    @property
    def closest_jnd(self) -> float:
        d = np.abs(self.distances_jnd)
        return float(d[np.triu_indices(len(d), 1)].min()) if len(d) > 1 else math.inf

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
                "distances_jnd": np.round(self.distances_jnd, 4).tolist(), "notes": list(self.notes),
                **({"printing": self.printing} if self.printing else {}),
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
