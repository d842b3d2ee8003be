"""Every texture the project can make, by name: standard bumps, flat tops, bump recipes, and the
natural-like, engineered and composite families (families.py)."""
from __future__ import annotations

from dataclasses import fields

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap, flat

from . import families, textures
from .grid import PIXEL_MM, SIZE_MM, check_seed, map_side


def names() -> list[str]:
    """Named textures and family names accepted by ``make_texture``."""
    return textures.texture_names() + ["bumps"] + list(families.FAMILIES)


def parse_params(items: list[str]) -> dict[str, float | str]:
    """``key=value`` strings to a dict; numbers become floats."""
    out: dict[str, float | str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise InputError(f"parameter {item!r} is not of the form key=value")
        try:
            out[key] = float(value)
        except ValueError:
            out[key] = value
    return out


def make_texture(name: str, seed: int = 0, size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM,
                 params: dict | None = None) -> tuple[Heightmap, dict]:
    """The heightmap (mm) and its recipe (JSON-ready) for a texture name or family.

    An error about one of ``params`` names the parameter ``params``.
    """
    check_seed(seed)
    map_side(size_mm, pixel_mm)
    params = dict(params or {})
    try:
        return _make(name, seed, size_mm, pixel_mm, params), {"name": name, "seed": seed, "size_mm": size_mm,
                                                               "pixel_mm": pixel_mm, "params": params}
    except InputError as err:
        if err.parameter in params:
            raise InputError(str(err), parameter="params") from None
        raise


def _make(name: str, seed: int, size_mm: float, pixel_mm: float, params: dict) -> Heightmap:
    if name in families.FAMILIES:
        return families.make(name, seed=seed, size_mm=size_mm, pixel_mm=pixel_mm, **params)
    if name == "bumps":
        allowed = {f.name for f in fields(textures.BumpRecipe)} - {"size_mm", "pixel_mm", "seed"}
        unknown = sorted(set(params) - allowed)
        if unknown or "lambda_mm" not in params:
            raise InputError(f"bumps needs lambda_mm=...; valid parameters: {', '.join(sorted(allowed))}"
                             + (f" (unknown: {', '.join(unknown)})" if unknown else ""), "params")
        r = textures.BumpRecipe(size_mm=size_mm, pixel_mm=pixel_mm, seed=seed, **params)
        return textures.bump_texture(r)
    if params:
        raise InputError(f"{name} takes no parameters (use 'bumps' with lambda_mm=... for custom bumps)", "params")
    if name.startswith("standard-"):
        lam = _number(name, "standard-")
        return textures.standard_texture(lam, seed=seed, size_mm=size_mm, pixel_mm=pixel_mm)
    if name.startswith("flattop-"):
        d = _number(name, "flattop-")
        return textures.flat_top_texture(d, seed=seed, size_mm=size_mm, pixel_mm=pixel_mm)
    if name == "flat":
        return flat(size_mm, pixel_mm)
    raise InputError(f"unknown texture {name!r}; valid: {', '.join(names())}")


def _number(name: str, prefix: str) -> float:
    try:
        return float(name[len(prefix):])
    except ValueError:
        raise InputError(f"unknown texture {name!r}; valid: {', '.join(names())}") from None
