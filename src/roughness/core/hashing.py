"""Content hashes: results and caches are keyed by what they depend on, never by a file name."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np


def canonical_json(value: object) -> str:
    """Compact JSON with sorted keys; numpy scalars and arrays become plain numbers and lists."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False, default=_plain_json)


def _plain_json(value: object) -> object:
    if isinstance(value, (np.generic, np.ndarray)):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def digest(value: object, length: int = 16) -> str:
    """The first ``length`` hex digits of the SHA-1 of ``value``'s canonical JSON (key order ignored)."""
    return hashlib.sha1(canonical_json(value).encode()).hexdigest()[:length]


def array_digest(array: np.ndarray, *scalars: float, length: int = 16) -> str:
    """Digest of an array's values (as little-endian float64, with its shape) and some scalars."""
    h = hashlib.sha1()
    a = np.ascontiguousarray(array, dtype="<f8")
    h.update(repr(a.shape).encode())
    h.update(a.tobytes())
    h.update(canonical_json([float(s) for s in scalars]).encode())
    return h.hexdigest()[:length]


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()
