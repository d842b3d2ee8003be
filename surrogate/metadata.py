"""The model metadata: what `train` writes into the checkpoint, `export` embeds in the ONNX file
(JSON under the metadata key ``roughness``) and the predictor, quantiser, card and CLI read.

One frozen dataclass and one reader; a missing or unknown key, or a value of the wrong type or out of
its domain, is an InputError that names it (for the ``model`` or ``checkpoint`` the metadata came from).
"""
from __future__ import annotations

import json
import math
import numbers
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING

from roughness.core.errors import InputError

if TYPE_CHECKING:
    import onnx

METADATA_KEY = "roughness"  # ONNX metadata_props key of the model's JSON metadata
OPTIONAL = ("int8", "ensemble", "multi_fidelity")  # keys only some models have
MAX_STAGES, MAX_CHANNELS = 16, 4096  # network size limits: convolution stages, channels (or units) per layer
MAX_PATCH_SIZE = 1000  # pixels along a side of the input patch (the shipped models: 100)


@dataclass(frozen=True)
class ModelMetadata:
    """Everything prediction needs besides the weights, and how the model was made."""

    widths: tuple[int, ...]  # channels per convolution stage
    hidden: int  # units of the hidden dense layer
    patch_pixel_mm: float  # pixel size of the input patch (mm)
    footprint_mm: float  # side of the square skin footprint (mm)
    log_offset: float  # the network predicts log(V + log_offset)
    label_fidelity: str  # FEM fidelity of the training labels
    simulation: dict  # SimConfig of the training labels (as_dict)
    domain: dict  # Domain.to_dict() of the training inputs
    metrics: dict  # scores per split: train, val, test, ood
    test_by_family: dict  # scores of the test split per family
    holdout_family: str | None  # family never trained on (None: none held out)
    test_fraction: float  # share of base textures in the test split
    data: dict  # training data: file, recipe, inputs_sha256
    train_config: dict  # TrainConfig as a dict
    best_epoch: int
    epochs: int
    minutes: float  # wall-clock training time
    parameters: int  # trainable parameters
    cost_core_seconds: dict  # {"data_fem": s, "training": s}: core-seconds spent making the model
    int8: dict | None = None  # quantisation check of an int8 model (quantize.py); None for fp32
    ensemble: dict | None = None  # members and uncertainty checks of an ensemble graph (ensemble.py); None: one net
    # A network trained on labels of several mesh levels with the spacing as an input (train.py):
    # {"query_h_mm": spacing it answers for, "rows_by_h_mm": labels per spacing, "extra_data": [files],
    #  "engines": engines of the labels (v3 on: "fem" and "spectral" when both)}
    multi_fidelity: dict | None = None

    @property
    def query_h_mm(self) -> float | None:
        """The contact spacing (mm) a multi-fidelity network answers for (None: a one-level network)."""
        return None if self.multi_fidelity is None else float(self.multi_fidelity["query_h_mm"])

    @property
    def engine_input(self) -> bool:
        """Whether the network learned spectral and FEM labels together (the engine an input of its head)."""
        return self.multi_fidelity is not None and len(self.multi_fidelity.get("engines", ["fem"])) > 1

    def to_dict(self) -> dict:
        """Plain JSON-able dict; the OPTIONAL keys only when present."""
        out = asdict(self) | {"widths": list(self.widths)}
        return {k: v for k, v in out.items() if k not in OPTIONAL or v is not None}

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @property
    def patch_size(self) -> int:
        """Pixels P along each side of the input patch (footprint_mm / patch_pixel_mm)."""
        return round(self.footprint_mm / self.patch_pixel_mm)

    @classmethod
    def from_dict(cls, data: dict, source: str = "model metadata", parameter: str | None = None) -> ModelMetadata:
        """Metadata from a dict; InputError (for ``parameter``) names missing and unknown keys and bad values."""
        if not isinstance(data, dict):
            raise InputError(f"{source}: metadata must be a JSON object, got {type(data).__name__}", parameter)
        names = {f.name for f in fields(cls)}
        required = {f.name for f in fields(cls) if f.name not in OPTIONAL}
        missing, unknown = sorted(required - set(data)), sorted(set(data) - names)
        if missing or unknown:
            raise InputError(f"{source}: not roughness model metadata of this version"
                             + (f"; missing keys: {', '.join(missing)}" if missing else "")
                             + (f"; unknown keys: {', '.join(unknown)}" if unknown else ""), parameter)
        problems = _problems(data)
        if problems:
            raise InputError(f"{source}: bad model metadata: {'; '.join(problems)}", parameter)
        return cls(**(data | {"widths": tuple(data["widths"])}))

    @classmethod
    def from_json(cls, text: str, source: str = "model metadata", parameter: str | None = None) -> ModelMetadata:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as err:
            raise InputError(f"{source}: metadata is not JSON: {err}", parameter) from None
        return cls.from_dict(data, source, parameter)


