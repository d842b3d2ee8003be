"""predict --json's "look": how each texture predicted looks (``roughness.design.look``) over the skin footprint its
V is of, and with --printer how the print looks beside the digital texture.

The footprint (10 mm square at --centre, repeated with --tile) is cut from the heightmap on its own pixels, or on
``LOOK_PIXEL_MM`` pixels where those are finer (box-averaged: ``surrogate.patch``), and rendered. Numpy only: no
torch, no scipy.stats (``predict`` answers in milliseconds; a render of 200 x 200 pixels takes about 10 ms).
"""
from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Iterator
from typing import TYPE_CHECKING

from roughness.surface.heightmap import Heightmap

if TYPE_CHECKING:
    from roughness.design.look import RegionLook

LOOK_PIXEL_MM = 0.05  # no finer: the eye at 400 mm resolves about 0.1 mm, and the render's cost grows as pixel^-3


class Looks:
    """The look of each (name, heightmap) that ``named`` passes on, made by ``take`` in the same order once its
    prediction is shown (so that the engines' checks of the input come first).

    ``pairs``: the heightmaps come as (digital, its print) pairs (``printer.PrintPairs``): each print's look also
    carries ``print_look_difference``, the print beside the digital texture (the reference of its contrasts).
    """

    def __init__(self, centre_mm: tuple[float, float] | None, tile: bool, pairs: bool) -> None:
        self.centre_mm, self.tile, self.pairs = centre_mm, tile, pairs
        self._heightmaps: deque[Heightmap] = deque()  # passed on, look not yet taken
        self._digital: RegionLook | None = None  # pairs: the digital texture footprint's look, until its print's turn

    def named(self, named: Iterable[tuple[str, Heightmap]]) -> Iterator[tuple[str, Heightmap]]:
        """``named``, unchanged, each heightmap kept for ``take``."""
        for name, hm in named:
            self._heightmaps.append(hm)
            yield name, hm

    def take(self) -> dict:
        """The next heightmap's look, as JSON fields."""
        from roughness.design.look import compare_looks, render, texture_look, whole_look

        window = self.window(self._heightmaps.popleft())
        luminance = render(window)  # once: the look, and with a printer the comparison of print and digital
        look = {"look": {"window_mm": window.size_mm[0], "pixel_mm": window.pixel_mm,
                         **texture_look(window, luminance).as_dict()}}
        if self.pairs and self._digital is not None:
            look["print_look_difference"] = compare_looks(whole_look(window, luminance), self._digital).as_dict()
            self._digital = None
        elif self.pairs:
            self._digital = whole_look(window, luminance)
        return look

    def window(self, hm: Heightmap) -> Heightmap:
        """The skin footprint of ``hm`` (mm) that its V is of, on pixels no finer than LOOK_PIXEL_MM."""
        from roughness.surrogate.patch import FOOTPRINT_MM, footprint_patch

        pixel_mm = max(hm.pixel_mm, LOOK_PIXEL_MM)
        return Heightmap(footprint_patch(hm, self.centre_mm, self.tile, pixel_mm, FOOTPRINT_MM), pixel_mm)
