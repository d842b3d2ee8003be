"""What a dataset holds and whether it is intact: ``info`` (counts, ranges, failures) and ``verify`` (problems)."""
from __future__ import annotations

import json
import math
import os
from collections import Counter
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError

from .layout import MAPS, open_h5, part_ids, parts_folder, read_index, read_part, sample_maps
from .reader import open_dataset
from .schema import OPTIONAL_FLOATS, RESULT_ATTRS, STATUSES, Entry, header_problems, sample_id

__all__ = ["info", "verify"]


def info(path: str | os.PathLike) -> dict:
    """Counts by status and family, value ranges of ok samples, failure reasons and file attributes."""
    with open_dataset(path) as ds:
        table = ds.table()
        ok = table["status"] == "ok"
        families: dict[str, Counter] = {}
        for family, status in zip(table["family"], table["status"]):
            families.setdefault(str(family), Counter())[str(status)] += 1
        return {
            "path": str(ds.path),
            "samples": len(ds),
            **{status: int(np.sum(table["status"] == status)) for status in STATUSES},
            "converged": int(np.sum(table["converged"][ok])),
            "restored": sum(e.restored for e in ds.entries().values()),
            "families": {f: {s: counts[s] for s in STATUSES} for f, counts in sorted(families.items())},
            "V": _span(table["V"][ok]),
            "contact_fraction": _span(table["contact_fraction"][ok]),
            "failure_reasons": dict(Counter(error for _, _, error in ds.failures()).most_common()),
            "roughness_version": ds.header.roughness_version,
            "created": ds.header.created,
            "schema_version": ds.header.schema_version,
        }


def _span(values: np.ndarray) -> list[float] | None:
    return [float(values.min()), float(values.max())] if values.size else None


def verify(path: str | os.PathLike) -> list[str]:
    """Problems found in a dataset (empty: all good), damage included (an index, sample or part file HDF5 or NumPy
    cannot read); InputError if the file is missing or not HDF5 (no dataset to verify)."""
    path = Path(path)
    with open_h5(path) as h5:
        problems = header_problems(h5.attrs)
        if problems:
            return problems
        try:
            _, entries = read_index(h5, path)
        except InputError as err:
            return [str(err)]
        samples = h5.get("samples", {})
        problems += [f"samples/{n}: not in the index (an unfinished sample)" for n in samples if n not in entries]
        for sid, entry in entries.items():
            try:
                maps = sample_maps(h5, sid) if sid in samples else {}
            except InputError as err:
                problems.append(f"samples/{sid}: {err}")
                continue
            problems += [f"samples/{sid}: {p}" for p in _entry_problems(entry, maps)]
    folder = parts_folder(path)
    for sid in part_ids(folder):
        try:
            entry, maps = read_part(folder / f"{sid}.npz")
        except (OSError, InputError) as err:
            problems.append(f"{folder.name}/{sid}.npz: unreadable ({err})")
            continue
        problems += [f"{folder.name}/{sid}.npz: {p}" for p in _entry_problems(entry, maps)]
        if entry.id != sid:
            problems.append(f"{folder.name}/{sid}.npz: holds sample {entry.id}")
    return problems


def _entry_problems(entry: Entry, maps: dict[str, np.ndarray]) -> list[str]:
    """What is wrong with one sample (its texture record is the index column ``recipe``)."""
    try:
        texture_record = json.loads(entry.recipe)
        expected = sample_id(texture_record)
    except (TypeError, ValueError):
        return ["recipe is not a JSON object"]
    problems = [] if expected == entry.id else [f"id does not match its recipe (expected {expected})"]
    if texture_record.get("family") != entry.family:
        problems.append(f"family {entry.family!r} is not the recipe's {texture_record.get('family')!r}")
    if entry.status == "ok":
        for name in ["pixel_mm"] + [n for k, (n, kind) in RESULT_ATTRS.items()
                                    if kind is float and k not in OPTIONAL_FLOATS]:
            if not math.isfinite(getattr(entry, name)):
                problems.append(f"{name} is {getattr(entry, name)}")
        for name in [m for m in MAPS if not (entry.restored and m == "fluctuation")]:
            if name not in maps or maps[name].ndim != 2:
                problems.append(f"{name} is missing or not 2-D")
            elif not np.all(np.isfinite(maps[name])):
                problems.append(f"{name} has non-finite values")
    elif entry.status == "failed":
        if not entry.error:
            problems.append("failed sample without an error message")
    else:
        problems.append(f"status {entry.status!r} is neither 'ok' nor 'failed'")
    return problems
