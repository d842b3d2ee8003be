"""Heightmaps given to the Python API, checked as the command line checks the files it loads (``loading``).

Every public function that takes a heightmap (``roughness.predict``, ``predict_map``, ``fem_roughness``, the
design tools) takes it through ``heightmap_argument``: an array (or nested list) becomes a ``Heightmap``
(``as_heightmap``: 2-D real numbers, a pixel size, missing points refused), and a ``Heightmap`` or array
whose relief, slope or pixel size look like metres or micrometres is refused by the unit check
(``units.check_units``) unless ``units_ok`` confirms that the numbers are millimetres. Both happen before any
engine runs.
"""
from __future__ import annotations

import math

import numpy as np

from roughness.core.checks import flag
from roughness.core.errors import InputError

from .cleanup import MAX_FILL_FRACTION, Cleanup, clean
from .heightmap import Heightmap, pixel_size, with_missing
from .units import check_units


def heightmap_argument(value: object, pixel_mm: float | None = None, parameter: str = "heightmap",
                       units_ok: bool = False, source: str | None = None) -> Heightmap:
    """``value`` (a Heightmap, or heights in mm with ``pixel_mm``) as a Heightmap whose numbers look like mm.

    ``parameter``: the caller's name for ``value`` (in errors about it); ``source``: how the unit check names the
    map (default: ``parameter``). InputError naming ``units_ok`` for implausible units unless ``units_ok``.
    """
    units_ok = flag("units_ok", units_ok)
    hm = as_heightmap(value, pixel_mm, parameter)
    check_units(hm, source or parameter, units_ok)
    return hm


def as_heightmap(heights: Heightmap | np.ndarray, pixel_mm: float | None = None, parameter: str = "heights", *,
                 fill: bool = False, max_fill: float | None = None) -> Heightmap:
    """A ``Heightmap`` from a ``Heightmap`` or a 2-D array of heights (mm) on square pixels of ``pixel_mm`` (mm).

    Parameters
    ----------
    heights : Heightmap or array_like, shape (ny, nx)
        Heights in mm; row index -> y, column -> x (a NumPy array, a masked array or a nested list of rows).
        NaN and masked points are missing data.
    pixel_mm : float, optional
        Pixel size in mm: required for an array; for a ``Heightmap`` it must match its own (or be None).
    parameter : str
        The caller's name for ``heights``, used in error messages.
    fill : bool
        Interpolate missing points harmonically (``roughness.surface.cleanup``, the command line's ``--fill``);
        default: refuse them.
    max_fill : float, optional
        ``fill`` refuses maps with more missing than this fraction (default: ``cleanup.MAX_FILL_FRACTION``).

    Raises
    ------
    InputError
        An array without ``pixel_mm``, a pixel size that contradicts the heightmap's, anything other than a 2-D
        array of real numbers, missing points without ``fill``, infinite heights.
    """
    if isinstance(heights, Heightmap):
        if pixel_mm is not None and not math.isclose(pixel_size(pixel_mm), heights.pixel_mm, rel_tol=1e-9):
            raise InputError(f"pixel_mm={pixel_mm:g} contradicts the heightmap's own pixel of {heights.pixel_mm:g} mm; "
                             "give pixel_mm only with an array", parameter="pixel_mm")
        return heights
    if isinstance(heights, (str, bytes)) or not hasattr(heights, "__array__") and not isinstance(heights, (list, tuple)):
        raise InputError(f"{parameter} must be a Heightmap or a 2-D array of heights in mm, got "
                         f"{type(heights).__name__}", parameter=parameter)
    if pixel_mm is None:
        raise InputError(f"{parameter} is an array of heights (mm) without a pixel size: pass pixel_mm= (mm per "
                         "pixel), or a Heightmap", parameter="pixel_mm")
    pixel_mm = pixel_size(pixel_mm)
    try:
        return _filled(heights, pixel_mm, parameter, max_fill) if flag("fill", fill) else \
            Heightmap(heights, pixel_mm)
    except InputError as err:
        err.parameter = parameter if err.parameter == "heights" else err.parameter
        raise


def _filled(heights: object, pixel_mm: float, parameter: str, max_fill: float | None) -> Heightmap:
    """``heights`` with its missing points interpolated (``cleanup.clean``; at most ``max_fill`` of the map)."""
    spec = Cleanup(fill=True, max_fill=MAX_FILL_FRACTION if max_fill is None else max_fill)
    return clean(with_missing(heights), pixel_mm, spec, parameter)[0]
