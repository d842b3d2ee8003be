"""The exported surrogate as a model object (numpy + onnxruntime; torch is never imported).

    model = SurrogateModel()                 # the shipped model
    v, reasons = model.run(np.stack([model.patch(hm)]))
    estimate = model.evaluate(np.stack([model.patch(hm)]))  # also the uncertainty of an ensemble model

Prediction with engine choice and FEM fallback is ``roughness.predict`` (roughness.prediction).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import onnxruntime as ort

from roughness.core.checks import file_path
from roughness.core.errors import InputError
from roughness.core.limits import MAX_MODEL_FILE_BYTES, check_size
from roughness.core.provenance import model_id
from roughness.models import MODELS_DIR
from roughness.surface.heightmap import Heightmap, flat

from .domain import Domain
from .metadata import ModelMetadata, read_metadata, require_model_file
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
        """Load and check the model at ``path``: its metadata (``read_metadata``), its graph's inputs and
        outputs, and one finite answer for a flat patch; InputError for ``model`` if any is wrong.
        ``threads``: onnxruntime's threads per call (a roughness map runs threads + 1 batches at once instead, each
        on one thread: ``single_threaded``)."""
        path = file_path("model", path)
        require_model_file(path)
        check_size(f"bytes of the surrogate model {path} (read whole)", path.stat().st_size, MAX_MODEL_FILE_BYTES,
                   "model")
        self.threads = threads
        try:
            data = path.read_bytes()  # hashed and loaded from the same bytes: the id is of what answers
        except OSError as err:
            raise InputError(f"cannot read the surrogate model {path}: {err.strerror}", parameter="model") from None
        self.model_id = model_id(data)
        self._data, self._single_threaded = data, None
        try:
            self.session = _session(data, threads)
        except Exception as err:
            raise InputError(f"{path} is not a loadable ONNX model: {err}", parameter="model") from None
        self.path = path
        self.meta: ModelMetadata = read_metadata(self.session.get_modelmeta().custom_metadata_map, path)
        version = self.session.get_modelmeta().version  # onnxruntime reads an unset model_version as 2**63 - 1
        self.model_version = int(version) if 0 <= version < 2**63 - 1 else 0  # the ONNX model_version (0: unset)
        self.domain = Domain.from_dict(self.meta.domain)
        self.pixel_mm = float(self.meta.patch_pixel_mm)
        self.footprint_mm = float(self.meta.footprint_mm)
        self.fidelity = str(self.meta.label_fidelity)
        self.outputs = [o.name for o in self.session.get_outputs()]
        self.has_std = STD_OUTPUT in self.outputs  # an ensemble graph (ensemble.py)
        self._check_signature()
        self._check_answers()  # also pays the one-time set-up costs

    def single_threaded(self) -> SurrogateModel:
        """This model on a one-thread onnxruntime session (itself if it has one), to run batches side by side on
        several Python threads, each on its own core (roughness maps)."""
        if self.threads == 1:
            return self
        if self._single_threaded is None:
            single = copy.copy(self)
            single.session, single.threads, single._single_threaded = _session(self._data, 1), 1, single
            self._single_threaded = single
        return self._single_threaded

    def _refuse(self, problem: str) -> InputError:
        return InputError(f"{self.path} is not a usable roughness model: {problem}", parameter="model")

    def _check_signature(self) -> None:
        """One input ``heights`` (batch, 1, P, P) float32 with P from the metadata; outputs ``log_roughness``
        (batch,) and ``embedding`` (batch, E) with E the domain's size, ``log_roughness_std`` (batch,) optional."""
        size, embedding = self.meta.patch_size, len(self.domain.mean)
        inputs = self.session.get_inputs()
        if [i.name for i in inputs] != [INPUT]:
            raise self._refuse(f"its graph takes {', '.join(i.name for i in inputs) or 'no input'}, not one input "
                               f"{INPUT!r}")
        expected = {INPUT: ("(batch, 1, P, P)", [None, 1, size, size])}
        expected[LOG_OUTPUT] = ("(batch,)", [None])
        expected[EMBEDDING_OUTPUT] = ("(batch, E)", [None, embedding])
        if self.has_std:
            expected[STD_OUTPUT] = ("(batch,)", [None])
        missing = [name for name in (LOG_OUTPUT, EMBEDDING_OUTPUT) if name not in self.outputs]
        if missing:
            raise self._refuse(f"its graph lacks the output(s) {', '.join(missing)} (has {', '.join(self.outputs)})")
        for arg in (*inputs, *self.session.get_outputs()):
            if arg.name not in expected:
                continue
            shape, dims = expected[arg.name]
            fits = len(arg.shape) == len(dims) and all(
                isinstance(got, int) == (want is not None) and (want is None or got == want)
                for got, want in zip(arg.shape, dims))
            if arg.type != "tensor(float)" or not fits:
                raise self._refuse(f"{arg.name} is {arg.type} of shape {arg.shape}, expected float32 {shape} with a "
                                   f"free batch axis, P = {size} (footprint_mm / patch_pixel_mm) and E = {embedding} "
                                   "(the size of its domain's embedding)")

    def _check_answers(self) -> None:
        """Two flat patches give finite outputs of the declared shapes."""
        flat_patch = self.patch(flat(self.footprint_mm + 1.0, self.pixel_mm / 2))
        try:
            out = dict(zip(self.outputs, self.session.run(None, {INPUT: np.stack([flat_patch] * 2)[:, None]})))
        except Exception as err:
            raise self._refuse(f"it fails on a flat patch: {err}") from None
        for name, shape in ((LOG_OUTPUT, (2,)), (EMBEDDING_OUTPUT, (2, len(self.domain.mean))),
                            *([(STD_OUTPUT, (2,))] if self.has_std else [])):
            value = np.asarray(out[name])
            negative = name == STD_OUTPUT and np.any(value < 0)
            if value.shape != shape or not np.all(np.isfinite(value)) or negative:
                got = value.tolist() if value.size < 5 else f"of shape {value.shape}"
                raise self._refuse(f"its {name} for two flat patches is {got}, not {'x'.join(map(str, shape))} "
                                   f"finite numbers{' >= 0' if name == STD_OUTPUT else ''}")

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
        relative = out[STD_OUTPUT].astype(np.float64) if self.has_std else None
        bad = ~np.isfinite(log_v)
        if relative is not None:
            bad |= ~(np.isfinite(relative) & (relative >= 0))
        if bad.any():
            raise self._refuse(f"it answered a non-finite V (or a negative or non-finite spread) for {int(bad.sum())} "
                               f"of {len(bad)} patches")
        v = roughness_from_log(log_v, self.meta.log_offset)
        spread = None if relative is None else np.exp(log_v) * relative
        if descriptors is None:
            descriptors = batch_descriptors(patches, self.pixel_mm)
        reasons = self.domain.check(descriptors, out[EMBEDDING_OUTPUT])
        return Estimate(v, spread, relative, reasons)


def _session(data: bytes, threads: int) -> ort.InferenceSession:
    """An onnxruntime CPU session of the ONNX bytes ``data`` on ``threads`` intra-op threads."""
    options = ort.SessionOptions()
    options.intra_op_num_threads = threads  # explicit: the default counts the host's cores
    options.inter_op_num_threads = 1
    return ort.InferenceSession(data, options, providers=["CPUExecutionProvider"])
