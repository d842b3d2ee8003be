"""Dataset recipes: which texture families, parameter ranges, perturbations and seeds.

A recipe is a JSON file (see ``datasets/training.json``). ``expand`` turns it into sample
records deterministically: sample i depends only on (recipe seed, i), so a larger ``n``
extends a dataset instead of reshuffling it. Each record holds everything that makes
the heightmap (family, parameters, texture seed, map size, perturbation pipeline) and is
what the sample id is computed from.
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.simulate.heightmap import Heightmap

from . import natural
from .catalogue import make_texture
from .perturb import Pipeline, random_pipeline

# Custom bump textures (the paper's family) sampled around the standard scale.
BUMP_RANGES: dict[str, tuple] = {"lambda_mm": (0.5, 2.5), "top": ("cap", "flat"), "top_diameter_mm": (0.1, 0.5),
                                 "height_mm": (0.3, 1.0), "base_diameter_mm": (1.0, 2.0)}


def default_ranges(family: str) -> dict[str, tuple]:
    """Parameter ranges a family is sampled from unless the recipe narrows them."""
    if family == "bumps":
        return dict(BUMP_RANGES)
    if family in natural.PARAMETER_RANGES:
        return dict(natural.PARAMETER_RANGES[family])
    raise InputError(f"unknown family {family!r} in recipe; valid: bumps, {', '.join(natural.PARAMETER_RANGES)}")


@dataclass(frozen=True)
class Recipe:
    """How to draw the samples of one dataset (lengths in mm)."""

    name: str = "dataset"
    seed: int = 0
    families: dict[str, float] = field(default_factory=lambda: {"bumps": 1.0})
    ranges: dict[str, dict[str, list]] = field(default_factory=dict)
    perturb_probability: float = 0.7
    max_perturb_steps: int = 3
    size_mm: float = 12.0
    pixel_mm: float = 0.05
    holdout_family: str | None = None  # never trained on: the out-of-family score
    test_fraction: float = 0.1  # share of base recipes (by sample id) held out for testing

    def __post_init__(self) -> None:
        if not self.families or min(self.families.values()) <= 0:
            raise InputError("recipe families need positive weights")
        for family in list(self.families) + list(self.ranges):
            default_ranges(family)
        if not 0.0 <= self.perturb_probability <= 1.0:
            raise InputError("perturb_probability must lie in [0, 1]")
        if self.holdout_family is not None and self.holdout_family not in self.families:
            raise InputError(f"holdout_family {self.holdout_family!r} is not among the recipe's families")
        if not 0.0 <= self.test_fraction < 1.0:
            raise InputError("test_fraction must lie in [0, 1)")

    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)


def load_recipe(path: str | Path) -> Recipe:
    """Recipe from a JSON file; InputError names what is wrong."""
    try:
        data = json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise InputError(f"recipe file not found: {path}") from None
    except json.JSONDecodeError as err:
        raise InputError(f"recipe {path} is not valid JSON: {err}") from None
    data.pop("_comment", None)
    try:
        return Recipe(**data)
    except TypeError as err:
        raise InputError(f"recipe {path}: {err}") from None


def _draw(rng: np.random.Generator, spec: tuple | list) -> float | str:
    if isinstance(spec[0], str):
        return str(spec[int(rng.integers(len(spec)))])
    return float(rng.uniform(spec[0], spec[1]))


def sample_record(recipe: Recipe, index: int) -> dict:
    """The generator record of sample ``index`` (deterministic)."""
    rng = np.random.default_rng([recipe.seed, index])
    names = sorted(recipe.families)
    weights = np.array([recipe.families[n] for n in names], dtype=float)
    family = names[int(rng.choice(len(names), p=weights / weights.sum()))]
    ranges = {**default_ranges(family), **{k: tuple(v) for k, v in recipe.ranges.get(family, {}).items()}}
    params = {key: _draw(rng, spec) for key, spec in sorted(ranges.items())}
    if family == "bumps" and params["top"] == "cap":
        params["top_diameter_mm"] = 0.3
    texture_seed = int(rng.integers(2**31))
    pipeline = random_pipeline(rng, recipe.max_perturb_steps) if rng.random() < recipe.perturb_probability else None
    return {"family": family, "params": params, "seed": texture_seed, "size_mm": recipe.size_mm,
            "pixel_mm": recipe.pixel_mm, "perturbation": None if pipeline is None else json.loads(pipeline.to_json()),
            "perturbation_seed": texture_seed + 1}


def expand(recipe: Recipe, n: int) -> list[dict]:
    """The first ``n`` sample records of the recipe."""
    if n < 1:
        raise InputError(f"--n must be at least 1, got {n}")
    return [sample_record(recipe, i) for i in range(n)]


def realise(record: dict) -> Heightmap:
    """The heightmap (mm) a sample record describes."""
    hm, _ = make_texture(record["family"], seed=record["seed"], size_mm=record["size_mm"],
                         pixel_mm=record["pixel_mm"], params=record["params"])
    if record["perturbation"]:
        hm = Pipeline.from_json(json.dumps(record["perturbation"])).apply(hm, record["perturbation_seed"])
    return hm
