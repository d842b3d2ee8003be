"""The exported surrogate as a model object (numpy + onnxruntime; torch is never imported).

    model = SurrogateModel()                 # the shipped model
    v, reasons = model.run(np.stack([model.patch(hm)]))

Prediction with engine choice and FEM fallback is roughness.engines.predict (``roughness.predict``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import onnxruntime as ort

from roughness.core.errors import InputError
from roughness.models import MODELS_DIR
from roughness.simulate.heightmap import Heightmap, flat

from .domain import Domain
from .metadata import ModelMetadata, read_metadata
from .patch import descriptors, footprint_patch
from .target import roughness_from_log

DEFAULT_MODEL = MODELS_DIR / "roughness-cnn.onnx"
INPUT = "heights"  # the graph's input: (batch, 1, P, P) float32 heights in mm


class SurrogateModel:
    """An exported surrogate: onnxruntime session, input domain and metadata."""

    def __init__(self, path: str | Path = DEFAULT_MODEL, threads: int = 1) -> None:
        path = Path(path)
        if not path.is_file():
            raise InputError(f"surrogate model not found: {path}", parameter="model")
        options = ort.SessionOptions()
        options.intra_op_num_threads = threads  # explicit: the default counts the host's cores
        options.inter_op_num_threads = 1
        try:
            self.session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
        except Exception as err:
            raise InputError(f"{path} is not a loadable ONNX model: {err}", parameter="model") from None
        self.path = path
        self.meta: ModelMetadata = read_metadata(self.session.get_modelmeta().custom_metadata_map, path)
        self.domain = Domain.from_dict(self.meta.domain)
        self.pixel_mm = float(self.meta.patch_pixel_mm)
        self.footprint_mm = float(self.meta.footprint_mm)
        self.fidelity = str(self.meta.label_fidelity)
        self.run(self.patch(flat(self.footprint_mm + 1.0, self.pixel_mm / 2))[None])  # one-time set-up costs

    def patch(self, heightmap: Heightmap, centre_mm: tuple[float, float] | None = None, tile: bool = False) -> np.ndarray:
        """The model's input for a heightmap: footprint heights (mm, max 0) on its pixel grid."""
        return footprint_patch(heightmap, centre_mm, tile, self.pixel_mm, self.footprint_mm)

    def run(self, patches: np.ndarray) -> tuple[np.ndarray, list[list[str]]]:
        """V and out-of-domain reasons for patches (n, P, P) from ``patch``."""
        patches = np.ascontiguousarray(patches, dtype=np.float32)
        if patches.ndim != 3 or not np.all(np.isfinite(patches)):
            raise InputError(f"patches must be a finite (n, P, P) array, got shape {patches.shape}")
        log_v, embedding = self.session.run(None, {INPUT: patches[:, None]})
        v = roughness_from_log(log_v, self.meta.log_offset)
        return v, self.domain.check(np.array([descriptors(p, self.pixel_mm) for p in patches]), embedding)
