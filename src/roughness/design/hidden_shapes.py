"""Seen but not felt, felt but not seen: the paper's hidden shapes (Tymms et al. 2018, section 6, Fig. 25-26).

A base texture (a periodic tile, laid over the plate) carries a shape (``design.shapes``) in one of two ways:

* ``seen`` (seen, not felt): the skin is pressed onto the whole base plate in one spectral contact solve
  (``simulate.spectral.gap``, at the FEM block's pressure); inside the shape, every pixel the skin stays more than
  ``gap_margin_mm`` above is lowered by ``recess_mm``. Lowering a pixel the skin does not touch leaves the contact
  solution as it was (the same tractions meet every contact condition: the gaps only grow), so the strain, V and
  the contact map do not change; raising the floor or hatching it upward could reach the skin, so the shape is
  recessed. The recesses deepen the shaded pockets at the bumps' feet: the shape shows as a darker area.
  A base with less than ``MIN_CLEAR`` of its area clear of the skin is refused with the least height or lateral
  scale of its tile that makes that room.
* ``felt`` (felt, not seen): inside the shape the tile is scaled so that its V differs by ``felt_jnd`` JND from the
  base's, by the spectral engine, with the mix of lateral and height scale that looks least different
  (``design.look_keeping``), rougher or smoother, whichever looks less different; all candidates are reported.

Every plate is checked by the engines: its spectral roughness map (``simulate.spectral.maps``, footprints
``step_mm`` apart; inside: sampling windows wholly in the shape, or centres in it if none fits; outside: windows
clear of it) gives V inside and outside
and their distance in JND on the spectral scale; the look measure gives the regions' look difference (a band of
``BAND_MM`` either side of the outline left out, where the shadows of one region fall on the other) beside the
same regions on the unchanged base. ``seen`` plates also get the contact map re-solved and compared and the
homogeneity verdict (``design.homogeneity``, each window by the spectral engine). A shape with no disk of the
footprint's width (10 mm) inside it is flagged as too small to feel as a region, with the plate size at which it
would be.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from roughness.core.checks import choice, in_range, non_negative, positive
from roughness.core.errors import InputError
from roughness.core.figures import new_figure
from roughness.core.reprs import short_repr
from roughness.dataset.textures import BumpRecipe, bump_texture
from roughness.perceptual_scale import JndDistance, jnd_distance, load_scale
from roughness.simulate.config import SimConfig
from roughness.simulate.footprints import RoughnessMap
from roughness.simulate.spectral.gap import ContactGap, contact_gap
from roughness.simulate.spectral.maps import spectral_map
from roughness.surface.heightmap import Heightmap

from .evaluation import Evaluator
from .homogeneity import homogeneity
from .look import BAND_MM, MIN_REGION_PIXELS, LookDifference, compare, photograph, region_interiors, render
from .look_keeping import LATERAL_FACTORS, keep_look
from .plate_relief import compose
from .shapes import check_mask, inscribed_width_mm
from .tactile_image import footprint_labels
from .tune import TOLERANCE_JND, scaled, target_of

MODES = ("seen", "felt")
GAP_MARGIN_MM = 0.05  # the skin stays at least this far above every pixel changed on a "seen" plate
RECESS_MM = 0.6
MIN_CLEAR = 0.02  # fraction of the base that must be clear of the skin by the margin to draw a shape there
MATCH_JND = 0.25  # "not felt": V inside and outside within this many JND
FELT_JND = 2.0
STEP_MM = 1.0
ROOM_FACTORS = {"height": (1.0, 3.0), "lateral": (1.0, 3.0)}  # searched for the least change that makes room
ROOM_STEPS = 8  # bisection steps (a factor to within 2/256)

Progress = Callable[[str], None]


def default_base() -> Heightmap:
    """The plates' default base: bumps 1 mm apart, 2.5 mm tall on 1 mm bases (the standard 1.9 mm bases and 1 mm
    heights leave no floor clear of the skin at 10 N: the spectral engine finds full contact)."""
    return bump_texture(BumpRecipe(1.0, height_mm=2.5, base_diameter_mm=1.0))


@dataclass(frozen=True)
class RegionFeel:
    """Spectral V over the footprint positions of a region: mean, its standard error over the positions
    (overlapping footprints are correlated: a lower bound), count."""

    roughness: float
    roughness_stderr: float
    positions: int

    def as_dict(self) -> dict:
        return {"roughness": self.roughness, "roughness_stderr": self.roughness_stderr, "positions": self.positions}


@dataclass(frozen=True)
class Check:
    """One claim about a plate, checked: what, whether it holds, and the number behind it."""

    claim: str
    passed: bool
    value: str

    def as_dict(self) -> dict:
        return {"claim": self.claim, "passed": self.passed, "value": self.value}


@dataclass(frozen=True)
class HiddenPlate:
    """A plate with a hidden shape: relief (mm), shape mask (rows = y), rendered luminance, the measures and checks."""

    mode: str
    heightmap: Heightmap
    mask: np.ndarray
    luminance: np.ndarray
    look: LookDifference  # inside vs outside, this plate
    base_look: LookDifference  # the same regions on the unchanged base plate
    feel_map: RoughnessMap
    inside: RegionFeel | None
    outside: RegionFeel | None
    feel: JndDistance | None  # inside vs outside
    change: dict
    checks: tuple[Check, ...]
    inscribed_mm: float
    footprint_mm: float
    notes: tuple[str, ...] = field(default=())

    def __repr__(self) -> str:
        feel = "no feel distance" if self.feel is None or self.feel.jnd is None else f"feel {self.feel.jnd:+.2f} JND"
        return short_repr(self, self.mode, repr(self.heightmap), feel, f"look {self.look.difference:.2f} look JND",
                          f"{sum(c.passed for c in self.checks)}/{len(self.checks)} checks pass")

    @property
    def feelable(self) -> bool:
        """A footprint-wide disk fits inside the shape."""
        return self.inscribed_mm >= self.footprint_mm

    def summary(self) -> dict:
        return {"mode": self.mode, "width_mm": self.heightmap.size_mm[0], "height_mm": self.heightmap.size_mm[1],
                "pixel_mm": self.heightmap.pixel_mm, "relief_mm": float(np.ptp(self.heightmap.heights)),
                "shape_fraction": float(self.mask.mean()), "inscribed_mm": self.inscribed_mm,
                "feelable_as_region": self.feelable, "change": self.change,
                "look": self.look.as_dict(), "base_look": self.base_look.as_dict(),
                "feel": {"engine": "spectral", "inside": None if self.inside is None else self.inside.as_dict(),
                         "outside": None if self.outside is None else self.outside.as_dict(),
                         "distance": None if self.feel is None else self.feel.as_dict(),
                         "map": self.feel_map.summary()},
                "checks": [c.as_dict() for c in self.checks], "passed": all(c.passed for c in self.checks),
                "notes": list(self.notes)}


def lay(tile: Heightmap, shape: tuple[int, int]) -> Heightmap:
    """The periodic ``tile`` laid over a plate of ``shape`` pixels (its pixel), lowest point at 0."""
    return compose(np.zeros(shape, dtype=int), [tile], tile.pixel_mm)


def hidden_plate(tile: Heightmap, mask: np.ndarray, mode: str, *, gap_margin_mm: float = GAP_MARGIN_MM,
                 recess_mm: float = RECESS_MM, felt_jnd: float = FELT_JND, step_mm: float = STEP_MM,
                 laterals: tuple[float, ...] = LATERAL_FACTORS, evaluator: Evaluator | None = None,
                 config: SimConfig | None = None, progress: Progress | None = None) -> HiddenPlate:
    """The ``mode`` plate (module docstring) of the periodic base ``tile`` (mm) with the shape ``mask`` (plate
    pixels of the tile's size, rows = y); ``laterals``: the lateral factors a felt plate's look-keeping search tries."""
    mode = choice("mode", mode, MODES)
    mask = check_mask(mask)
    config = config or SimConfig()
    evaluator = evaluator or Evaluator(fidelity="spectral")
    say = progress or (lambda _: None)
    base = lay(tile, mask.shape)
    base.require_footprint(config.width_mm)
    inscribed = inscribed_width_mm(mask, tile.pixel_mm)
    notes = []
    if inscribed < config.width_mm:
        notes.append(f"the shape is {inscribed:.1f} mm across at its widest (the largest disk inside it), less than "
                     f"the {config.width_mm:g} mm a fingertip presses: too small to feel as a region; at "
                     f"{config.width_mm / inscribed:.2f} times this size it would be")
    if mode == "seen":
        say("seen: the skin pressed onto the whole base plate (spectral contact)")
        plate, change, gap = _seen(tile, base, mask, non_negative("gap_margin_mm", gap_margin_mm),
                                   positive("recess_mm", recess_mm), config)
    else:
        plate, change = _felt(tile, mask, in_range("felt_jnd", felt_jnd, 0.01, 20.0), laterals, evaluator, say)
        gap = None
    say(f"{mode}: rendering the look and mapping the feel (spectral, footprints {step_mm:g} mm apart)")
    inside_look, outside_look = look_regions(mask, tile.pixel_mm)
    luminance = render(plate)
    look = compare(luminance, inside_look, outside_look, tile.pixel_mm)
    base_look = compare(render(base), inside_look, outside_look, tile.pixel_mm)
    feel_map, map_notes = spectral_map(plate, step_mm, config=config)
    inside, outside, fallback = _region_feel(feel_map, mask, tile.pixel_mm, config)
    if fallback:
        notes.append(fallback)
    distance = None if inside is None or outside is None else jnd_distance(
        load_scale("spectral"), inside.roughness, outside.roughness, inside.roughness_stderr, outside.roughness_stderr)
    if inside is None:
        notes.append("no footprint position has its centre in the shape: the feel inside is not measured")
    if outside is None:
        notes.append(f"no footprint position has its {config.window_mm:g} mm sampling window clear of the shape: the "
                     "feel outside is not measured (a larger plate leaves room)")
    checks = [Check("look: shape and background differ by at least 1 look JND" if mode == "seen" else
                    "look: shape and background differ by less than 1 look JND",
                    (look.difference >= 1) == (mode == "seen"),
                    f"{look.difference:.2f} look JND (base plate, same regions: {base_look.difference:.2f})")]
    feel_jnd = None if distance is None else distance.jnd
    if mode == "seen":
        checks.append(Check(f"feel: V inside and outside within {MATCH_JND:g} JND",
                            feel_jnd is not None and abs(feel_jnd) <= MATCH_JND, _jnd_text(distance)))
        say("seen: the contact re-solved on the finished plate; homogeneity (50 windows, spectral)")
        checks += _seen_checks(plate, gap, config, change, evaluator)
    else:
        wanted = felt_jnd - TOLERANCE_JND
        checks.append(Check(f"feel: V inside and outside at least {felt_jnd:g} JND apart (within tune's "
                            f"{TOLERANCE_JND:g})", feel_jnd is not None and abs(feel_jnd) >= wanted,
                            _jnd_text(distance)))
    return HiddenPlate(mode, plate, mask, luminance, look, base_look, feel_map, inside, outside, distance, change,
                       tuple(checks), inscribed, config.width_mm, tuple(notes + map_notes))


def _jnd_text(distance: JndDistance | None) -> str:
    if distance is None or distance.jnd is None:
        return "not measured"
    se = "" if distance.jnd_stderr is None else f" ± {distance.jnd_stderr:.2f}"
    return f"{distance.jnd:+.2f}{se} JND (spectral map)"


def _seen(tile: Heightmap, base: Heightmap, mask: np.ndarray, margin_mm: float, recess_mm: float,
          config: SimConfig) -> tuple[Heightmap, dict, ContactGap]:
    """The seen-not-felt plate: clear pixels inside the shape recessed; InputError if the base has no room."""
    gap = contact_gap(base, config)
    clear = gap.clear_of(margin_mm)
    if clear.mean() < MIN_CLEAR:
        raise InputError(_no_room(tile, gap, clear.mean(), margin_mm, config), parameter="texture")
    changed = mask & clear
    if not changed.any():
        raise InputError(f"the skin comes within {margin_mm:g} mm of every pixel inside the shape: nothing in it "
                         "can be changed unfelt", parameter="mask")
    heights = np.where(changed, base.heights - recess_mm, base.heights)
    plate = Heightmap(heights - heights.min(), base.pixel_mm)
    change = {"how": f"pixels inside the shape the skin stays more than {margin_mm:g} mm above, recessed by "
                     f"{recess_mm:g} mm", "gap_margin_mm": margin_mm, "recess_mm": recess_mm,
              "base_contact_fraction": gap.contact_fraction, "clear_fraction": float(clear.mean()),
              "changed_fraction_of_shape": float(changed.sum() / mask.sum()),
              "contact_solve": gap.message}
    return plate, change, gap


def _no_room(tile: Heightmap, gap: ContactGap, clear: float, margin_mm: float, config: SimConfig) -> str:
    """Why a base is refused for a seen-not-felt plate, and the least change of its tile that makes room."""
    options = []
    for knob, (lo, hi) in ROOM_FACTORS.items():
        factor = _least_room(tile, knob, lo, hi, margin_mm, config)
        what = "heights" if knob == "height" else "lateral size (sparser, wider bumps)"
        options.append(f"{what} x {factor:.2f}" if factor is not None else f"no {what} x {hi:g} or less")
    return (f"the skin touches {100 * gap.contact_fraction:.1f}% of the base texture at {config.force_n:g} N and stays "
            f"more than {margin_mm:g} mm above only {100 * clear:.2f}% of it (at least {100 * MIN_CLEAR:g}% needed): "
            "nothing can be drawn where it is not felt. Least change of the texture that makes room: "
            + "; or ".join(options))


def _least_room(tile: Heightmap, knob: str, lo: float, hi: float, margin_mm: float, config: SimConfig) -> float | None:
    """The least scale factor of ``tile`` by ``knob`` within (lo, hi] that leaves ``MIN_CLEAR`` of it clear."""
    def room(factor: float) -> bool:
        return contact_gap(scaled(tile, knob, factor), config).clear_of(margin_mm).mean() >= MIN_CLEAR

    try:
        if not room(hi):
            return None
    except InputError:  # too tall for linear elasticity at the far end
        return None
    for _ in range(ROOM_STEPS):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if room(mid) else (mid, hi)
    return hi


def _seen_checks(plate: Heightmap, before: ContactGap, config: SimConfig, change: dict,
                 evaluator: Evaluator) -> list[Check]:
    """The contact map re-solved on the finished plate against the base's (unchanged within the margin: no pixel
    changes between touching and clear by more than the margin), and the homogeneity verdict."""
    after = contact_gap(plate, config)
    flipped = after.in_contact != before.in_contact
    margin = change["gap_margin_mm"]
    beyond = int(np.count_nonzero(flipped & ((before.gap_mm > margin) | (after.gap_mm > margin))))
    change["contact_pixels_changed"] = int(flipped.sum())
    found = homogeneity(plate, engine="fem", evaluator=evaluator)
    spread = "no spread" if found.range_jnd is None else f"10-90% range {found.range_jnd:.2f} JND"
    return [Check(f"contact: the contact map unchanged within the {margin:g} mm margin", beyond == 0,
                  f"{int(flipped.sum())} of {plate.heights.size:,} pixels changed between touching and clear, "
                  f"{beyond} of them by more than the margin (contact {before.contact_fraction:.4f} -> "
                  f"{after.contact_fraction:.4f})"),
            Check("homogeneity: verdict homogeneous", found.verdict == "homogeneous",
                  f"{found.verdict}, {spread} over {len(found.roughness)} windows (spectral)")]


def _felt(tile: Heightmap, mask: np.ndarray, felt_jnd: float, laterals: tuple[float, ...], evaluator: Evaluator,
          say: Progress) -> tuple[Heightmap, dict]:
    """The felt-not-seen plate: inside the shape the tile rougher or smoother by ``felt_jnd``, by the mix of lateral
    and height scale that looks least different (``look_keeping``), whichever direction looks less different."""
    kept, refused = {}, {}
    for steps in (felt_jnd, -felt_jnd):
        try:
            kept[steps] = keep_look(tile, target_of(evaluator, jnd=steps, heightmap=tile, tile=True), evaluator,
                                    tile=True, laterals=laterals, progress=lambda line, s=steps: say(f"felt ({s:+g} JND): {line}"))
        except InputError as err:
            refused[steps] = str(err)
    if not kept:
        raise InputError(f"neither {felt_jnd:g} JND rougher nor smoother is reachable from the base texture: "
                         + "; ".join(refused.values()), parameter="felt_jnd")
    steps = min(kept, key=lambda s: kept[s].chosen.look.difference)
    chosen = kept[steps].chosen
    plate = compose(mask.astype(int), [tile, kept[steps].heightmap], tile.pixel_mm)
    change = {"how": f"inside the shape the texture {abs(steps):g} JND {'rougher' if steps > 0 else 'smoother'} "
                     f"(spectral engine): lateral x {chosen.lateral:.4g}, height x {chosen.height or 1:.4g}, the "
                     "mix that looks least different", "target_jnd": steps,
              **{f"{s:+g} JND": kept[s].summary() for s in kept}, **{f"{s:+g} JND refused": refused[s] for s in refused}}
    return plate, change


def look_regions(mask: np.ndarray, pixel_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """Inside and outside the shape, a band of ``BAND_MM`` either side of the outline left out (each region whole
    if the band would leave too little of it)."""
    outside, inside = region_interiors(mask.astype(int), pixel_mm, 2, BAND_MM)
    return ((inside if inside.sum() >= MIN_REGION_PIXELS else mask),
            (outside if outside.sum() >= MIN_REGION_PIXELS else ~mask))


def _region_feel(feel_map: RoughnessMap, mask: np.ndarray, pixel_mm: float,
                 config: SimConfig) -> tuple[RegionFeel | None, RegionFeel | None, str]:
    """V over the positions whose sampling window lies wholly in the shape (if none: those centred in it), over
    those whose window is clear of it, and a note when the inside fell back to centres."""
    xs, ys = feel_map.x_mm, feel_map.y_mm
    windows = footprint_labels(mask.astype(int), pixel_mm, xs, ys, config.window_mm)
    inside, note = windows == 1, ""
    if not inside.any():
        rows = np.clip((ys / pixel_mm).astype(int), 0, mask.shape[0] - 1)
        cols = np.clip((xs / pixel_mm).astype(int), 0, mask.shape[1] - 1)
        inside = mask[np.ix_(rows, cols)]
        note = (f"no {config.window_mm:g} mm sampling window fits inside the shape: the feel inside is V at the "
                "positions centred in it (their windows take in the background too)")

    def region(where: np.ndarray) -> RegionFeel | None:
        v = feel_map.roughness[where]
        if v.size == 0:
            return None
        se = float(v.std(ddof=1) / np.sqrt(v.size)) if v.size > 1 else 0.0
        return RegionFeel(float(v.mean()), se, int(v.size))

    return region(inside), region(windows == 0), note


def figure(plate: HiddenPlate):
    """The paper's Fig. 25 for one plate: the rendered look, the heightmap and the feel (spectral V) map side by
    side, the shape's outline on each."""
    fig = new_figure(figsize=(15, 5), layout="constrained")
    axes = fig.subplots(1, 3)
    w, h = plate.heightmap.size_mm
    extent = (0, w, h, 0)
    axes[0].imshow(photograph(plate.luminance), cmap="gray", vmin=0, vmax=1, extent=extent, interpolation="antialiased")
    axes[0].set_title(f"look (rendered, as photographed): {plate.look.difference:.2f} look JND")
    shown = axes[1].imshow(plate.heightmap.heights, cmap="viridis", extent=extent)
    fig.colorbar(shown, ax=axes[1], label="height (mm)", shrink=0.8)
    axes[1].set_title(f"heightmap, relief {np.ptp(plate.heightmap.heights):.2f} mm")
    m = plate.feel_map
    step = m.x_mm[1] - m.x_mm[0] if len(m.x_mm) > 1 else 1.0
    shown = axes[2].imshow(m.roughness, cmap="magma", extent=(m.x_mm[0] - step / 2, m.x_mm[-1] + step / 2,
                                                               m.y_mm[-1] + step / 2, m.y_mm[0] - step / 2))
    axes[2].set_xlim(0, w)
    axes[2].set_ylim(h, 0)
    fig.colorbar(shown, ax=axes[2], label="V (spectral)", shrink=0.8)
    feel = "not measured" if plate.feel is None or plate.feel.jnd is None else f"{plate.feel.jnd:+.2f} JND"
    axes[2].set_title(f"feel (V map): {feel}")
    x = (np.arange(plate.mask.shape[1]) + 0.5) * plate.heightmap.pixel_mm
    y = (np.arange(plate.mask.shape[0]) + 0.5) * plate.heightmap.pixel_mm
    for ax in axes:
        ax.contour(x, y, plate.mask.astype(float), levels=[0.5], colors="cyan", linewidths=0.8)
        ax.set_xlabel("x (mm)")
    axes[0].set_ylabel("y (mm)")
    title = "seen, not felt" if plate.mode == "seen" else "felt, not seen"
    fig.suptitle(f"{title}: {sum(c.passed for c in plate.checks)} of {len(plate.checks)} checks pass")
    return fig
