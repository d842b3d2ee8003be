"""A picture's flat colours, found with a colour tolerance: JPEG noise and anti-aliased edges join the nearest.

Colours are compared in CIELAB (D65), where a distance (Delta E 1976) of about 2.3 is just noticeable to the
eye and flat colours a designer tells apart are tens of units apart. A pixel is *flat* when its four
neighbours are all within the tolerance of it: inside a region, not on an edge whose blend steps exceed the
tolerance (in a picture of one or two rows or columns where none is, every pixel counts as flat). Flat pixels'
colours are grouped greedily: the most frequent ungrouped colour leads a group of
every ungrouped colour within the tolerance of it, until all are grouped. Groups covering at least
``min_fraction`` of the picture's pixels are its flat colours; their centres are refined (a few k-means steps
on the flat pixels), and every pixel, edges included, joins the nearest centre. Pixels farther than the
tolerance from their centre are *reassigned* (anti-aliased edges, compression ringing); pixels within it whose
colour differs from their centre's are *merged* (noise).

A picture drawn with flat fills (at least CLEAN_SHARE of its pixels have four neighbours of exactly their colour)
keeps its exact flat colours however close (a logo's shades): each colour with ``min_fraction`` of such pixels, at
least DISTINCT_DELTA_E from every larger one, leads a group first and is never merged with another such colour.
Centres refined to within the tolerance of each other are otherwise merged. A thin stroke's pixels (a colour drawn
exactly over ``min_fraction`` of the picture, its two neighbours across or down exactly its colour) count as flat.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError

MIN_COLOUR_FRACTION = 0.005
TOLERANCE = 20.0  # Delta E (CIELAB 1976): JPEG noise inside flat regions, quality 75 (examples/design/shapes.png)
MAX_GROUPS = 256  # more groups than this: not a flat-colour picture (a photograph), refused
REFINE_STEPS = 5
FLAT_STEP = 0.5  # a flat pixel's neighbours are within this fraction of the tolerance of it
BLEND_FRACTION = 0.025  # groups smaller than this share of the flat pixels may be blends of two larger ones
CLEAN_SHARE = 0.5  # a picture this share of whose pixels have four exactly like neighbours is drawn with flat fills
DISTINCT_DELTA_E = 5.0  # exact flat colours of a clean picture this far apart are distinct (about 2 JND of the eye)
STRIP_PIXELS = 1 << 20  # pixels per strip when looking for flat pixels (bounds the working memory)


@dataclass(frozen=True)
class PictureColours:
    """A picture's flat colours (n, 3) uint8 RGB, lightest first, and what the clustering did."""

    colours: np.ndarray
    labels: np.ndarray  # (h, w) index of each pixel's flat colour
    tolerance: float  # Delta E
    distinct: int  # distinct colours in the picture
    merged: int  # pixels within the tolerance of their colour but not equal to it (noise)
    reassigned: int  # pixels farther than the tolerance from every flat colour, given the nearest (edges)

    @property
    def pixels(self) -> int:
        return int(self.labels.size)

    def clustered(self) -> np.ndarray:
        """The picture as clustered: each pixel in its flat colour (h, w, 3) uint8."""
        return self.colours[self.labels]

    def describe(self) -> str:
        """One line: what was clustered into what."""
        share = 100 * self.reassigned / self.pixels
        return (f"{self.distinct:,} distinct colours clustered into {len(self.colours)} flat colours "
                f"(tolerance Delta E {self.tolerance:g}): {self.merged:,} pixels within the tolerance merged, "
                f"{self.reassigned:,} ({share:.1f}%) farther than it (edges, compression) reassigned to the nearest")

    def summary(self) -> dict:
        return {"tolerance_delta_e": self.tolerance, "distinct_colours": self.distinct,
                "flat_colours": len(self.colours), "pixels": self.pixels, "pixels_merged": self.merged,
                "pixels_reassigned": self.reassigned}


def lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB (D65) of sRGB colours (..., 3) uint8."""
    from skimage.color import rgb2lab

    return rgb2lab(np.asarray(rgb, dtype=np.uint8)[None]).reshape(np.shape(rgb)).astype(np.float32)


def cluster_colours(rgb: np.ndarray, tolerance: float = TOLERANCE, min_fraction: float = MIN_COLOUR_FRACTION,
                    source: str = "the picture") -> PictureColours:
    """The picture's flat colours within ``tolerance`` (Delta E) and each pixel's (module docstring).

    ``source`` names the picture in errors: fewer than 2 flat colours, or more than MAX_GROUPS groups.
    """
    tolerance = positive("colour_tolerance", tolerance)
    flat = rgb.reshape(-1, 3)
    codes = (flat[:, 0].astype(np.int32) << 16) | (flat[:, 1].astype(np.int32) << 8) | flat[:, 2]
    counts = np.bincount(codes, minlength=1 << 24)
    present = np.flatnonzero(counts)
    colours = np.column_stack([present >> 16, (present >> 8) & 255, present & 255]).astype(np.uint8)
    lookup = np.zeros(1 << 24, dtype=np.int32)  # colour code -> index in `present`
    lookup[present] = np.arange(len(present), dtype=np.int32)
    index = lookup[codes].reshape(rgb.shape[:2])
    del lookup, codes
    colour_lab = lab(colours)
    common = counts[present] >= min_fraction * index.size  # colours drawn exactly over a share of the picture
    flat_pixels = _flat_pixels(index, colour_lab, tolerance * FLAT_STEP, common)
    if min(index.shape) < 3 and not flat_pixels.any():  # one or two rows or columns: no pixel inside the picture
        flat_pixels[:] = True  # for the four-neighbour test to tell a region's inside from its edge, so all count
    weight = np.bincount(index[flat_pixels], minlength=len(present)).astype(float)
    seeds = _exact_colours(index, colour_lab, min_fraction * index.size)
    centres, seeded = _groups(colours, colour_lab, weight, tolerance, min_fraction * index.size, source, seeds)
    if len(centres) < 2:
        _too_few(colours, counts[present], centres, weight.sum() / index.size, tolerance, min_fraction, source)
    for _ in range(REFINE_STEPS):  # k-means on the flat pixels, from the groups' leaders
        nearest = _nearest(colour_lab, centres)
        centres = np.array([np.average(colour_lab[nearest == i], axis=0, weights=weight[nearest == i])
                            if weight[nearest == i].sum() > 0 else centres[i] for i in range(len(centres))])
    nearest = _nearest(colour_lab, centres)
    centres = _merge_close(centres, seeded, colour_lab, weight, nearest, tolerance)
    nearest = _nearest(colour_lab, centres)
    if len(np.unique(nearest)) < len(centres):  # two centres refined onto one: one colour
        centres = centres[np.unique(nearest)]
        nearest = _nearest(colour_lab, centres)
        if len(centres) < 2:
            _too_few(colours, counts[present], centres, weight.sum() / index.size, tolerance, min_fraction, source)
    members = [nearest == i for i in range(len(centres))]
    rgb_centres = np.array([np.round(np.average(colours[m].astype(float), axis=0,
                                                weights=weight[m] if weight[m].sum() > 0 else counts[present][m]))
                            for m in members]).astype(np.uint8)
    order = np.argsort(-(rgb_centres.astype(float) @ [0.299, 0.587, 0.114]), kind="stable")
    rank = np.empty(len(order), dtype=np.intp)
    rank[order] = np.arange(len(order))
    far = np.linalg.norm(colour_lab - centres[nearest], axis=1) > tolerance
    exact = (colours == rgb_centres[nearest]).all(axis=1)
    pixel_counts = counts[present]
    return PictureColours(rgb_centres[order], rank[nearest][index], tolerance, len(present),
                          int(pixel_counts[~far & ~exact].sum()), int(pixel_counts[far].sum()))


def _exact_colours(index: np.ndarray, colour_lab: np.ndarray, min_pixels: float) -> np.ndarray:
    """Indices of a clean picture's exact flat colours, most pixels first: in a picture at least CLEAN_SHARE of
    whose pixels have four neighbours of exactly their colour (drawn with flat fills, not compressed), the colours
    with at least ``min_pixels`` such pixels, each at least DISTINCT_DELTA_E from every one before it (none in
    any other picture)."""
    same = np.zeros(index.shape, dtype=bool)
    same[1:-1, 1:-1] = ((index[1:-1, 1:-1] == index[:-2, 1:-1]) & (index[1:-1, 1:-1] == index[2:, 1:-1])
                        & (index[1:-1, 1:-1] == index[1:-1, :-2]) & (index[1:-1, 1:-1] == index[1:-1, 2:]))
    if same.mean() < CLEAN_SHARE:
        return np.array([], dtype=int)
    counts = np.bincount(index[same], minlength=len(colour_lab))
    kept: list[int] = []
    for i in np.argsort(-counts, kind="stable"):
        if counts[i] < min_pixels:
            break
        if all(np.linalg.norm(colour_lab[i] - colour_lab[k]) >= DISTINCT_DELTA_E for k in kept):
            kept.append(int(i))
    return np.array(kept, dtype=int)


def _merge_close(centres: np.ndarray, seeded: np.ndarray, colour_lab: np.ndarray, weight: np.ndarray,
                 nearest: np.ndarray, tolerance: float) -> np.ndarray:
    """Centres (Lab) with any two refined to within ``tolerance`` of each other merged (weighted by their flat
    pixels): they are one colour by the tolerance's definition, unless both are exact flat colours (``seeded``)."""
    sizes = [float(weight[nearest == i].sum()) for i in range(len(centres))]
    seeded = list(seeded)
    centres = [c for c in centres]
    while len(centres) > 1:
        d = np.linalg.norm(np.array(centres)[:, None] - np.array(centres)[None], axis=-1)
        d[np.diag_indices(len(centres))] = np.inf
        both = np.array(seeded)[:, None] & np.array(seeded)[None]
        d[both] = np.inf
        a, b = np.unravel_index(np.argmin(d), d.shape)
        if d[a, b] > tolerance:
            break
        total = sizes[a] + sizes[b]
        merged = (centres[a] * sizes[a] + centres[b] * sizes[b]) / total if total > 0 else centres[a]
        centres[a], sizes[a], seeded[a] = merged, total, seeded[a] or seeded[b]
        del centres[b], sizes[b], seeded[b]
    return np.array(centres)


