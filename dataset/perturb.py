"""Seeded, recorded perturbations that mimic printing and scanning of a heightmap (mm).

A Perturbation is a named operation with JSON-serialisable parameters; a Pipeline applies a list
of them with one random generator, so a pipeline and a seed reproduce a heightmap exactly. Maps
are treated as periodic tiles (filters and resampling wrap at the edges); resampling is bilinear.
Heights stay >= 0: a step that leaves negative heights (only ``noise`` can) is moved up to start at 0.
"""
from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from roughness.core.checks import integer, non_negative, positive, real
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

LAYER_MM = 0.03  # FDM/SLA layer height used by quantise
# Ranges drawn by random_pipeline: each step's parameters are uniform in these bounds (mm, degrees
# or factors); quantise uses LAYER_MM and is included with probability QUANTISE_PROBABILITY.
RANDOM_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "lateral_scale": {"factor": (0.85, 1.15)},
    "rotate": {"angle_deg": (0.0, 360.0)},
    "shift": {"dx_mm": (-6.0, 6.0), "dy_mm": (-6.0, 6.0)},
    "height_scale": {"factor": (0.7, 1.3)},
    "inflate": {"radius_mm": (-0.05, 0.05)},
    "blur": {"sigma_mm": (0.0, 0.1)},
    "noise": {"rms_mm": (0.0, 0.02), "correlation_mm": (0.0, 0.2)},
}
QUANTISE_PROBABILITY = 0.5
# Order of steps in a random pipeline: design geometry, then printing, then scanning.
RANDOM_ORDER = ("lateral_scale", "rotate", "shift", "height_scale", "inflate", "blur", "quantise", "noise")

Operation = Callable[..., np.ndarray]


def _blur(h: np.ndarray, pixel_mm: float, rng: np.random.Generator, sigma_mm: float) -> np.ndarray:
    """Gaussian blur with standard deviation ``sigma_mm`` (mm)."""
    return ndimage.gaussian_filter(h, sigma_mm / pixel_mm, mode="wrap")


def _disk(radius_px: float) -> np.ndarray:
    """Boolean disk footprint of radius ``radius_px`` pixels (at least the centre pixel)."""
    reach = math.floor(radius_px)
    offsets = np.arange(-reach, reach + 1)
    return offsets[:, None] ** 2 + offsets[None, :] ** 2 <= radius_px**2 + 1e-9


def _inflate(h: np.ndarray, pixel_mm: float, rng: np.random.Generator, radius_mm: float) -> np.ndarray:
    """Grey dilation by a flat disk of ``radius_mm`` (mm); erosion for a negative radius."""
    footprint = _disk(abs(radius_mm) / pixel_mm)
    morph = ndimage.grey_dilation if radius_mm > 0 else ndimage.grey_erosion
    return morph(h, footprint=footprint, mode="wrap")


def _height_scale(h: np.ndarray, pixel_mm: float, rng: np.random.Generator, factor: float) -> np.ndarray:
    """Heights multiplied by ``factor``."""
    return h * factor


def _resample(h: np.ndarray, matrix: np.ndarray, offset_px: np.ndarray) -> np.ndarray:
    """Periodic bilinear resampling; output pixel (i, j) samples centre + matrix @ ((i, j) - centre) - offset (pixels).

    Source coordinates within 1e-9 pixels of a whole pixel are snapped to it, so whole-pixel shifts
    and quarter turns are exact.
    """
    centre = (np.array(h.shape) - 1) / 2
    index = np.indices(h.shape).reshape(2, -1).astype(float) - centre[:, None]
    source = matrix @ index + (centre - offset_px)[:, None]
    whole = np.rint(source)
    source = np.where(np.abs(source - whole) < 1e-9, whole, source)
    return ndimage.map_coordinates(h, source, order=1, mode="grid-wrap").reshape(h.shape)


def _lateral_scale(h: np.ndarray, pixel_mm: float, rng: np.random.Generator, factor: float) -> np.ndarray:
    """Features stretched by ``factor`` about the map centre; map and pixel size kept."""
    return _resample(h, np.eye(2) / factor, np.zeros(2))


