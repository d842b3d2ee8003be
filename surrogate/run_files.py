"""The files of a training run folder: ``checkpoint.pt`` (weights and metadata), ``metrics.json`` (the metadata
but the domain, with the provenance of the labels), ``history.csv`` (losses per epoch) and ``predictions.csv``
(label and predicted V of every scored row); every file written atomically."""
from __future__ import annotations

import io
import json
from pathlib import Path

import torch

from roughness.core.files import atomic_write
from roughness.core.hashing import digest
from roughness.core.provenance import make_provenance

from .evaluation import Evaluation
from .metadata import ModelMetadata
from .network import RoughnessNet

CHECKPOINT, METRICS, HISTORY, PREDICTIONS = "checkpoint.pt", "metrics.json", "history.csv", "predictions.csv"


def write_run(out: Path, model: RoughnessNet, meta: ModelMetadata, history: list[tuple],
              evaluation: Evaluation) -> Path:
    """Write the run's files into the folder ``out``; returns the checkpoint's path.

    ``history``: (epoch, training loss, validation loss, learning rate, minutes) per epoch."""
    plain = json.loads(meta.to_json())  # plain types only (no numpy scalars): export loads it with weights_only
    save_torch({"state_dict": model.state_dict(), **plain}, out / CHECKPOINT)
    # the digest of the labels' simulation record (for FEM labels the result cache's); the model id comes with the
    # exported file
    provenance = make_provenance("surrogate", meta.label_fidelity,
                                 f"{meta.simulation.get('engine', 'fem')}-{digest(meta.simulation)}")
    write_text(out / METRICS, json.dumps({k: v for k, v in meta.to_dict().items() if k != "domain"}
                                         | {"provenance": provenance.as_dict()}, indent=1))
    write_text(out / HISTORY, "epoch,train_loss,val_loss,lr,minutes\n" + "".join(
        ",".join(f"{v:.6g}" for v in row) + "\n" for row in history))
    e = evaluation
    write_text(out / PREDICTIONS, "id,family,split,V_fem,V_predicted,out_of_domain,h_mm\n" + "".join(
        f"{i},{f},{s},{v:.6g},{p:.6g},{int(o)},{h:g}\n" for i, f, s, v, p, o, h in zip(
            e.scored.ids, e.scored.family, e.scored.split, e.scored.roughness, e.predicted, e.flagged, e.scored.h_mm)))
    return out / CHECKPOINT


def write_text(path: Path, text: str) -> None:
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))


def save_torch(obj: object, path: Path) -> None:
    """``torch.save`` atomically, through a buffer: torch's own file writer reports a full disk as an unexplained
    RuntimeError, a plain write as the OSError that ``atomic_write`` words ("no space left on device")."""
    buffer = io.BytesIO()
    torch.save(obj, buffer)
    atomic_write(path, lambda tmp: Path(tmp).write_bytes(buffer.getvalue()))
