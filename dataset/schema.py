"""What a dataset file holds: its root configuration (one typed header) and one index entry per sample.

Layout ("roughness.dataset", version 2)
---------------------------------------
``/``                    attrs ``schema``, ``schema_version``, ``config`` (JSON of ``DatasetConfig``),
                         ``roughness_version`` (package that created the file), ``created`` (ISO 8601, UTC)
``/index/<field>``       one 1-D column per ``Entry`` field, one row per sample, sorted by id: opening
                         a dataset reads these columns, never the sample groups (columns added later,
                         ``ADDED_FIELDS``, may be absent from older files: read as their defaults)
``/samples/<id>``        ``<id> = sample_id(texture record)``, 16 hex digits
  ``heightmap``          float32 (ny, nx) heights in mm, one gzip chunk; shapes may differ between samples;
                         absent for a failed sample whose texture could not be made
  ``fluctuation``        float32 strain fluctuation map at receptor depth (ok samples that were simulated,
                         not restored from a labels file), one gzip chunk;
                         attr ``grid_axis_mm``: coordinates (mm) of its rows and columns
Version 1 files (no ``/index``; each sample group carries the ``Entry`` fields as attributes) are
read by walking the groups, and converted to version 2 by the next writer.
"""
from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from roughness.core.errors import InputError
from roughness.core.hashing import canonical_json, digest

SCHEMA = "roughness.dataset"
SCHEMA_VERSION = 2
READABLE_VERSIONS = (1, 2)
ROOT_ATTRS = ("schema", "schema_version", "config", "roughness_version", "created")
STATUSES = ("ok", "failed")
# write_result's result_fields key (a simulate.result.Result attribute) -> (Entry field, type).
RESULT_ATTRS = {
    "roughness": ("V", float),
    "roughness_stderr": ("V_stderr", float),
    "contact_fraction": ("contact_fraction", float),
    "indentation_mm": ("indentation_mm", float),
    "converged": ("converged", bool),
    "iterations": ("iterations", int),
    "unresolved_nodes": ("unresolved_nodes", int),
    "cycled": ("cycled", bool),
    "seconds": ("seconds", float),
    "discretization_error": ("discretization_error", float),
}
# Result floats that may be missing (nan): the discretization-error estimate of a single-level run,
# and files written before it was stored.
OPTIONAL_FLOATS = ("discretization_error",)
RESULT_ARRAYS = ("contact_history", "grid_axis_mm", "ladder")
# Variable-length index columns (Entry tuple fields) and their element types.
TUPLE_FIELDS = {"contact_history": int, "ladder_h_mm": float, "ladder_V": float}


def sample_id(texture_record: dict) -> str:
    """16 hex digits of the SHA-1 of the texture record's canonical JSON: independent of key order."""
    if not isinstance(texture_record, dict):
        raise TypeError(f"a texture record is a dict, got {type(texture_record).__name__}")
    return digest(texture_record)


def result_fields(result: object) -> dict:
    """The ``result_fields`` of ``DatasetWriter.write_result`` from a ``simulate.result.Result``."""
    return {key: getattr(result, key) for key in (*RESULT_ATTRS, *RESULT_ARRAYS)}


@dataclass(frozen=True)
class DatasetConfig:
    """How every sample of a dataset was made: ``SimConfig.as_dict()`` and the ``Recipe``'s fields."""

    simulation: dict
    recipe: dict

    @classmethod
    def parse(cls, value: object, source: str = "dataset configuration") -> DatasetConfig:
        """The one reader of a configuration (a dict, or its JSON text); InputError says what is wrong."""
        if isinstance(value, str):
            try:
                value = json.loads(value)
            except ValueError:
                raise InputError(f"{source} is not JSON") from None
        if not (isinstance(value, Mapping) and set(value) == {"simulation", "recipe"}
                and all(isinstance(value[k], Mapping) for k in value)):
            raise InputError(f"{source} is not an object of 'simulation' and 'recipe' objects")
        plain = json.loads(canonical_json(dict(value)))
        return cls(plain["simulation"], plain["recipe"])

    def to_json(self) -> str:
        return canonical_json(asdict(self))

    def differences(self, other: DatasetConfig) -> str:
        """``section.key: file ..., given ...`` for every value that differs."""
        out = []
        for section in ("simulation", "recipe"):
            a, b = getattr(self, section), getattr(other, section)
            out += [f"{section}.{k}: file {a.get(k, '<none>')!r}, given {b.get(k, '<none>')!r}"
                    for k in sorted(set(a) | set(b)) if a.get(k, ...) != b.get(k, ...)]
        return "; ".join(out)


