"""Moved to ``roughness.surface.detrend``; this alias stays for one release (it warns on import)."""
import warnings

from roughness.surface.detrend import METHODS, CUTOFF_WAVELENGTHS, LONGEST_TEXTURE_FRACTION, Detrend, Separation, parse_detrend, detrend, quadratic_fit, lowpass, dominant_wavelength_mm  # noqa: F401

warnings.warn("roughness.simulate.detrend moved to roughness.surface.detrend", DeprecationWarning, stacklevel=2)
