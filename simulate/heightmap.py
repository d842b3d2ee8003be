"""Moved to ``roughness.surface.heightmap``; this alias stays for one release (it warns on import)."""
import warnings

from roughness.surface.heightmap import TOLERANCE_MM, Heightmap, flat, pixel_size, bracket  # noqa: F401

warnings.warn("roughness.simulate.heightmap moved to roughness.surface.heightmap", DeprecationWarning, stacklevel=2)
