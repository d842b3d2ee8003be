"""How a texture lies on a surface, without UVs: the texture's height at points of the base surface.

Every mapping answers one question, used both to displace the mesh (``texturing``) and to read back the
texture under a footprint (``feel``): the texture's height (mm, along the outward normal, as the flat
texture would print: bumps up) at points of the untextured base surface with their unit normals.
"""
from __future__ import annotations

from typing import Protocol

import numpy as np


class TextureMapping(Protocol):
    """A texture laid on a surface."""

    @property
    def pixel_mm(self) -> float:
        """The texture's pixel on the surface (mm): the resolution the mesh is refined to."""
        ...

    def heights(self, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """Heights (mm, >= 0, along the outward normal) at ``points`` (n, 3; mm) of the base surface with unit
        ``normals`` (n, 3); returns shape (n,)."""
        ...
