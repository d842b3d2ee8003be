"""Moved to ``roughness.surface.detrend``; this alias stays for one release (it warns on import)."""
import warnings

from roughness.surface.detrend import (  # noqa: F401
    CUTOFF_WAVELENGTHS,
    LONGEST_TEXTURE_FRACTION,
    METHODS,
    Detrend,
    Separation,
    detrend,
    dominant_wavelength_mm,
    lowpass,
    parse_detrend,
    quadratic_fit,
)

warnings.warn("roughness.simulate.detrend moved to roughness.surface.detrend", DeprecationWarning, stacklevel=2)
