"""Does a texture feel the same everywhere? The paper's homogeneity test on windows across the surface.

Definition (written down, as the paper leaves the details open):

* ``n`` windows (default 50) of side ``window_mm`` are placed uniformly at random (seeded): wholly on
  the map, or anywhere if the map is a periodic tile (``tile``).
* The local roughness V_i of a window is V of the skin footprint (10 mm) centred on it. A window
  smaller than the footprint (the paper's 5 mm) is felt alone: it and its three mirror images make a
  seamless periodic tile, read periodically under the footprint. The default window is the footprint.
* ``relative_variance`` = var(V_i) / mean(V_i)^2 (sample variance, n - 1): the squared coefficient
  of variation, dimensionless. The paper reports about 1e-4 for most of its textures and calls
  textures above 1e-3 inhomogeneous (``PAPER_THRESHOLD``; ``paper_verdict``). Undefined (None, and no
  paper verdict) when mean V is below the standard scale's floor (``StandardScale.floor``, about
  0.003): there the ratio measures the engine's noise around zero, not a texture (a flat map gave
  "Infinity").
* ``spread_jnd`` = standard deviation over the windows of ln(lambda_i) / ln(1.19), lambda_i the
  equivalent wavelength of V_i on the standard scale, a window below the scale counted at its floor
  (the scale's threshold, as in ``jnd_distance``: the spread is then a lower bound); ``range_jnd`` =
  the 10th to 90th percentile of the same. The ``verdict`` is perceptual: "inhomogeneous" if
  ``range_jnd`` >= 1, i.e. a fingertip moved over the surface finds parts a just-noticeable difference
  apart. With every window below the scale there is no spread (None) and the verdict is "homogeneous":
  no roughness anywhere.

Measured (coarse FEM, footprint windows; see docs/how-to/homogeneity.md): a grating varies by 1e-4, as the paper's
textures; random bump textures by about 1.5e-3 (the bumps under a 10 mm footprint differ from place
to place), 0.1 JND. The surrogate adds its own position-to-position error (about 5e-3 on bump textures,
2e-2 on gratings): use ``engine="fem"`` when the relative variance itself matters.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.checks import flag, integer, positive
from roughness.core.errors import InputError
from roughness.core.figures import new_figure, save_figure
from roughness.core.limits import MAX_WINDOWS, MAX_WORKING_VALUES, check_size
from roughness.core.reprs import short_repr
from roughness.perceptual_scale import LOG_JND
from roughness.surface.heightmap import Heightmap

from .evaluation import ENGINES, Evaluator

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from roughness.surface.printing import PrintResult

PAPER_THRESHOLD = 1e-3  # relative variance above which the paper calls a texture inhomogeneous
JND_RANGE = 1.0  # 10th-90th percentile range (JND) at and above which parts of a surface feel different
N_WINDOWS = 50
MIN_WINDOW_PIXELS = 8


@dataclass(frozen=True)
class Homogeneity:
    """Local roughness over ``n`` windows of a texture, its spread and the verdicts.

    ``x_mm``, ``y_mm``: window centres (mm); ``roughness``: V per window; ``lambda_mm``: its
    equivalent wavelength (mm); ``in_domain``: whether the surrogate was inside its training
    domain (always True for the FEM).
    """

    window_mm: float
    x_mm: np.ndarray
    y_mm: np.ndarray
    roughness: np.ndarray
    lambda_mm: np.ndarray
    in_domain: np.ndarray
    engine: str
    relative_variance: float | None  # var(V) / mean(V)^2 over the windows; None: mean V below the scale's floor
    spread_jnd: float | None  # SD of ln(lambda_eq) / ln(1.19) over the windows; None: every window below the scale
    range_jnd: float | None  # 10th to 90th percentile of ln(lambda_eq) / ln(1.19); None as spread_jnd
    mean_roughness: float
    floor: float = 0.0  # V of the standard scale's floor
    below_scale: int = 0  # windows whose V is below the floor
    digital: Homogeneity | None = None  # judged as printed: the digital texture's test on the same windows
    print_result: PrintResult | None = None  # judged as printed: what the printer did

    def __repr__(self) -> str:
        spread = "" if self.range_jnd is None else f"10-90% range {self.range_jnd:.2f} JND"
        return short_repr(self, self.verdict, f"{len(self.roughness)} windows of {self.window_mm:g} mm",
                          f"mean V {self.mean_roughness:.4g}", spread, self.engine)

    @property
    def verdict(self) -> str:
        """Perceptual: "inhomogeneous" if the windows' 10-90% range spans a JND or more (never with no range:
        every window below the scale is smooth everywhere)."""
        return "inhomogeneous" if self.range_jnd is not None and self.range_jnd >= JND_RANGE else "homogeneous"

    @property
    def paper_verdict(self) -> str | None:
        """The paper's: "inhomogeneous" above a relative variance of 1e-3; None where that is undefined."""
        if self.relative_variance is None:
            return None
        return "inhomogeneous" if self.relative_variance > PAPER_THRESHOLD else "homogeneous"

    @property
    def note(self) -> str:
        """What the windows below the scale's floor do to the statistics (empty if there are none)."""
        n = len(self.roughness)
        if self.below_scale == n:
            return (f"no roughness anywhere: every window is below the standard scale (V < {self.floor:.4f}); "
                    "relative variance undefined (mean V ~ 0), no spread in JND")
        if not self.below_scale:
            return ""
        undefined = "; relative variance undefined (mean V below the floor)" if self.relative_variance is None else ""
        return (f"{self.below_scale} of {n} windows are below the standard scale (V < {self.floor:.4f}), counted at "
                f"its floor: the spread in JND is a lower bound{undefined}")

    def summary(self) -> dict:
        return {"engine": self.engine, "windows": len(self.roughness), "window_mm": self.window_mm,
                "mean_roughness": self.mean_roughness, "relative_variance": self.relative_variance,
                "spread_jnd": self.spread_jnd, "range_jnd": self.range_jnd, "verdict": self.verdict,
                "paper_threshold": PAPER_THRESHOLD, "paper_verdict": self.paper_verdict,
                "scale_floor_roughness": self.floor, "below_scale_windows": self.below_scale, "note": self.note,
                "in_domain_fraction": float(np.mean(self.in_domain)),
                "definition": "V_i: V of the footprint centred on window i (a window smaller than the footprint "
                              "is felt alone, mirror-tiled); relative_variance = var(V_i) / mean(V_i)^2; "
                              "spread_jnd = SD of ln(lambda_i) / ln 1.19 (a V below the scale's floor counted at "
                              "it); range_jnd = its 10-90% range; verdict: inhomogeneous if range_jnd >= 1; "
                              "relative_variance null if mean V is below the floor, spreads null if every V is",
                **({"digital": self.digital.summary()} if self.digital is not None else {}),
                **({"printing": self.print_result.as_dict()} if self.print_result is not None else {})}


