"""Labels files: a dataset's FEM results without its maps, small enough to commit beside the recipe.

A build's cost is its FEM runs; its heightmaps are made again from the recipe in milliseconds.
A labels file keeps what the FEM computed (every index entry but the texture record) with a digest
of each sample's heightmap, so ``build(..., labels=...)`` remakes a dataset without the FEM:
a sample whose id (the hash of its texture record), configuration and remade heightmap all match
a label takes it; any other sample is simulated. Restored samples have no strain fluctuation map
(``Entry.restored``); nothing in training reads it.

Format: gzip (no name, no time stamp: the same labels give the same bytes) of JSON lines; the
first line is the header ``{"schema": "roughness.labels", "version": 1, "config": DatasetConfig,
"samples": n}``, then one line per sample, sorted by id: ``{"id", "heights", "entry"}``
(``heights``: ``heights_digest`` of the stored heightmap, "" if none; ``entry``: the Entry
fields except id, recipe and family).
"""
from __future__ import annotations

import gzip
import io
import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.core.files import atomic_write, check_output
from roughness.core.hashing import array_digest

from .reader import open_dataset
from .schema import ENTRY_FIELDS, TUPLE_FIELDS, DatasetConfig

SCHEMA = "roughness.labels"
VERSION = 1
KEPT_FIELDS = tuple(f for f in ENTRY_FIELDS if f not in ("id", "recipe", "family", "restored"))


def heights_digest(heights: np.ndarray, pixel_mm: float) -> str:
    """Digest of a heightmap as stored (float32 values, shape) and its pixel size (mm)."""
    return array_digest(np.asarray(heights, dtype=np.float32), pixel_mm)


@dataclass(frozen=True)
class Label:
    """One sample's stored FEM result: its Entry values and the digest of the heightmap it was made on."""

    heights: str
    values: dict  # Entry fields except id, recipe and family


@dataclass(frozen=True)
class LabelSet:
    """The labels of one dataset configuration, by sample id."""

    config: DatasetConfig
    labels: dict[str, Label]

    def __len__(self) -> int:
        return len(self.labels)


def export_labels(dataset: str | os.PathLike, out: str | os.PathLike, overwrite: bool = False) -> LabelSet:
    """Write the labels of every sample of ``dataset`` to ``out`` (``.jsonl.gz``); returns them."""
    out = check_output(out, overwrite)
    with open_dataset(dataset) as ds:
        entries = ds.entries()
        labels = {}
        for sid, entry in entries.items():
            try:
                heights = ds.heightmap(sid)
                digest = heights_digest(heights.heights, heights.pixel_mm)
            except KeyError:  # a failed sample whose texture could not be made
                digest = ""
            values = {k: list(v) if k in TUPLE_FIELDS else v for k, v in asdict(entry).items() if k in KEPT_FIELDS}
            labels[sid] = Label(digest, values)
        result = LabelSet(ds.config, labels)
    atomic_write(out, lambda tmp: Path(tmp).write_bytes(_encode(result)), overwrite)
    return result


def load_labels(path: str | os.PathLike) -> LabelSet:
    """Read a labels file; InputError says what is wrong with it."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path} is a folder, not a labels file", parameter="labels")
    if not path.is_file():
        raise InputError(f"no labels file {path}", parameter="labels")
    try:
        lines = gzip.decompress(path.read_bytes()).decode().splitlines()
        header = json.loads(lines[0])
    except (OSError, EOFError, UnicodeDecodeError, ValueError, IndexError):
        raise InputError(f"{path} is not a gzip file of JSON lines (a labels file)", parameter="labels") from None
    if not isinstance(header, dict) or header.get("schema") != SCHEMA or header.get("version") != VERSION:
        raise InputError(f"{path} is not a roughness labels file of version {VERSION}", parameter="labels")
    config = DatasetConfig.parse(header.get("config"), f"{path}: its configuration")
    labels = {}
    try:
        for line in lines[1:]:
            row = json.loads(line)
            values = {k: (math.nan if v is None else v) for k, v in row["entry"].items()}
            if set(values) != set(KEPT_FIELDS):
                raise KeyError(sorted(set(KEPT_FIELDS) ^ set(values)))
            labels[row["id"]] = Label(str(row["heights"]), values)
    except (ValueError, KeyError, TypeError) as err:
        raise InputError(f"{path}: a sample line is damaged ({err})", parameter="labels") from None
    if len(labels) != header.get("samples"):
        raise InputError(f"{path} holds {len(labels)} samples, its header says {header.get('samples')}: "
                         "the file is truncated or edited", parameter="labels")
    return LabelSet(config, labels)


def _encode(labels: LabelSet) -> bytes:
    text = io.StringIO()
    header = {"schema": SCHEMA, "version": VERSION, "config": json.loads(labels.config.to_json()),
              "samples": len(labels)}
    text.write(json.dumps(header, sort_keys=True) + "\n")
    for sid in sorted(labels.labels):
        label = labels.labels[sid]
        entry = {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in label.values.items()}
        text.write(json.dumps({"id": sid, "heights": label.heights, "entry": entry}, sort_keys=True) + "\n")
    return gzip.compress(text.getvalue().encode(), compresslevel=9, mtime=0)
