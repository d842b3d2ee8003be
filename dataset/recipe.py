"""Dataset recipes: which texture families, parameter ranges, perturbations and seeds.

A recipe is a JSON file (see ``recipes/training.json``). ``expand`` turns it into texture
records deterministically: sample i depends only on (recipe seed, i), so a larger ``n``
extends a dataset instead of reshuffling it. Each record holds everything that makes
the heightmap (family, parameters, texture seed, map size, perturbation pipeline) and is
what the sample id is computed from.
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np

from roughness.core.checks import in_range, integer, positive, real
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from . import families
from .catalogue import make_texture
from .grid import PIXEL_MM, SIZE_MM, check_seed, map_side
from .perturb import Pipeline, random_pipeline

# Custom bump textures (the paper's family) sampled around the standard scale.
BUMP_RANGES: dict[str, tuple] = {"lambda_mm": (0.5, 2.5), "top": ("cap", "flat"), "top_diameter_mm": (0.1, 0.5),
                                 "height_mm": (0.3, 1.0), "base_diameter_mm": (1.0, 2.0)}


def default_ranges(family: str) -> dict[str, tuple]:
    """Parameter ranges a family is sampled from unless the recipe narrows them."""
    if family == "bumps":
        return dict(BUMP_RANGES)
    if family in families.PARAMETER_RANGES:
        return dict(families.PARAMETER_RANGES[family])
    raise InputError(f"unknown family {family!r} in recipe; valid: bumps, {', '.join(families.PARAMETER_RANGES)}")


@dataclass(frozen=True)
class Recipe:
    """How to draw the samples of one dataset (lengths in mm); every field is checked on creation."""

    name: str = "dataset"
    seed: int = 0
    families: dict[str, float] = field(default_factory=lambda: {"bumps": 1.0})
    ranges: dict[str, dict[str, list]] = field(default_factory=dict)  # family -> parameter -> [low, high] or choices
    perturb_probability: float = 0.7
    max_perturb_steps: int = 3
    size_mm: float = SIZE_MM
    pixel_mm: float = PIXEL_MM
    holdout_family: str | None = None  # never trained on: the out-of-family score
    test_fraction: float = 0.1  # share of base recipes (by sample id) held out for testing
    # printed versions: with this probability a sample is printed by one of ``printers`` (names of
    # roughness.surface.printing.PROFILES), drawn after everything else, so a recipe with probability 1 makes the
    # printed twins of the same recipe's unprinted samples (same base texture, same split)
    print_probability: float = 0.0
    printers: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InputError(f"name must be a non-empty string, got {self.name!r}", "name")
        check_seed(self.seed)
        if not isinstance(self.families, dict) or not self.families:
            raise InputError(f"families must be a non-empty object of family: weight, got {self.families!r}",
                             "families")
        for family, weight in self.families.items():
            _known("families", family)
            positive(f"families.{family}", weight)
        if not isinstance(self.ranges, dict):
            raise InputError(f"ranges must be an object of family: {{parameter: range}}, got {self.ranges!r}",
                             "ranges")
        for family, ranges in self.ranges.items():
            allowed = _known("ranges", family)
            if not isinstance(ranges, dict):
                raise InputError(f"ranges.{family} must be an object of parameter: range, got {ranges!r}", "ranges")
            for key, spec in ranges.items():
                _check_range(family, key, spec, allowed)
        in_range("perturb_probability", self.perturb_probability, 0.0, 1.0)
        integer("max_perturb_steps", self.max_perturb_steps, minimum=0)
        map_side(self.size_mm, self.pixel_mm)
        if self.holdout_family is not None and (not isinstance(self.holdout_family, str)
                                                or self.holdout_family not in self.families):
            raise InputError(f"holdout_family {self.holdout_family!r} is not among the recipe's families",
                             "holdout_family")
        if in_range("test_fraction", self.test_fraction, 0.0, 1.0) == 1.0:
            raise InputError("test_fraction must be below 1, got 1", "test_fraction")
        in_range("print_probability", self.print_probability, 0.0, 1.0)
        _check_printers(self.printers, self.print_probability)

    def to_json(self) -> str:
        """The recipe as JSON; the print fields only when used (so recipes from before them keep their JSON, and
        their datasets resume)."""
        data = asdict(self)
        if not self.print_probability and not self.printers:
            del data["print_probability"], data["printers"]
        return json.dumps(data, sort_keys=True)


def _check_printers(printers: object, probability: float) -> None:
    """InputError unless ``printers`` is a list of shipped print profile names, non-empty if ``probability`` > 0."""
    from roughness.surface.printing import PROFILES

    if not isinstance(printers, list) or any(p not in PROFILES for p in printers):
        raise InputError(f"printers must be a list of print profile names ({', '.join(PROFILES)}), got {printers!r}",
                         "printers")
    if probability > 0 and not printers:
        raise InputError("print_probability > 0 needs printers to draw from", "printers")


def _known(field_name: str, family: object) -> dict[str, tuple]:
    """The default ranges of ``family``, or InputError naming the recipe field."""
    try:
        return default_ranges(family)
    except InputError as err:
        raise InputError(f"{field_name}: {err}", field_name) from None


def _check_range(family: str, key: str, spec: object, allowed: dict[str, tuple]) -> None:
    """InputError unless ``spec`` is a usable range of parameter ``key``: choices among the allowed
    ones, or [low, high] with low <= high (within the family's limits, ``families.PARAMETER_LIMITS``, for the
    parametric families: wider than the default ranges)."""
    name = f"ranges.{family}.{key}"
    if key not in allowed:
        raise InputError(f"{name}: {family} has no parameter {key!r}; valid: {', '.join(allowed)}", "ranges")
    choices = allowed[key]
    if isinstance(choices[0], str):
        if not isinstance(spec, list) or not spec or any(c not in choices for c in spec):
            raise InputError(f"{name} must be a non-empty list of {', '.join(choices)}, got {spec!r}", "ranges")
        return
    if not isinstance(spec, list) or len(spec) != 2:
        raise InputError(f"{name} must be [low, high], got {spec!r}", "ranges")
    limits = families.PARAMETER_LIMITS.get(family, {}).get(key)
    low, high = ((in_range(f"{name}[{i}]", v, *limits) if limits else real(f"{name}[{i}]", v))
                 for i, v in enumerate(spec))
    if low > high:
        raise InputError(f"{name} must be [low, high] with low <= high, got {spec!r}", "ranges")


def load_recipe(path: str | Path) -> Recipe:
    """Recipe from a JSON file; InputError names what is wrong (the field, for a bad value)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"recipe file not found: {path}") from None
    except UnicodeDecodeError:
        raise InputError(f"recipe {path} is not a text (JSON) file") from None
    except OSError as err:
        raise InputError(f"cannot read recipe {path}: {err.strerror}") from None
    except json.JSONDecodeError as err:
        raise InputError(f"recipe {path} is not valid JSON: {err}") from None
    if not isinstance(data, dict):
        raise InputError(f"recipe {path} must be a JSON object of recipe fields, got a {type(data).__name__}")
    data.pop("_comment", None)
    unknown = sorted(set(data) - {f.name for f in fields(Recipe)})
    if unknown:
        raise InputError(f"recipe {path}: unknown field(s) {', '.join(unknown)}; valid: "
                         f"{', '.join(f.name for f in fields(Recipe))}")
    try:
        return Recipe(**data)
    except InputError as err:  # a field of the file, not a flag: named in the words (a check may name only its value)
        field = f"{err.parameter}: " if err.parameter and err.parameter not in str(err) else ""
        raise InputError(f"recipe {path}: {field}{err}") from None


