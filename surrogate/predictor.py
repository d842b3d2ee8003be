"""The exported surrogate as a model object (numpy + onnxruntime; torch is never imported).

    model = SurrogateModel()                 # the shipped model
    v, reasons = model.run(np.stack([model.patch(hm)]))
    estimate = model.evaluate(np.stack([model.patch(hm)]))  # also the uncertainty of an ensemble model

Prediction with engine choice and FEM fallback is roughness.engines.predict (``roughness.predict``).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import onnxruntime as ort

from roughness.core.errors import InputError
from roughness.models import MODELS_DIR
from roughness.simulate.heightmap import Heightmap, flat

from .domain import Domain
from .metadata import ModelMetadata, read_metadata
from .patch import batch_descriptors, footprint_patch
from .target import roughness_from_log

DEFAULT_MODEL = MODELS_DIR / "roughness-cnn.onnx"
INPUT = "heights"  # the graph's input: (batch, 1, P, P) float32 heights in mm
LOG_OUTPUT, STD_OUTPUT, EMBEDDING_OUTPUT = "log_roughness", "log_roughness_std", "embedding"


@dataclass
class Estimate:
    """The surrogate's answer for a batch of patches."""

    roughness: np.ndarray  # (n,) V
    roughness_std: np.ndarray | None  # (n,) standard deviation of V over the ensemble; None: a single network
    relative_std: np.ndarray | None  # (n,) roughness_std / (V + log_offset): the spread of log(V + offset)
    reasons: list[list[str]]  # per input, why it is out of domain (empty: in domain)


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
        self.outputs = [o.name for o in self.session.get_outputs()]
        self.has_std = STD_OUTPUT in self.outputs  # an ensemble graph (ensemble.py)
        self.run(self.patch(flat(self.footprint_mm + 1.0, self.pixel_mm / 2))[None])  # one-time set-up costs

    def patch(self, heightmap: Heightmap, centre_mm: tuple[float, float] | None = None, tile: bool = False) -> np.ndarray:
        """The model's input for a heightmap: footprint heights (mm, max 0) on its pixel grid."""
        return footprint_patch(heightmap, centre_mm, tile, self.pixel_mm, self.footprint_mm)

    def run(self, patches: np.ndarray) -> tuple[np.ndarray, list[list[str]]]:
        """V and out-of-domain reasons for patches (n, P, P) from ``patch``."""
        estimate = self.evaluate(patches)
        return estimate.roughness, estimate.reasons

    def evaluate(self, patches: np.ndarray, descriptors: np.ndarray | None = None) -> Estimate:
        """V, its ensemble spread (if the model is an ensemble) and out-of-domain reasons for patches (n, P, P).

        ``descriptors``: the patches' ``batch_descriptors``, if already computed. The spread of V is first
        order in the members' spread of log(V + offset): (V + offset) x that spread.
        """
        patches = np.ascontiguousarray(patches, dtype=np.float32)
        if patches.ndim != 3 or not np.all(np.isfinite(patches)):
            raise InputError(f"patches must be a finite (n, P, P) array, got shape {patches.shape}")
        out = dict(zip(self.outputs, self.session.run(None, {INPUT: patches[:, None]})))
        log_v = out[LOG_OUTPUT].astype(np.float64)
        v = roughness_from_log(log_v, self.meta.log_offset)
        relative = out[STD_OUTPUT].astype(np.float64) if self.has_std else None
        spread = None if relative is None else np.exp(log_v) * relative
        if descriptors is None:
            descriptors = batch_descriptors(patches, self.pixel_mm)
        reasons = self.domain.check(descriptors, out[EMBEDDING_OUTPUT])
        return Estimate(v, spread, relative, reasons)
