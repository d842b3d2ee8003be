"""Checksums of a dataset file: the bytes, and the inputs in a form that regeneration reproduces.

The file's own SHA-256 identifies one artifact; it changes with every build (creation times,
completion order). ``inputs_sha256`` hashes, in id order, each sample's id, texture record and
heightmap bytes: a rebuild from the same recipe gives the same value.
"""
from __future__ import annotations

import hashlib
from pathlib import Path

from .reader import open_dataset


def inputs_sha256(path: str | Path) -> str:
    h = hashlib.sha256()
    with open_dataset(path) as ds:
        for sid, texture_record in sorted(zip(ds.ids, ds.texture_records), key=lambda pair: pair[0]):
            h.update(sid.encode())
            h.update(repr(sorted(texture_record.items())).encode())
            try:
                h.update(ds.heightmap(sid).heights.astype("<f4").tobytes())
            except KeyError:  # a failed sample whose texture could not be made
                h.update(b"no heightmap")
    return h.hexdigest()
