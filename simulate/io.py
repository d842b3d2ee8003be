"""Moved to ``roughness.surface.io``; this alias stays for one release (it warns on import)."""
import warnings

from roughness.surface.io import SUFFIXES, SAVE_SUFFIXES, DEFAULT_DATASET, FULL_SCALE, PNG_16BIT, PNG_ERRORS, UNITS_KEY, SAME_UNIT_RTOL, load_heightmap, heightmap_files, save_heightmap, open_image  # noqa: F401

warnings.warn("roughness.simulate.io moved to roughness.surface.io", DeprecationWarning, stacklevel=2)
