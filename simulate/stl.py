"""Moved to ``roughness.surface.stl``; this alias stays for one release (it warns on import)."""
import warnings

from roughness.surface.stl import DEFAULT_BASE_MM, STL_RECORD, Plate, plate, stl_bytes  # noqa: F401

warnings.warn("roughness.simulate.stl moved to roughness.surface.stl", DeprecationWarning, stacklevel=2)