def window_centres(heightmap: Heightmap, window_mm: float, footprint_mm: float, n: int, seed: int = 0,
                   tile: bool = False) -> np.ndarray:
    """(n, 2) random window centres (x, y in mm): anywhere on a tile, else with window and footprint on the map."""
    width, height = heightmap.size_mm
    rng = np.random.default_rng(seed)
    if tile:
        return np.column_stack([rng.uniform(0, width, n), rng.uniform(0, height, n)])
    half = max(window_mm, min(footprint_mm, window_mm)) / 2
    if 2 * half > min(width, height) + 1e-9:
        raise InputError(f"a {2 * half:g} mm window does not fit on the {width:.2f} mm x {height:.2f} mm map; "
                         "use a smaller window (or tile, for a periodic texture)", parameter="window_mm")
    return np.column_stack([rng.uniform(half, width - half, n), rng.uniform(half, height - half, n)])


def mirrored_window(heightmap: Heightmap, centre_mm: tuple[float, float], window_mm: float,
                    tile: bool = False) -> Heightmap:
    """The window (side ``window_mm``, whole pixels) and its mirror images: a seamless periodic tile."""
    side = round(window_mm / heightmap.pixel_mm)
    ny, nx = heightmap.shape
    j0 = round(centre_mm[0] / heightmap.pixel_mm - side / 2)
    i0 = round(centre_mm[1] / heightmap.pixel_mm - side / 2)
    if tile:
        w = heightmap.heights[np.ix_(np.arange(i0, i0 + side) % ny, np.arange(j0, j0 + side) % nx)]
    else:
        j0, i0 = min(max(j0, 0), nx - side), min(max(i0, 0), ny - side)
        w = heightmap.heights[i0:i0 + side, j0:j0 + side]
    top = np.hstack([w, w[:, ::-1]])
    return Heightmap(np.vstack([top, top[::-1]]), heightmap.pixel_mm)


