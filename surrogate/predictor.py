"""Roughness prediction with the ONNX surrogate (numpy + onnxruntime; torch is never imported).

    from roughness.surrogate import predict
    [p] = predict(heightmap)            # engine "auto": surrogate, FEM where out of domain
    p.roughness, p.in_domain, p.placement.equivalent_lambda_mm

Engines: ``surrogate`` (milliseconds), ``fem`` (the reference; seconds) and ``auto`` (the
surrogate, falling back to FEM for inputs outside the model's domain). The FEM runs at the
fidelity the model was trained on unless told otherwise, so the engines share one scale;
equivalent wavelengths are always read off the standard scale of the engine's fidelity.
"""
from __future__ import annotations

import itertools
import json
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import onnxruntime as ort

from roughness.core.errors import InputError
from roughness.models import MODELS_DIR
from roughness.simulate.heightmap import Heightmap, flat

from .calibration import Placement, load_scale
from .domain import Domain
from .patch import descriptors, footprint_patch

DEFAULT_MODEL = MODELS_DIR / "roughness-cnn.onnx"
ENGINES = ("surrogate", "fem", "auto")
METADATA_KEY = "roughness"  # ONNX metadata_props key of the model's JSON metadata
INPUT = "heights"  # the graph's input: (batch, 1, P, P) float32 heights in mm


@dataclass
class Prediction:
    """Roughness V (dimensionless strain variation) of one input and how it was obtained."""

    source: str
    roughness: float
    engine: str  # "surrogate" or "fem"
    fidelity: str  # FEM fidelity of the engine's scale (for the surrogate: of its training labels)
    in_domain: bool
    seconds: float  # wall time spent on this input (batched surrogate time is shared out)
    placement: Placement
    domain_notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"input": self.source, "roughness": self.roughness, "engine": self.engine, "fidelity": self.fidelity,
                "in_domain": self.in_domain, "seconds": self.seconds, **self.placement.as_dict(),
                "domain_notes": self.domain_notes}


class SurrogateModel:
    """An exported surrogate: onnxruntime session, input domain and metadata."""

    def __init__(self, path: str | Path = DEFAULT_MODEL, threads: int = 1) -> None:
        path = Path(path)
        if not path.is_file():
            raise InputError(f"surrogate model not found: {path}")
        options = ort.SessionOptions()
        options.intra_op_num_threads = threads  # explicit: the default counts the host's cores
        options.inter_op_num_threads = 1
        try:
            self.session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
        except Exception as err:
            raise InputError(f"{path} is not a loadable ONNX model: {err}") from None
        props = self.session.get_modelmeta().custom_metadata_map
        if METADATA_KEY not in props:
            raise InputError(f"{path} is an ONNX model without roughness metadata (export it with `roughness export`)")
        self.path = path
        self.meta = json.loads(props[METADATA_KEY])
        self.domain = Domain.from_dict(self.meta["domain"])
        self.pixel_mm = float(self.meta["patch_pixel_mm"])
        self.footprint_mm = float(self.meta["footprint_mm"])
        self.fidelity = str(self.meta["label_fidelity"])
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
        v = np.maximum(np.exp(log_v.astype(float)) - self.meta["log_offset"], 0.0)
        return v, self.domain.check(np.array([descriptors(p, self.pixel_mm) for p in patches]), embedding)


def predict(heightmaps: Heightmap | Iterable[Heightmap], engine: str = "auto",
            model: SurrogateModel | str | Path | None = None, centre_mm: tuple[float, float] | None = None,
            tile: bool = False, fidelity: str | None = None, batch_size: int = 256,
            sources: Iterable[str] | None = None,
            on_result: Callable[[Prediction], None] | None = None) -> list[Prediction]:
    """Predict V for each heightmap (mm); see the module docstring for the engines.

    ``fidelity`` is the FEM's (default: the model's training labels'). ``sources`` names the
    inputs in the results; ``on_result`` is called as each result is ready.
    """
    if engine not in ENGINES:
        raise InputError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}")
    if batch_size < 1:
        raise InputError(f"batch size must be at least 1, got {batch_size}")
    model = model if isinstance(model, SurrogateModel) else SurrogateModel(model or DEFAULT_MODEL)
    fem = FemFallback({**model.meta["simulation"], "fidelity": fidelity or model.fidelity}, centre_mm, tile)
    scale = load_scale(model.fidelity)
    names = iter(sources) if sources is not None else (f"heightmap {i}" for i in itertools.count())
    results: list[Prediction] = []
    batch: list[tuple[str, Heightmap]] = []

    def flush() -> None:
        start = time.perf_counter()
        values, reasons = model.run(np.stack([model.patch(hm, centre_mm, tile) for _, hm in batch]))
        share = (time.perf_counter() - start) / len(batch)
        for (source, hm), v, why in zip(batch, values, reasons):
            if engine == "fem" or (engine == "auto" and why):
                result = fem(source, hm, not why, why)
            else:
                result = Prediction(source, float(v), "surrogate", model.fidelity, not why, share,
                                    scale.place(float(v)), why)
            results.append(result)
            if on_result:
                on_result(result)
        batch.clear()

    for hm in [heightmaps] if isinstance(heightmaps, Heightmap) else heightmaps:
        batch.append((next(names), hm))
        if len(batch) >= batch_size:
            flush()
    if batch:
        flush()
    return results


class FemFallback:
    """The FEM reference with the model's simulation parameters, built on first use."""

    def __init__(self, config: dict, centre_mm: tuple[float, float] | None, tile: bool) -> None:
        self.config, self.fidelity, self.centre_mm, self.tile = config, config["fidelity"], centre_mm, tile
        self.scale = load_scale(self.fidelity)
        self._simulator = None

    def __call__(self, source: str, heightmap: Heightmap, in_domain: bool, notes: list[str]) -> Prediction:
        from roughness.simulate.config import SimConfig
        from roughness.simulate.model import Simulator

        if self._simulator is None:
            self._simulator = Simulator(SimConfig(**self.config))
        start = time.perf_counter()
        v = self._simulator.run(heightmap, self.centre_mm, self.tile).roughness
        return Prediction(source, v, "fem", self.fidelity, in_domain, time.perf_counter() - start,
                          self.scale.place(v), notes)