def _flat_pixels(index: np.ndarray, colour_lab: np.ndarray, tolerance: float, common: np.ndarray) -> np.ndarray:
    """Pixels whose four neighbours are within ``tolerance`` of them, or whose colour is ``common`` (by colour
    index) and whose two neighbours across or two neighbours down are exactly that colour (a thin line's pixels: no
    pixel of a stroke 1 or 2 pixels wide has four like neighbours), in strips of rows (bounded memory)."""
    h, w = index.shape
    flat = np.ones((h, w), dtype=bool)
    line = np.zeros((h, w), dtype=bool)
    rows = max(1, STRIP_PIXELS // w)
    for top in range(0, h, rows):
        codes = index[top:top + rows + 1]  # one more row: the last row's lower neighbour
        block = colour_lab[codes]
        across = np.linalg.norm(block[:, 1:] - block[:, :-1], axis=-1) > tolerance
        down = np.linalg.norm(block[1:] - block[:-1], axis=-1) > tolerance
        view = flat[top:top + len(block)]
        view[:, 1:] &= ~across
        view[:, :-1] &= ~across
        view[1:] &= ~down
        view[:-1] &= ~down
        same = line[top:top + len(block)]
        same[:, 1:-1] |= (codes[:, 1:-1] == codes[:, :-2]) & (codes[:, 1:-1] == codes[:, 2:])
        same[1:-1] |= (codes[1:-1] == codes[:-2]) & (codes[1:-1] == codes[2:])
    return flat | line & common[index]


def _groups(colours: np.ndarray, colour_lab: np.ndarray, weight: np.ndarray, tolerance: float, min_pixels: float,
            source: str, seeds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Leaders (Lab) of the groups of flat colours covering at least ``min_pixels`` flat pixels, less blends:
    a group smaller than BLEND_FRACTION of the flat pixels whose leader is within the tolerance of a mix of
    two larger groups' leaders (an edge band, wide where a picture was enlarged smoothly); and which were
    ``seeds`` (exact flat colours: they lead the first groups, each of the colours within the tolerance nearest
    to it)."""
    ungrouped = weight > 0
    leaders, sizes, leads = [], [], []
    if len(seeds):
        d = np.linalg.norm(colour_lab[:, None] - colour_lab[seeds][None], axis=-1)
        nearest_seed = np.argmin(d, axis=1)
        for k, lead in enumerate(seeds):
            near = ungrouped & (nearest_seed == k) & (d[:, k] <= tolerance)
            near[lead] = True
            leaders.append(colour_lab[lead])
            leads.append(int(lead))
            sizes.append(weight[near].sum())
        ungrouped &= ~((d <= tolerance).any(axis=1))
        ungrouped[seeds] = False
    while ungrouped.any():
        if len(leaders) == MAX_GROUPS:
            raise InputError(f"{source} is not a picture of flat colours: more than {MAX_GROUPS} groups of colours "
                             f"Delta E {tolerance:g} apart (a photograph?); a tactile image needs a few flat colours, "
                             "one per region (or raise --colour-tolerance)", parameter="colour_tolerance")
        lead = int(np.argmax(np.where(ungrouped, weight, -1)))
        near = ungrouped & (np.linalg.norm(colour_lab - colour_lab[lead], axis=1) <= tolerance)
        leaders.append(colour_lab[lead])
        leads.append(lead)
        sizes.append(weight[near].sum())
        ungrouped &= ~near
    total = weight.sum()
    kept: list[int] = []
    for i in np.argsort(sizes)[::-1]:
        if sizes[i] < min_pixels:
            break
        if sizes[i] >= BLEND_FRACTION * total or not _is_blend(colours[leads[i]], [colours[leads[k]] for k in kept],
                                                                colour_lab[leads[i]], tolerance):
            kept.append(i)
    return np.array([leaders[i] for i in kept]).reshape(-1, 3), np.array([i < len(seeds) for i in kept], dtype=bool)


def _is_blend(colour: np.ndarray, others: list[np.ndarray], colour_lab: np.ndarray, tolerance: float) -> bool:
    """Whether ``colour`` is within ``tolerance`` (Delta E) of a mix of two of ``others`` (mixed in sRGB values,
    as resampling and anti-aliasing mix them)."""
    mix = np.linspace(0, 1, 33)[:, None]
    for a in range(len(others)):
        for b in range(a + 1, len(others)):
            line = np.round(others[a] * (1 - mix) + others[b] * mix).astype(np.uint8)
            if np.linalg.norm(lab(line) - colour_lab, axis=1).min() <= tolerance:
                return True
    return False


def _nearest(colour_lab: np.ndarray, centres: np.ndarray, chunk: int = 1 << 16) -> np.ndarray:
    """Index of the nearest centre of each colour, in chunks of colours (bounded memory)."""
    return np.concatenate([np.argmin(((colour_lab[i:i + chunk, None, :] - centres[None]) ** 2).sum(-1), axis=1)
                           for i in range(0, len(colour_lab), chunk)])


def hex_colour(rgb) -> str:
    """#rrggbb of an RGB triple."""
    r, g, b = (int(c) for c in rgb)
    return f"#{r:02x}{g:02x}{b:02x}"


def _too_few(colours: np.ndarray, counts: np.ndarray, centres: np.ndarray, flat_share: float, tolerance: float,
             min_fraction: float, source: str) -> None:
    shown = colours[np.argsort(-counts, kind="stable")[:5]]
    raise InputError(
        f"{source} has fewer than 2 flat colours: {len(colours)} distinct colour(s) "
        f"({', '.join(hex_colour(c) for c in shown)}{', ...' if len(colours) > 5 else ''}), "
        f"{len(centres)} group(s) within Delta E {tolerance:g} covering >= {100 * min_fraction:g}% of its pixels, "
        f"{100 * flat_share:.0f}% of its pixels in flat areas; a tactile image needs a picture with 2 or more flat "
        "colours, one per region (e.g. an 8-bit RGB or greyscale PNG, or shapes on a transparent background; "
        "--colour-tolerance: lower it to tell close colours apart, raise it for a noisy picture)", parameter="image")
