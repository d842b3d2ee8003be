"""The layer's transfer functions on a pixel grid, and the fields they make.

A ``Modes`` object holds, for every wave vector of an (ny, nx) grid of ``pixel_mm`` pixels, the
layer's response (``layer.mode_response``) and the direction cosines of the mode's axis. With it a
face displacement (u_x, u_y, u_z) becomes the strain tensor field at the receptor depth, and face
tractions become face displacements (the compliance, for the contact solver). The uniform mode
(k = 0) carries no texture: the engine adds the flat state for it. Units: mm, MPa.

Two bases. ``periodic``: the grid is one period (rfft2 layout). ``mirror``: the grid is mirrored
across each of its edges (the texture extended without a jump), which is the periodic basis on the
doubled (2ny, 2nx) grid at a quarter of its cost: by the mirror symmetry every field is even or odd
across the edges (u_z, p and the normal strains even-even; u_x, t_x, e_xz odd in x; e_xy odd-odd),
so it is a sum of cosines and sines (DCT-II / DST-II per axis) at the wave numbers pi m / (n pixel),
m = 0..n. A real coefficient R of a field odd along ``q`` axes is the complex amplitude
R (-i)^q of the mode's positive wave vector, and back: the isotropic layer maps the four mirrored
exponentials of a mode alike, so the complex transfer functions apply unchanged.
"""
from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from functools import cached_property
from threading import Lock

import numpy as np
from scipy import fft

from .layer import Tissue, mode_response

FACE_COMPONENTS = 3  # u_x, u_y, u_z
STRAIN_COMPONENTS = ("xx", "yy", "zz", "xy", "xz", "yz")
BASES = ("periodic", "mirror")
Parity = tuple[int, int]  # (along x, along y): 0 even, 1 odd across the mirrored edges
FACE_PARITY: tuple[Parity, ...] = ((1, 0), (0, 1), (0, 0))  # u_x, u_y, u_z (and the tractions)
STRAIN_PARITY: tuple[Parity, ...] = ((0, 0), (0, 0), (0, 0), (1, 1), (1, 0), (0, 1))
EVEN: tuple[Parity, ...] = ((0, 0),)


@dataclass(frozen=True)
class GridKey:
    """What the transfer functions depend on: grid shape (pixels), pixel (mm), tissue, depth (mm),
    and the basis (``BASES``)."""

    shape: tuple[int, int]
    pixel_mm: float
    tissue: Tissue
    depth_mm: float
    basis: str = "periodic"


def _mirror_transform(field: np.ndarray, parity: Parity, inverse: bool) -> np.ndarray:
    """DCT-II (even) or DST-II (odd) of ``field`` along x then y, or their inverses."""
    for axis, odd in ((-1, parity[0]), (-2, parity[1])):
        if inverse:
            field = (fft.idst if odd else fft.idct)(field, type=2, axis=axis)
        else:
            field = (fft.dst if odd else fft.dct)(field, type=2, axis=axis)
    return field