def _rotate(h: np.ndarray, pixel_mm: float, rng: np.random.Generator, angle_deg: float) -> np.ndarray:
    """Texture rotated by ``angle_deg`` (counter-clockwise from +x towards +y) about the map centre."""
    cos, sin = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    # (row, col) = (y, x): a feature at p moves to R p, so the output samples R^-1 q.
    return _resample(h, np.array([[cos, -sin], [sin, cos]]), np.zeros(2))


def _shift(h: np.ndarray, pixel_mm: float, rng: np.random.Generator, dx_mm: float, dy_mm: float) -> np.ndarray:
    """Texture moved by (dx_mm, dy_mm) (mm), wrapping periodically; exact for whole pixels."""
    return _resample(h, np.eye(2), np.array([dy_mm, dx_mm]) / pixel_mm)


def _noise(h: np.ndarray, pixel_mm: float, rng: np.random.Generator, rms_mm: float,
           correlation_mm: float) -> np.ndarray:
    """Added Gaussian noise of RMS ``rms_mm`` (mm), smoothed by a Gaussian of sigma ``correlation_mm`` (mm)."""
    noise = ndimage.gaussian_filter(rng.standard_normal(h.shape), correlation_mm / pixel_mm, mode="wrap")
    return h + noise * (rms_mm / noise.std())


def _quantise(h: np.ndarray, pixel_mm: float, rng: np.random.Generator, step_mm: float) -> np.ndarray:
    """Heights rounded to the nearest multiple of ``step_mm`` (mm), like printed layers."""
    return np.round(h / step_mm) * step_mm


# name -> (operation, {parameter: rule})
OPERATIONS: dict[str, tuple[Operation, dict[str, Callable[[str, object], float]]]] = {
    "blur": (_blur, {"sigma_mm": non_negative}),
    "inflate": (_inflate, {"radius_mm": real}),
    "height_scale": (_height_scale, {"factor": positive}),
    "lateral_scale": (_lateral_scale, {"factor": positive}),
    "rotate": (_rotate, {"angle_deg": real}),
    "shift": (_shift, {"dx_mm": real, "dy_mm": real}),
    "noise": (_noise, {"rms_mm": non_negative, "correlation_mm": non_negative}),
    "quantise": (_quantise, {"step_mm": positive}),
}


def _checked_params(name: str, params: dict) -> dict[str, float]:
    """``params`` as floats, or InputError naming the unknown operation or the bad parameter."""
    if name not in OPERATIONS:
        raise InputError(f"unknown perturbation {name!r}; valid perturbations: {', '.join(OPERATIONS)}")
    rules = OPERATIONS[name][1]
    if set(params) != set(rules):
        raise InputError(f"{name} takes parameters {', '.join(rules)}, got {', '.join(params) or 'none'}")
    return {key: check(f"{name} parameter {key}", params[key]) for key, check in rules.items()}


@dataclass(frozen=True)
class Perturbation:
    """One named perturbation with its parameters (mm, degrees or factors); validated on creation."""

    name: str
    params: dict[str, float]

    def __post_init__(self) -> None:
        object.__setattr__(self, "params", _checked_params(self.name, dict(self.params)))

    def apply(self, hm: Heightmap, rng: np.random.Generator) -> Heightmap:
        """The perturbed heightmap (same shape and pixel size); heights moved up to >= 0 if needed."""
        operation = OPERATIONS[self.name][0]
        heights = operation(np.array(hm.heights), hm.pixel_mm, rng, **self.params)
        return Heightmap(heights - min(float(heights.min()), 0.0), hm.pixel_mm)

    def to_dict(self) -> dict:
        """JSON-serialisable {"name": ..., "params": {...}}."""
        return {"name": self.name, "params": dict(self.params)}

    @classmethod
    def from_dict(cls, data: dict) -> Perturbation:
        """Inverse of to_dict; InputError for a malformed record."""
        if not isinstance(data, dict) or set(data) != {"name", "params"} or not isinstance(data["params"], dict):
            raise InputError(f'a perturbation record needs exactly "name" and a "params" object, got {data!r}')
        return cls(data["name"], data["params"])


def blur(sigma_mm: float) -> Perturbation:
    """Gaussian blur of standard deviation ``sigma_mm`` (mm): rounded edges of a print."""
    return Perturbation("blur", {"sigma_mm": sigma_mm})


