"""The package version, from the installed metadata (the src layout: ``roughness`` imports only when installed)."""
from __future__ import annotations

# The release, as provenance records name it without importlib.metadata (~30 ms a fresh process): kept equal to
# pyproject.toml's version and CITATION.cff's by tests/test_provenance.py
RELEASE = "0.1.0"


def package_version() -> str:
    """``roughness``'s installed version (``unknown`` if its metadata is missing, e.g. a copied tree)."""
    from importlib.metadata import PackageNotFoundError, version  # here: ~30 ms that prediction need not pay

    try:
        return version("roughness")
    except PackageNotFoundError:
        return "unknown"