def _problems(data: dict) -> list[str]:
    """What is wrong with the values of metadata whose keys are complete (empty: nothing)."""
    from roughness.simulate.config import FIDELITY_SPACING_MM, SimConfig

    from .patch import DESCRIPTOR_NAMES

    def number(x: object) -> bool:
        return isinstance(x, numbers.Real) and not isinstance(x, bool) and math.isfinite(x)

    def whole(x: object) -> bool:
        return isinstance(x, int) and not isinstance(x, bool)

    def reals(x: object, n: int | None = None) -> bool:
        return isinstance(x, list) and (n is None or len(x) == n) and all(number(v) for v in x)

    out = []
    widths = data["widths"]
    if not (isinstance(widths, list | tuple) and 0 < len(widths) <= MAX_STAGES
            and all(whole(w) and 0 < w <= MAX_CHANNELS for w in widths)):
        out.append(f"widths must be 1 to {MAX_STAGES} whole numbers of channels in 1..{MAX_CHANNELS}, got {widths!r}")
    if not (whole(data["hidden"]) and 0 < data["hidden"] <= MAX_CHANNELS):
        out.append(f"hidden must be a whole number of units in 1..{MAX_CHANNELS}, got {data['hidden']!r}")
    for key in ("patch_pixel_mm", "footprint_mm", "log_offset"):
        if not (number(data[key]) and data[key] > 0):
            out.append(f"{key} must be a positive finite number, got {data[key]!r}")
    if not out:
        pixels = data["footprint_mm"] / data["patch_pixel_mm"]
        if not (1 <= round(pixels) <= MAX_PATCH_SIZE and abs(pixels - round(pixels)) < 1e-6 * pixels):
            out.append(f"footprint_mm / patch_pixel_mm must be a whole number of pixels in 1..{MAX_PATCH_SIZE}, "
                       f"got {data['footprint_mm']!r} / {data['patch_pixel_mm']!r}")
    fidelity = data["label_fidelity"]
    if fidelity not in FIDELITY_SPACING_MM:
        out.append(f"label_fidelity must be one of {', '.join(FIDELITY_SPACING_MM)}, got {fidelity!r}")
    elif not isinstance(data["simulation"], dict):
        out.append(f"simulation must be an object, got {data['simulation']!r}")
    else:
        try:
            SimConfig(**{**data["simulation"], "fidelity": fidelity})
        except (InputError, TypeError) as err:
            out.append(f"simulation: {err}")
    domain, parts = data["domain"], {"descriptors", "low", "high", "mean", "precision", "threshold"}
    if not (isinstance(domain, dict) and parts <= set(domain)):
        out.append("domain must be an object with descriptors, low, high, mean, precision and threshold")
    elif domain["descriptors"] != list(DESCRIPTOR_NAMES):
        out.append(f"domain descriptors must be {list(DESCRIPTOR_NAMES)}, got {domain['descriptors']!r}")
    elif not (reals(domain["low"], len(DESCRIPTOR_NAMES)) and reals(domain["high"], len(DESCRIPTOR_NAMES))
              and all(lo <= hi for lo, hi in zip(domain["low"], domain["high"]))):
        out.append(f"domain low and high must be {len(DESCRIPTOR_NAMES)} finite bounds with low <= high")
    elif not (reals(domain["mean"]) and domain["mean"] and isinstance(domain["precision"], list)
              and len(domain["precision"]) == len(domain["mean"])
              and all(reals(row, len(domain["mean"])) for row in domain["precision"])):
        out.append("domain mean must be a finite vector and precision a finite square matrix of its size")
    elif not (number(domain["threshold"]) and domain["threshold"] > 0):
        out.append(f"domain threshold must be a positive finite number, got {domain['threshold']!r}")
    for key in ("metrics", "test_by_family", "data", "train_config", "cost_core_seconds"):
        if not isinstance(data[key], dict):
            out.append(f"{key} must be an object, got {data[key]!r}")
    for key in ("int8", "ensemble", "multi_fidelity"):
        if data.get(key) is not None and not isinstance(data[key], dict):
            out.append(f"{key} must be an object, got {data[key]!r}")
    if data["holdout_family"] is not None and not isinstance(data["holdout_family"], str):
        out.append(f"holdout_family must be a family name or null, got {data['holdout_family']!r}")
    if not (number(data["test_fraction"]) and 0 <= data["test_fraction"] < 1):
        out.append(f"test_fraction must be a number in [0, 1), got {data['test_fraction']!r}")
    for key in ("best_epoch", "epochs", "parameters"):
        if not whole(data[key]):
            out.append(f"{key} must be a whole number, got {data[key]!r}")
    if not (number(data["minutes"]) and data["minutes"] >= 0):
        out.append(f"minutes must be a finite number >= 0, got {data['minutes']!r}")
    multi, ensemble = data.get("multi_fidelity"), data.get("ensemble")
    if isinstance(multi, dict) and not (number(multi.get("query_h_mm")) and multi["query_h_mm"] > 0):
        out.append(f"multi_fidelity query_h_mm must be a positive spacing (mm), got {multi.get('query_h_mm')!r}")
    if isinstance(ensemble, dict) and ensemble.get("max_std") is not None and not (
            number(ensemble["max_std"]) and ensemble["max_std"] > 0):
        out.append(f"ensemble max_std must be a positive finite number, got {ensemble['max_std']!r}")
    return out