@dataclass(frozen=True)
class Header:
    """The root attributes of a dataset file."""

    config: DatasetConfig
    roughness_version: str
    created: str
    schema_version: int = SCHEMA_VERSION

    def attrs(self) -> dict:
        return {"schema": SCHEMA, "schema_version": self.schema_version, "config": self.config.to_json(),
                "roughness_version": self.roughness_version, "created": self.created}


def header_problems(attrs: Mapping) -> list[str]:
    """What keeps root attributes ``attrs`` from being a dataset header (empty: nothing)."""
    problems = [f"root attribute {name!r} is missing" for name in ROOT_ATTRS if name not in attrs]
    if problems:
        return problems
    if _text(attrs["schema"]) != SCHEMA:
        problems.append(f"schema is {_text(attrs['schema'])!r}, not {SCHEMA!r}")
    elif attrs["schema_version"] not in READABLE_VERSIONS:
        problems.append(f"schema version {attrs['schema_version']} is not one of {READABLE_VERSIONS}")
    try:
        DatasetConfig.parse(_text(attrs["config"]), "root attribute 'config'")
    except InputError as err:
        problems.append(str(err))
    return problems


def read_header(attrs: Mapping, source: str) -> Header:
    """The header of a file from its root attributes; InputError lists every problem."""
    problems = header_problems(attrs)
    if problems:
        raise InputError(f"{source} is not a roughness dataset: {'; '.join(problems)}")
    return Header(DatasetConfig.parse(_text(attrs["config"])), _text(attrs["roughness_version"]),
                  _text(attrs["created"]), int(attrs["schema_version"]))


@dataclass(frozen=True)
class Entry:
    """One sample's row of the index: everything about it except its maps (lengths in mm, times in s)."""

    id: str
    recipe: str  # canonical JSON of the texture record (the file's column name)
    family: str
    status: str  # "ok" | "failed"
    pixel_mm: float
    written: str  # ISO 8601, UTC
    roughness_version: str  # package that wrote the sample
    error: str = ""  # why the simulation failed
    V: float = math.nan
    V_stderr: float = math.nan
    contact_fraction: float = math.nan
    indentation_mm: float = math.nan
    converged: bool = False
    iterations: int = -1
    unresolved_nodes: int = -1
    cycled: bool = False
    seconds: float = math.nan
    contact_history: tuple[int, ...] = field(default=())  # contact node count per round
    discretization_error: float = math.nan  # estimated relative error of V from the mesh (nan: none)
    ladder_h_mm: tuple[float, ...] = field(default=())  # contact spacing of each solved level, coarsest first
    ladder_V: tuple[float, ...] = field(default=())  # V at each of those levels (the last is V)
    restored: bool = False  # result taken from a labels file (dataset.labels): no fluctuation map

    def values(self) -> dict:
        """Scalar values of the sample (Sample.values): results if ok, the error if failed."""
        results = (*(name for name, _ in RESULT_ATTRS.values()), *TUPLE_FIELDS)
        keep = ("pixel_mm", "written", "roughness_version", *(results if self.status == "ok" else ("error",)))
        return {k: list(getattr(self, k)) if k in TUPLE_FIELDS else getattr(self, k) for k in keep}


ENTRY_FIELDS = tuple(f.name for f in fields(Entry))
# Entry fields added to version 2 after it first shipped: absent from older files' index (defaults).
ADDED_FIELDS = ("discretization_error", "ladder_h_mm", "ladder_V", "restored")
TEXT_FIELDS = ("id", "recipe", "family", "status", "written", "roughness_version", "error")


def entry_from_attrs(sid: str, attrs: Mapping) -> Entry:
    """An index entry from a version-1 sample group's attributes (or any mapping of Entry fields)."""
    values = {k: _plain(attrs[k]) for k in ENTRY_FIELDS if k in attrs and k not in ("id", "family")}
    try:
        family = json.loads(values["recipe"])["family"]
        return Entry(id=sid, family=family, **as_tuples(values))
    except (KeyError, TypeError, ValueError):
        raise InputError(f"sample {sid} has no readable recipe, status or pixel size; run verify") from None


def as_tuples(values: dict) -> dict:
    """``values`` with the tuple fields (lists, arrays or absent) as tuples of their element type."""
    return {**values, **{k: tuple(kind(v) for v in values.get(k, ())) for k, kind in TUPLE_FIELDS.items()}}


def ladder_columns(ladder: list) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Spacings (mm) and V of a result's solved levels (``simulate.result.Level`` or their dicts)."""
    rows = [level if isinstance(level, Mapping) else asdict(level) for level in ladder]
    return tuple(float(r["h_contact_mm"]) for r in rows), tuple(float(r["roughness"]) for r in rows)


def _plain(value: object) -> object:
    if isinstance(value, bytes):
        return value.decode()
    return value.tolist() if isinstance(value, (np.generic, np.ndarray)) else value


def _text(value: object) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)
