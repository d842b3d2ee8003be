"""Moved to ``roughness.surface.io``; this alias stays for one release (it warns on import)."""
import warnings

from roughness.surface.io import (  # noqa: F401
    DEFAULT_DATASET,
    FULL_SCALE,
    PNG_16BIT,
    PNG_ERRORS,
    SAME_UNIT_RTOL,
    SAVE_SUFFIXES,
    SUFFIXES,
    UNITS_KEY,
    heightmap_files,
    load_heightmap,
    open_image,
    save_heightmap,
)

warnings.warn("roughness.simulate.io moved to roughness.surface.io", DeprecationWarning, stacklevel=2)
