"""The package version: installed metadata, or pyproject.toml in a source tree."""
from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import tomllib

SOURCE_ROOT = Path(__file__).resolve().parents[2]


def package_version() -> str:
    """``roughness``'s version; ``X+source`` when running from a checkout that is not installed."""
    try:
        return version("roughness")
    except PackageNotFoundError:
        try:
            with open(SOURCE_ROOT / "pyproject.toml", "rb") as f:
                return tomllib.load(f)["project"]["version"] + "+source"
        except (OSError, KeyError, tomllib.TOMLDecodeError):
            return "unknown"