def _apply(matrices: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Per mode, (3, 3, ...) matrices times (3, ...) vectors."""
    return matrices[:, 0] * vectors[0] + matrices[:, 1] * vectors[1] + matrices[:, 2] * vectors[2]


class Modes:
    """Transfer functions of one ``GridKey``, on its spectral grid: (ny, nx // 2 + 1) (periodic, rfft2
    layout) or (ny + 1, nx + 1) (mirror: wave numbers pi m / (n pixel), m = 0..n per axis)."""

    def __init__(self, key: GridKey) -> None:
        self.key = key
        ny, nx = key.shape
        if key.basis == "mirror":
            kx, ky = np.pi * np.arange(nx + 1) / (nx * key.pixel_mm), np.pi * np.arange(ny + 1) / (ny * key.pixel_mm)
        else:
            kx = 2 * np.pi * np.fft.rfftfreq(nx, key.pixel_mm)
            ky = 2 * np.pi * np.fft.fftfreq(ny, key.pixel_mm)
        kx, ky = np.meshgrid(kx, ky)
        k = np.hypot(kx, ky)
        k[0, 0] = 1.0  # placeholder: the uniform mode is set apart below
        self.c, self.s = kx / k, ky / k
        self.c[0, 0] = self.s[0, 0] = 0.0
        unique, where = np.unique(k, return_inverse=True)  # the response depends on |k| only
        response = mode_response(unique, key.tissue, key.depth_mm)
        shape = k.shape

        def grid(values: np.ndarray) -> np.ndarray:
            out = np.take(values, where.ravel(), axis=0).reshape(shape + values.shape[1:])
            out[0, 0] = 0.0
            return out

        self.exx, self.ezz, self.exz = grid(response.exx), grid(response.ezz), grid(response.exz)
        self.exy, self.eyz = grid(response.exy), grid(response.eyz)
        stiffness = grid(response.traction)
        thickness, mu = key.tissue.thickness_mm, key.tissue.shear_mpa
        stiffness[0, 0] = np.diag([mu, key.tissue.oedometric_mpa]) / thickness  # uniform shear and compression
        antiplane = grid(response.antiplane_traction)
        antiplane[0, 0] = mu / thickness
        self.stiffness, self.antiplane = stiffness, antiplane
        det = stiffness[..., 0, 0] * stiffness[..., 1, 1] - stiffness[..., 0, 1] * stiffness[..., 1, 0]
        self.compliance = np.stack([np.stack([stiffness[..., 1, 1], -stiffness[..., 0, 1]], -1),
                                    np.stack([-stiffness[..., 1, 0], stiffness[..., 0, 0]], -1)], -2) / det[..., None, None]
        # Frictionless face (no shear traction): A = -K_SB / K_SS B, and the normal stiffness left.
        self.slide = -stiffness[..., 0, 1] / stiffness[..., 0, 0]
        self.normal_stiffness = stiffness[..., 1, 1] - stiffness[..., 0, 1] ** 2 / stiffness[..., 0, 0]

    @property
    def shape(self) -> tuple[int, int]:
        return self.key.shape

    @property
    def mirror(self) -> bool:
        return self.key.basis == "mirror"

    @property
    def uniform(self) -> float:
        """The uniform mode's coefficient of a field equal to 1 everywhere."""
        return float(np.prod(self.shape)) * (4.0 if self.mirror else 1.0)

    def forward(self, fields: np.ndarray, parity: tuple[Parity, ...] = FACE_PARITY) -> np.ndarray:
        """Spectra (c, ...) of real fields (c, ny, nx) with the given parities (mirror basis only)."""
        if not self.mirror:
            return np.fft.rfft2(fields)
        phases = np.array([(-1j) ** (px + py) for px, py in parity])
        return self.coefficients(fields, parity) * phases[:, None, None]

    def inverse(self, spectra: np.ndarray, parity: tuple[Parity, ...] = FACE_PARITY) -> np.ndarray:
        """Real fields (c, ny, nx) of spectra (c, ...) with the given parities (mirror basis only)."""
        if not self.mirror:
            return np.fft.irfft2(spectra, s=self.shape)
        phases = np.array([1j ** (px + py) for px, py in parity])
        return self.fields((spectra * phases[:, None, None]).real, parity)

    def coefficients(self, fields: np.ndarray, parity: tuple[Parity, ...] = FACE_PARITY) -> np.ndarray:
        """Mirror basis: the real cosine/sine coefficients (c, ny + 1, nx + 1) of real fields (c, ny, nx)
        (the spectra without their phases: ``forward``)."""
        ny, nx = self.shape
        out = np.zeros((len(fields), ny + 1, nx + 1))
        for i, (field, (px, py)) in enumerate(zip(fields, parity, strict=True)):
            out[i, py:py + ny, px:px + nx] = _mirror_transform(field, (px, py), inverse=False)
        return out

    def fields(self, coefficients: np.ndarray, parity: tuple[Parity, ...] = FACE_PARITY) -> np.ndarray:
        """Mirror basis: real fields (c, ny, nx) of real cosine/sine coefficients (c, ny + 1, nx + 1)."""
        ny, nx = self.shape
        out = np.empty((len(coefficients),) + self.shape)
        for i, (coefficient, (px, py)) in enumerate(zip(coefficients, parity, strict=True)):
            out[i] = _mirror_transform(coefficient[py:py + ny, px:px + nx], (px, py), inverse=True)
        return out

    @cached_property
    def real_operators(self) -> tuple[np.ndarray, np.ndarray]:
        """Mirror basis: the stick face's compliance and stiffness as real matrices (3, 3, ny + 1, nx + 1) on the
        cosine/sine coefficients of (x, y, z) face fields (``coefficients``): the complex operators with the
        phases of the components' parities folded in, M_ij = Re(L_ij i^q_i (-i)^q_j) (the imaginary part is zero).
        Built on first use (the contact solver's inner loop: real arithmetic, no mode frames)."""
        q = np.array([px + py for px, py in FACE_PARITY])
        phase = (1j ** q)[:, None] * ((-1j) ** q)[None, :]
        unit = np.zeros((3, 3) + self.stiffness.shape[:2], dtype=complex)
        for j in range(3):
            unit[j, j] = 1.0
        compliance = np.stack([self.displacement(unit[j], False) for j in range(3)], axis=1)  # (out, in, ...)
        stiffness = np.stack([self.traction(unit[j]) for j in range(3)], axis=1)
        return ((compliance * phase[:, :, None, None]).real.copy(), (stiffness * phase[:, :, None, None]).real.copy())

    def stick_displacement(self, traction: np.ndarray) -> np.ndarray:
        """Face displacements (3, ny, nx) of a stick face under face tractions (3, ny, nx) on the skin (real fields)."""
        if not self.mirror:
            return self.inverse(self.displacement(self.forward(traction), False))
        return self.fields(_apply(self.real_operators[0], self.coefficients(traction)))

    def stick_traction(self, face: np.ndarray) -> np.ndarray:
        """Face tractions (3, ny, nx) that hold face displacements (3, ny, nx) of a stick face (real fields)."""
        if not self.mirror:
            return self.inverse(self.traction(self.forward(face)))
        return self.fields(_apply(self.real_operators[1], self.coefficients(face)))

    def to_mode_frame(self, ux: np.ndarray, uy: np.ndarray, uz: np.ndarray) -> tuple[np.ndarray, ...]:
        """Fourier face displacements (x, y, z) -> (A, B, C): u_x' = i A, u_z = B, u_y' = C."""
        along = self.c * ux + self.s * uy
        return -1j * along, uz, -self.s * ux + self.c * uy

    def from_mode_frame(self, along: np.ndarray, across: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Fourier components along x' and y' -> along x and y."""
        return self.c * along - self.s * across, self.s * along + self.c * across

    def strain(self, face: np.ndarray) -> np.ndarray:
        """Strain components (6, ny, nx) at the depth, in the order ``STRAIN_COMPONENTS``, from Fourier
        face displacements (3, ny, nx//2+1). The uniform mode of ``face`` is ignored (the engine's
        flat state stands for it)."""
        a, b, c = self.to_mode_frame(*face)
        e_aa = self.exx[..., 0] * a + self.exx[..., 1] * b
        e_zz = self.ezz[..., 0] * a + self.ezz[..., 1] * b
        e_az = 1j * (self.exz[..., 0] * a + self.exz[..., 1] * b)
        e_ab = 1j * self.exy * c
        e_bz = self.eyz * c
        cc, ss, cs = self.c**2, self.s**2, self.c * self.s
        xz, yz = self.from_mode_frame(e_az, e_bz)
        spectra = np.stack([cc * e_aa - 2 * cs * e_ab, ss * e_aa + 2 * cs * e_ab, e_zz,
                            cs * e_aa + (cc - ss) * e_ab, xz, yz])
        return self.inverse(spectra, STRAIN_PARITY)

    def slid(self, uz: np.ndarray) -> np.ndarray:
        """Fourier face displacements (3, ...) of a frictionless face whose normal displacement is ``uz``."""
        along = 1j * self.slide * uz  # u_x' = i A with A = slide * B
        ux, uy = self.from_mode_frame(along, np.zeros_like(uz))
        return np.stack([ux, uy, uz])

    def displacement(self, traction: np.ndarray, frictionless: bool) -> np.ndarray:
        """Fourier face displacements (3, ...) under Fourier face tractions (3, ...) on the skin.

        ``frictionless``: only the normal traction acts (the face slides freely).
        """
        if frictionless:
            return self.slid(traction[2] / self.normal_stiffness)
        a_t, p, c_t = self.to_mode_frame(*traction)  # t_x' = i S: S = -i t_x' = a_t
        g = self.compliance
        a = g[..., 0, 0] * a_t + g[..., 0, 1] * p
        b = g[..., 1, 0] * a_t + g[..., 1, 1] * p
        ux, uy = self.from_mode_frame(1j * a, c_t / self.antiplane)
        return np.stack([ux, uy, b])

    def traction(self, face: np.ndarray) -> np.ndarray:
        """Fourier face tractions (3, ...) that hold Fourier face displacements (3, ...) in place."""
        a, b, c = self.to_mode_frame(*face)
        k = self.stiffness
        s = k[..., 0, 0] * a + k[..., 0, 1] * b
        p = k[..., 1, 0] * a + k[..., 1, 1] * b
        tx, ty = self.from_mode_frame(1j * s, self.antiplane * c)
        return np.stack([tx, ty, p])


_CACHE: OrderedDict[GridKey, Modes] = OrderedDict()
_CACHE_LOCK = Lock()
CACHE_SIZE = 8  # grids kept (a 400 x 400 grid holds about 20 MB of transfer functions)


def modes(key: GridKey) -> Modes:
    """The (cached, thread-safe) transfer functions of ``key``."""
    with _CACHE_LOCK:
        if key in _CACHE:
            _CACHE.move_to_end(key)
            return _CACHE[key]
    built = Modes(key)
    with _CACHE_LOCK:
        _CACHE[key] = built
        while len(_CACHE) > CACHE_SIZE:
            _CACHE.popitem(last=False)
    return built