def read_metadata(props: dict[str, str], source: str | Path) -> ModelMetadata:
    """The metadata of an ONNX model from its metadata properties (``key -> value``); InputError for ``model``."""
    if METADATA_KEY not in props:
        raise InputError(f"{source} is an ONNX model without roughness metadata (export it with `roughness export`)",
                         parameter="model")
    return ModelMetadata.from_json(props[METADATA_KEY], str(source), parameter="model")


def load_onnx(path: str | Path) -> onnx.ModelProto:
    """An ONNX file's graph, read with onnx (no session, no external data); InputError for ``model`` if the file
    is missing or not ONNX."""
    import onnx
    from google.protobuf.message import DecodeError

    require_model_file(path)
    try:
        return onnx.load(str(path), load_external_data=False)
    except DecodeError as err:
        raise InputError(f"{path} is not an ONNX model: {err}", parameter="model") from None


def require_model_file(path: str | Path) -> Path:
    """``path`` as a Path if it is a regular file (or a link to one); InputError for ``model`` saying what it is
    otherwise (missing, a folder, or a FIFO, socket or device, which are never opened: reading one could block)."""
    path = Path(path)
    if path.is_file():
        return path
    if path.is_dir():
        raise InputError(f"{path} is a folder, not a model file", parameter="model")
    if path.exists():
        raise InputError(f"{path} is not a regular file (a FIFO, socket or device): give the model's .onnx file",
                         parameter="model")
    raise InputError(f"model not found: {path}", parameter="model")


def onnx_metadata(path: str | Path) -> ModelMetadata:
    """The metadata of an ONNX file, read with onnx (no session)."""
    graph = load_onnx(path)
    return read_metadata({p.key: p.value for p in graph.metadata_props}, path)
