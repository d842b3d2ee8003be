"""The model metadata: what `train` writes into the checkpoint, `export` embeds in the ONNX file
(JSON under the metadata key ``roughness``) and the predictor, quantiser, card and CLI read.

One frozen dataclass and one reader; a missing or unknown key is an InputError that names it.
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from roughness.core.errors import InputError

METADATA_KEY = "roughness"  # ONNX metadata_props key of the model's JSON metadata
OPTIONAL = ("int8", "ensemble", "multi_fidelity")  # keys only some models have


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
    # {"query_h_mm": spacing it answers for, "rows_by_h_mm": labels per spacing, "extra_data": [files]}
    multi_fidelity: dict | None = None

    @property
    def query_h_mm(self) -> float | None:
        """The contact spacing (mm) a multi-fidelity network answers for (None: a one-level network)."""
        return None if self.multi_fidelity is None else float(self.multi_fidelity["query_h_mm"])

    def to_dict(self) -> dict:
        """Plain JSON-able dict; the OPTIONAL keys only when present."""
        out = asdict(self) | {"widths": list(self.widths)}
        return {k: v for k, v in out.items() if k not in OPTIONAL or v is not None}

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @classmethod
    def from_dict(cls, data: dict, source: str = "model metadata") -> ModelMetadata:
        """Metadata from a dict; InputError names missing and unknown keys."""
        if not isinstance(data, dict):
            raise InputError(f"{source}: metadata must be a JSON object, got {type(data).__name__}")
        names = {f.name for f in fields(cls)}
        required = {f.name for f in fields(cls) if f.name not in OPTIONAL}
        missing, unknown = sorted(required - set(data)), sorted(set(data) - names)
        if missing or unknown:
            raise InputError(f"{source}: not roughness model metadata of this version"
                             + (f"; missing keys: {', '.join(missing)}" if missing else "")
                             + (f"; unknown keys: {', '.join(unknown)}" if unknown else ""))
        return cls(**(data | {"widths": tuple(int(w) for w in data["widths"])}))

    @classmethod
    def from_json(cls, text: str, source: str = "model metadata") -> ModelMetadata:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as err:
            raise InputError(f"{source}: metadata is not JSON: {err}") from None
        return cls.from_dict(data, source)


def read_metadata(props: dict[str, str], source: str | Path) -> ModelMetadata:
    """The metadata of an ONNX model from its metadata properties (``key -> value``)."""
    if METADATA_KEY not in props:
        raise InputError(f"{source} is an ONNX model without roughness metadata (export it with `roughness export`)")
    return ModelMetadata.from_json(props[METADATA_KEY], str(source))


def onnx_metadata(path: str | Path) -> ModelMetadata:
    """The metadata of an ONNX file, read with onnx (no session)."""
    import onnx

    graph = onnx.load(str(path), load_external_data=False)
    return read_metadata({p.key: p.value for p in graph.metadata_props}, path)
