"""roughness: predicted tactile roughness of surface textures (after Tymms, Gardner & Zorin 2018)."""
from importlib.metadata import PackageNotFoundError, version


def _source_version() -> str:
    """Version from pyproject.toml when running from a source tree (not installed)."""
    import tomllib
    from pathlib import Path

    try:
        with open(Path(__file__).parents[1] / "pyproject.toml", "rb") as f:
            return tomllib.load(f)["project"]["version"] + "+source"
    except (OSError, KeyError, tomllib.TOMLDecodeError):
        return "unknown"


try:
    __version__ = version("roughness")
except PackageNotFoundError:
    __version__ = _source_version()