def inflate(radius_mm: float) -> Perturbation:
    """Grey dilation by a disk of ``radius_mm`` (mm), erosion if negative: over/under-extrusion."""
    return Perturbation("inflate", {"radius_mm": radius_mm})


def height_scale(factor: float) -> Perturbation:
    """Heights multiplied by ``factor`` (> 0)."""
    return Perturbation("height_scale", {"factor": factor})


def lateral_scale(factor: float) -> Perturbation:
    """Features stretched by ``factor`` (> 0) about the map centre; map and pixel size kept."""
    return Perturbation("lateral_scale", {"factor": factor})


def rotate(angle_deg: float) -> Perturbation:
    """Rotation by ``angle_deg`` (degrees, +x towards +y) about the map centre, wrapping periodically."""
    return Perturbation("rotate", {"angle_deg": angle_deg})


def shift(dx_mm: float, dy_mm: float) -> Perturbation:
    """Translation by (dx_mm, dy_mm) (mm), wrapping periodically."""
    return Perturbation("shift", {"dx_mm": dx_mm, "dy_mm": dy_mm})


def noise(rms_mm: float, correlation_mm: float = 0.0) -> Perturbation:
    """Additive Gaussian scan noise of RMS ``rms_mm`` (mm), correlated over ``correlation_mm`` (mm, Gaussian sigma)."""
    return Perturbation("noise", {"rms_mm": rms_mm, "correlation_mm": correlation_mm})


def quantise(step_mm: float = LAYER_MM) -> Perturbation:
    """Heights rounded to multiples of ``step_mm`` (mm; default a 30 um print layer)."""
    return Perturbation("quantise", {"step_mm": step_mm})


@dataclass(frozen=True)
class Pipeline:
    """Perturbations applied in order with one random generator per seed."""

    steps: tuple[Perturbation, ...] = ()

    def __post_init__(self) -> None:
        steps = tuple(self.steps)
        for step in steps:
            if not isinstance(step, Perturbation):
                raise InputError(f"pipeline steps must be Perturbations, got {step!r}")
        object.__setattr__(self, "steps", steps)

    def apply(self, hm: Heightmap, seed: int) -> Heightmap:
        """The heightmap after every step; deterministic per ``seed``."""
        rng = np.random.default_rng(seed)
        for step in self.steps:
            hm = step.apply(hm, rng)
        return hm

    def to_json(self) -> str:
        """JSON list of the steps' records."""
        return json.dumps([step.to_dict() for step in self.steps])

    @classmethod
    def from_json(cls, text: str) -> Pipeline:
        """Inverse of to_json; InputError for malformed JSON."""
        try:
            records = json.loads(text)
        except json.JSONDecodeError as error:
            raise InputError(f"pipeline JSON is malformed: {error}") from None
        if not isinstance(records, list):
            raise InputError(f"pipeline JSON must be a list of perturbations, got {type(records).__name__}")
        return cls(tuple(Perturbation.from_dict(record) for record in records))


def random_pipeline(rng: np.random.Generator | int, max_steps: int = 3) -> Pipeline:
    """A plausible random pipeline of at most ``max_steps`` distinct steps, in RANDOM_ORDER.

    Quantisation to LAYER_MM is included with probability QUANTISE_PROBABILITY; the other steps
    (0 up to the remaining budget, chosen uniformly) have parameters uniform in RANDOM_RANGES.
    """
    integer("max_steps", max_steps, minimum=0)
    rng = np.random.default_rng(rng)
    with_quantise = max_steps > 0 and rng.random() < QUANTISE_PROBABILITY
    count = int(rng.integers(0, min(max_steps - with_quantise, len(RANDOM_RANGES)) + 1))
    names = [str(name) for name in rng.choice(list(RANDOM_RANGES), size=count, replace=False)]
    steps = {name: Perturbation(name, {key: float(rng.uniform(low, high)) for key, (low, high)
                                       in RANDOM_RANGES[name].items()}) for name in names}
    if with_quantise:
        steps["quantise"] = quantise()
    return Pipeline(tuple(steps[name] for name in RANDOM_ORDER if name in steps))
