"""The package version: installed metadata, or pyproject.toml in a source tree."""
from __future__ import annotations

from pathlib import Path

import tomllib

SOURCE_ROOT = Path(__file__).resolve().parents[2]
# The release, as provenance records name it without importlib.metadata (~30 ms a fresh process): kept equal to
# pyproject.toml's version and CITATION.cff's by tests/test_provenance.py
RELEASE = "0.1.0"


def package_version() -> str:
    """``roughness``'s version; ``X+source`` when running from a checkout that is not installed."""
    from importlib.metadata import PackageNotFoundError, version  # here: ~30 ms that prediction need not pay

    try:
        return version("roughness")
    except PackageNotFoundError:
        try:
            with open(SOURCE_ROOT / "pyproject.toml", "rb") as f:
                return tomllib.load(f)["project"]["version"] + "+source"
        except (OSError, KeyError, tomllib.TOMLDecodeError):
            return "unknown"
