"""Moved to ``roughness.surface.heightmap``; this alias stays for one release (it warns on import)."""
import warnings

from roughness.surface.heightmap import TOLERANCE_MM, Heightmap, bracket, flat, pixel_size  # noqa: F401

warnings.warn("roughness.simulate.heightmap moved to roughness.surface.heightmap", DeprecationWarning, stacklevel=2)
