"""Where the skin touches a whole plate, and how far above the texture it stays elsewhere: one spectral contact solve.

The plate, mirrored across its edges, is pressed by the skin layer at the flat state's contact pressure (the
FEM block's at its centre, ``flat_state.block_flat_state``: what one fingertip presses anywhere on the plate),
contact solved on the pixel grid (``contact.solve_contact``). The gap is the skin face's height above the texture
(mm): 0 where it touches. In partial contact the load is shared over the whole plate, as in ``maps``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughness.core.limits import check_size
from roughness.core.reprs import short_repr
from roughness.surface.heightmap import Heightmap

from ..config import SimConfig
from .contact import solve_contact
from .engine import tissue_of
from .flat_state import block_flat_state
from .maps import MAX_MAP_PIXELS
from .modes import GridKey, modes


@dataclass(frozen=True)
class ContactGap:
    """The skin on a plate: touching pixels (rows = y), the gap above the texture elsewhere (mm), the pressure
    (MPa) and how the contact solve ended."""

    in_contact: np.ndarray
    gap_mm: np.ndarray
    pressure_mpa: float
    converged: bool
    message: str

    def __repr__(self) -> str:
        return short_repr(self, f"contact {self.contact_fraction:.3f}", f"largest gap {self.gap_mm.max():.3g} mm",
                          self.message)

    @property
    def contact_fraction(self) -> float:
        return float(self.in_contact.mean())

    def clear_of(self, margin_mm: float) -> np.ndarray:
        """Pixels the skin stays more than ``margin_mm`` above."""
        return self.gap_mm > margin_mm


def contact_gap(heightmap: Heightmap, config: SimConfig | None = None) -> ContactGap:
    """The skin pressed onto the whole of ``heightmap`` (module docstring); InputError above ``MAX_MAP_PIXELS``
    pixels, before any work."""
    config = config or SimConfig()
    check_size("pixels of one contact solve over the plate (use a coarser pixel or a smaller plate)",
               heightmap.heights.size, MAX_MAP_PIXELS, "pixel_mm")
    heights = heightmap.heights
    grid = modes(GridKey(heights.shape, heightmap.pixel_mm, tissue_of(config), config.depth_mm, "mirror"))
    pressure = block_flat_state(config).pressure_mpa
    state = solve_contact(grid, heights, pressure, config.contact == "frictionless")
    gap = grid.inverse(state.face)[2] - heights - state.offset_mm
    gap = np.where(state.in_contact, 0.0, np.maximum(gap, 0.0))
    return ContactGap(state.in_contact.copy(), gap, pressure, state.success, state.message)
