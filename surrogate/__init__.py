"""CNN surrogate of the FEM roughness: training (torch), ONNX export, the model (numpy + onnxruntime).

Prediction with engine choice is ``roughness.predict`` (roughness.engines); names load on first use.
"""
from importlib import import_module

_HOMES = {"SurrogateModel": "predictor", "DEFAULT_MODEL": "predictor", "ModelMetadata": "metadata"}

__all__ = sorted(_HOMES)


def __getattr__(name: str) -> object:
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f".{_HOMES[name]}", __name__), name)