def _draw(rng: np.random.Generator, spec: tuple | list) -> float | str:
    if isinstance(spec[0], str):
        return str(spec[int(rng.integers(len(spec)))])
    return float(rng.uniform(spec[0], spec[1]))


def sample_record(recipe: Recipe, index: int) -> dict:
    """The texture record of sample ``index`` (deterministic): a dict, whose ``sample_id`` is the sample's id."""
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
    record = {"family": family, "params": params, "seed": texture_seed, "size_mm": recipe.size_mm,
              "pixel_mm": recipe.pixel_mm, "perturbation": None if pipeline is None else json.loads(pipeline.to_json()),
              "perturbation_seed": texture_seed + 1}
    if recipe.print_probability > 0 and rng.random() < recipe.print_probability:
        record["printer"] = recipe.printers[int(rng.integers(len(recipe.printers)))]
    return record


def expand(recipe: Recipe, n: int) -> list[dict]:
    """The first ``n`` texture records of the recipe."""
    integer("n", n, minimum=1)
    return [sample_record(recipe, i) for i in range(n)]


def realise(record: dict) -> Heightmap:
    """The heightmap (mm) a texture record describes."""
    hm, _ = make_texture(record["family"], seed=record["seed"], size_mm=record["size_mm"],
                         pixel_mm=record["pixel_mm"], params=record["params"])
    if record["perturbation"]:
        hm = Pipeline.from_json(json.dumps(record["perturbation"])).apply(hm, record["perturbation_seed"])
    if record.get("printer"):
        from roughness.surface.printing import PROFILES, printed

        hm = printed(hm, PROFILES[record["printer"]]).heightmap
    return hm