def homogeneity(heightmap: Heightmap, engine: str = "surrogate", window_mm: float | None = None,
                n: int = N_WINDOWS, seed: int = 0, tile: bool = False, evaluator: Evaluator | None = None,
                progress=None) -> Homogeneity:
    """The homogeneity test (module docstring) of a heightmap (mm) with ``engine`` ("surrogate" or "fem").

    ``window_mm``: window side (default: the 10 mm footprint); ``tile``: the map is a periodic tile;
    ``progress(done, total)`` is called after each FEM window.
    """
    if engine not in ENGINES:
        raise InputError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}", parameter="engine")
    n = check_size("windows", integer("n", n, minimum=3), MAX_WINDOWS, "n")
    seed, tile = integer("seed", seed, minimum=0), flag("tile", tile)
    evaluator = evaluator or Evaluator()
    footprint = evaluator.footprint_mm
    window_mm = footprint if window_mm is None else positive("window_mm", window_mm)
    if window_mm / heightmap.pixel_mm < MIN_WINDOW_PIXELS:
        raise InputError(f"window_mm={window_mm:g} spans fewer than {MIN_WINDOW_PIXELS} pixels of "
                         f"{heightmap.pixel_mm:g} mm", parameter="window_mm")
    if not tile:
        heightmap.require_footprint(footprint)
    centres = window_centres(heightmap, window_mm, footprint, n, seed, tile)
    if window_mm < footprint:  # each window felt alone
        side = 2 * round(window_mm / heightmap.pixel_mm)
        check_size(f"values of {n} mirrored windows of {side} x {side} pixels", n * side**2, MAX_WORKING_VALUES, "n")
        maps = [mirrored_window(heightmap, tuple(c), window_mm, tile) for c in centres]
        places, periodic = [None] * n, True
    else:
        maps, places, periodic = [heightmap] * n, [tuple(c) for c in centres], tile
    if engine == "surrogate":
        v, in_domain = evaluator.surrogate(maps, tile=periodic, centres_mm=places)
    else:
        v = np.empty(n)
        for i, (hm, c) in enumerate(zip(maps, places)):
            v[i] = evaluator.verify(hm, tile=periodic, centre_mm=c).roughness
            if progress:
                progress(i + 1, n)
        in_domain = np.ones(n, dtype=bool)
    scale = evaluator.scale
    floor, below = scale.floor, int(np.sum(v < scale.floor))
    lam = np.array([scale.floored_lambda(float(x)) for x in v])  # below the scale: at its floor
    steps = np.log(lam) / LOG_JND
    mean = float(v.mean())
    relative_variance = float(v.var(ddof=1) / mean**2) if mean >= floor else None
    spread = range_ = None
    if below < n:
        p10, p90 = np.percentile(steps, [10, 90])
        spread, range_ = float(np.std(steps, ddof=1)), float(p90 - p10)
    return Homogeneity(window_mm, centres[:, 0], centres[:, 1], v, lam, in_domain, engine, relative_variance,
                       spread, range_, mean, floor, below)


def homogeneity_as_printed(heightmap: Heightmap, engine: str = "surrogate", window_mm: float | None = None,
                           n: int = N_WINDOWS, seed: int = 0, tile: bool = False, evaluator: Evaluator | None = None,
                           progress=None) -> Homogeneity:
    """``homogeneity`` of the map as the evaluator's ``printer`` prints it (printed once, whole, then windowed), with
    the digital map's on the same windows (same ``seed``) as its ``digital`` and the print as its ``print_result``;
    InputError (parameter ``printer``) without a printer."""
    from dataclasses import replace

    from roughness.surface.printing import printed

    evaluator = evaluator or Evaluator()
    if evaluator.printer is None:
        raise InputError("homogeneity_as_printed needs an evaluator with a printer", parameter="printer")
    result = printed(heightmap, evaluator.printer, flag("tile", tile))
    plain = replace(evaluator, printer=None)  # the print is made once here, not once per window
    as_printed = homogeneity(result.heightmap, engine, window_mm, n, seed, tile, plain, progress)
    digital = homogeneity(heightmap, engine, window_mm, n, seed, tile, plain, progress)
    evaluator.fem_runs = plain.fem_runs
    return replace(as_printed, digital=digital, print_result=result)


def save_map(result: Homogeneity, heightmap: Heightmap, path: str | Path | None = None,
             overwrite: bool = True) -> Figure:
    """The heightmap in grey with each window outlined and coloured by its V; written as PNG to ``path`` if given.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (no pyplot: the backend is left as it was).
    """
    import matplotlib
    from matplotlib.patches import Rectangle

    width, height = heightmap.size_mm
    fig = new_figure(figsize=(6.4, 5))
    ax = fig.subplots()
    ax.imshow(heightmap.heights, cmap="gray", extent=(0, width, height, 0))
    cmap = matplotlib.colormaps["magma"]
    lo, hi = float(result.roughness.min()), float(result.roughness.max())
    norm = matplotlib.colors.Normalize(lo, hi if hi > lo else lo + 1e-9)
    half = result.window_mm / 2
    for x, y, v in zip(result.x_mm, result.y_mm, result.roughness):
        ax.add_patch(Rectangle((x - half, y - half), result.window_mm, result.window_mm, fill=False,
                               edgecolor=cmap(norm(v)), linewidth=0.8, alpha=0.8))
    ax.scatter(result.x_mm, result.y_mm, c=result.roughness, cmap=cmap, norm=norm, s=25, edgecolors="white",
               linewidths=0.4)
    fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="V of the window")
    ax.set(xlabel="x (mm)", ylabel="y (mm)", title=f"{result.verdict}: " + (
        "all below the standard scale" if result.spread_jnd is None else
        f"relative variance {_format(result.relative_variance, '.1e')}, spread {result.spread_jnd:.2f} JND"))
    fig.tight_layout()
    return save_figure(fig, path, 80, overwrite)


def _format(value: float | None, spec: str) -> str:
    return "undefined" if value is None else format(value, spec)
