"""roughness: predicted tactile roughness of surface textures (after Tymms, Gardner & Zorin 2018)."""
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("roughness")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0.0.0+source"
