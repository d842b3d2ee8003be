"""Every parametric texture family by name: the natural-like ones (natural.py) and the engineered and
composite ones (engineered.py), with the parameter ranges a recipe samples by default (bumps:
recipe.BUMP_RANGES) and the wider limits a recipe's own ranges and a direct call may reach."""
from __future__ import annotations

from collections.abc import Callable

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from . import engineered, natural
from .grid import PIXEL_MM, SIZE_MM

FAMILIES: dict[str, Callable[..., Heightmap]] = {**natural.FAMILIES, **engineered.FAMILIES}
PARAMETER_RANGES: dict[str, dict[str, tuple]] = {**natural.PARAMETER_RANGES, **engineered.PARAMETER_RANGES}
PARAMETER_LIMITS: dict[str, dict[str, tuple]] = {**natural.PARAMETER_LIMITS, **engineered.PARAMETER_LIMITS}


def make(family: str, seed: int = 0, size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, **params) -> Heightmap:
    """Heightmap (mm) of a texture family by name; InputError names a bad family or parameter."""
    if family not in FAMILIES:
        raise InputError(f"unknown texture family {family!r}; valid families: {', '.join(FAMILIES)}")
    unknown = sorted(set(params) - set(PARAMETER_RANGES[family]))
    if unknown:
        raise InputError(f"unknown {family} parameter(s) {', '.join(unknown)}; "
                         f"valid parameters: {', '.join(PARAMETER_RANGES[family])}")
    return FAMILIES[family](size_mm=size_mm, pixel_mm=pixel_mm, seed=seed, **params)
