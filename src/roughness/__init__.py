"""roughness: predicted tactile roughness of surface textures (after Tymms, Gardner & Zorin 2018).

The public Python API, loaded on first use (``import roughness`` is cheap; prediction loads
no FEM stack and no torch)::

    import numpy as np
    import roughness

    hm = roughness.standard_texture(1.0)          # bumps 1 mm apart, 12 mm square (files: load_heightmap)
    [p] = roughness.predict(hm)                   # the surrogate, climbing to physics where unsure
    print(p)                                      # V, its spread, the engine, the place on the standard scale
    [q] = roughness.predict(np.asarray(hm.heights), pixel_mm=hm.pixel_mm)  # any 2-D array of heights (mm)
    named = roughness.predict({"fine": roughness.standard_texture(0.75), "coarse": hm},
                              options=roughness.PredictOptions(tile=True))  # periodic tiles, answers by name
    r = roughness.fem_roughness(hm, fidelity="coarse")  # the FEM reference: r.roughness, r.roughness_stderr
    m = roughness.predict_map(hm, engine="spectral", tile=True, step_mm=4.0)  # m.map: V over it (Dask: client=)

Design tools and perception analysis with plain arguments: ``tune``, ``palette``, ``tactile_image``,
``homogeneity``, ``embed_trials``, ``fit_embedding``. Plot functions return ``matplotlib.figure.Figure``
objects and never change the backend.

Subpackages: ``roughness.simulate`` (FEM), ``roughness.dataset`` (textures, HDF5 datasets),
``roughness.surrogate`` (CNN, ONNX), ``roughness.models`` (shipped models).
"""
from __future__ import annotations

from importlib import import_module

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (type checkers take this name as True)
if TYPE_CHECKING:  # what type checkers and IDEs see; at run time the names load on first use (``__getattr__``)
    from roughness.core.errors import InputError, SimulationError
    from roughness.dataset.reader import open_dataset
    from roughness.dataset.textures import named_texture, standard_texture
    from roughness.design.api import homogeneity, palette, tactile_image, tune
    from roughness.maps import MapPrediction, predict_map
    from roughness.perception.api import embed_trials, fit_embedding
    from roughness.perceptual_scale import StandardScale, load_scale
    from roughness.prediction import CurvedBase, Prediction, PredictOptions, predict
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator
    from roughness.simulate.model import roughness as fem_roughness
    from roughness.simulate.result import Result
    from roughness.surface.arguments import as_heightmap
    from roughness.surface.heightmap import Heightmap
    from roughness.surface.io import load_heightmap, save_heightmap

    __version__: str

_HOMES = {
    "Heightmap": "roughness.surface.heightmap",
    "as_heightmap": "roughness.surface.arguments",
    "InputError": "roughness.core.errors",
    "SimulationError": "roughness.core.errors",
    "load_heightmap": "roughness.surface.io",
    "save_heightmap": "roughness.surface.io",
    "SimConfig": "roughness.simulate.config",
    "Simulator": "roughness.simulate.model",
    "Result": "roughness.simulate.result",
    "fem_roughness": "roughness.simulate.model:roughness",
    "predict": "roughness.prediction",
    "PredictOptions": "roughness.prediction",
    "CurvedBase": "roughness.prediction",
    "Prediction": "roughness.prediction",
    "predict_map": "roughness.maps",
    "MapPrediction": "roughness.maps",
    "StandardScale": "roughness.perceptual_scale",
    "load_scale": "roughness.perceptual_scale",
    "standard_texture": "roughness.dataset.textures",
    "named_texture": "roughness.dataset.textures",
    "open_dataset": "roughness.dataset.reader",
    "tune": "roughness.design.api",
    "palette": "roughness.design.api",
    "tactile_image": "roughness.design.api",
    "homogeneity": "roughness.design.api",
    "embed_trials": "roughness.perception.api",
    "fit_embedding": "roughness.perception.api",
}

# subpackages offered to tab completion, imported on first use like the names above
_SUBPACKAGES = ("dataset", "design", "perception", "simulate", "surface", "surrogate")

__all__ = sorted(_HOMES) + ["__version__"]


def __getattr__(name: str) -> object:
    if name == "__version__":  # read on first use: importlib.metadata costs ~30 ms at start-up
        from .core.version import package_version

        return package_version()
    if name in _SUBPACKAGES:
        return import_module(f"{__name__}.{name}")
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module, _, attr = _HOMES[name].partition(":")
    return getattr(import_module(module), attr or name)


def __dir__() -> list[str]:
    """The public API beside the module's own attributes, for tab completion and ``help()``."""
    own = {name for name in globals() if name.startswith("__")}
    return sorted(own | set(__all__) | set(_SUBPACKAGES))
