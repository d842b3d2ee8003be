"""Provenance: which tool, model, engine and configuration made a result.

One record, built by ``make_provenance`` and written under the JSON key ``provenance`` by every command
(and carried by ``roughness.Prediction``), so a result can be traced to what made it and a cached or
shared one checked against what would make it now.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

from roughness.core.version import RELEASE

MODEL_ID_DIGITS = 16  # hex digits of the model file's SHA-256 kept as its id


@dataclass(frozen=True)
class Provenance:
    """What made a result.

    ``tool_version``: roughness's release (``core.version.RELEASE``); ``engine``: ``surrogate``, ``spectral``,
    ``fem``, a classical measure (``compare``), or several joined with ``+`` (``combined``); ``fidelity``: the
    FEM fidelity of its scale (``spectral`` for that engine; None where none applies); ``config_digest``: the
    digest the result cache keys results by (``SimConfig.identity``: ``fem-...`` / ``spectral-...``); ``model_id``:
    ``sha256:`` and the first 16 hex digits of the ONNX file's SHA-256 (None: no model used);
    ``model_version``: the ONNX file's ``model_version`` (0: an unversioned file).
    """

    tool_version: str
    engine: str
    fidelity: str | None = None
    config_digest: str | None = None
    model_id: str | None = None
    model_version: int | None = None

    def as_dict(self) -> dict:
        return asdict(self)


def combined(records: list[Provenance]) -> Provenance:
    """One record for results made by several (``jnd``'s two answers): fields that differ are joined with
    ``+`` (their model versions: None), so the record says the results were not all made alike."""
    def join(values: list) -> str | None:
        distinct = list(dict.fromkeys(v for v in values if v is not None))
        return "+".join(map(str, distinct)) if distinct else None

    versions = {r.model_version for r in records}
    return Provenance(join([r.tool_version for r in records]), join([r.engine for r in records]),
                      join([r.fidelity for r in records]), join([r.config_digest for r in records]),
                      join([r.model_id for r in records]), versions.pop() if len(versions) == 1 else None)


def make_provenance(engine: str, fidelity: str | None = None, config_digest: str | None = None,
                    model: object | None = None) -> Provenance:
    """The provenance of a result of ``engine``; ``model`` is the ``SurrogateModel`` used, if any."""
    return Provenance(RELEASE, engine, fidelity, config_digest,
                      getattr(model, "model_id", None), getattr(model, "model_version", None))


def model_id(data: bytes) -> str:
    """A model's id from its file's bytes: ``sha256:`` and the first ``MODEL_ID_DIGITS`` hex digits."""
    import hashlib

    return "sha256:" + hashlib.sha256(data).hexdigest()[:MODEL_ID_DIGITS]
