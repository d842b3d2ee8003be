"""Rough random (fractional Brownian) surfaces by spectral synthesis."""
from __future__ import annotations

import numpy as np

from roughness.core.checks import in_range, positive
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from .grid import PIXEL_MM, SIZE_MM, check_seed, map_side


def fbm_surface(size_mm: float = SIZE_MM, pixel_mm: float = PIXEL_MM, hurst: float = 0.8, rms_mm: float = 0.15,
                cutoff_mm: float = 0.4, seed: int = 0) -> Heightmap:
    """Isotropic fBm heightmap with RMS height ``rms_mm``, rescaled to start at 0.

    The power spectrum falls as k^-(2 + 2 hurst) and is cut off below wavelength ``cutoff_mm``
    (features finer than a fingertip or a printer resolves are not generated).
    """
    if not 0.0 < in_range("hurst", hurst, 0.0, 1.0) < 1.0:
        raise InputError(f"hurst must lie in (0, 1), got {hurst}", "hurst")
    positive("rms_mm", rms_mm)
    positive("cutoff_mm", cutoff_mm)
    check_seed(seed)
    n = map_side(size_mm, pixel_mm)
    rng = np.random.default_rng(seed)
    f = np.fft.fftfreq(n, d=pixel_mm)
    k = np.hypot(*np.meshgrid(f, f))
    k[0, 0] = np.inf
    amplitude = np.where(k <= 1.0 / cutoff_mm, k ** (-(1.0 + hurst)), 0.0)
    spectrum = amplitude * np.exp(2j * np.pi * rng.random((n, n)))
    h = np.real(np.fft.ifft2(spectrum))
    h *= rms_mm / h.std()
    return Heightmap(h - h.min(), pixel_mm)
