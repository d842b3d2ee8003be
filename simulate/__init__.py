"""FEM reference engine: skin block on a rigid texture, strain at receptor depth, variation V.

Names are imported on first use, so ``Heightmap`` (from ``roughness.surface``) loads without the FEM stack.
"""
from importlib import import_module

_HOMES = {"SimConfig": ".config", "Heightmap": "roughness.surface.heightmap",
          "InputError": "roughness.surface.heightmap", "load_heightmap": "roughness.surface.io",
          "save_heightmap": "roughness.surface.io", "Result": ".result", "SimulationError": ".model",
          "Simulator": ".model", "roughness": ".model"}

__all__ = sorted(_HOMES)


def __getattr__(name: str) -> object:
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(_HOMES[name], __name__), name)
