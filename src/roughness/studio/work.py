"""The studio's background work (``roughness.studio.jobs``): module-level functions of ``(report, ...)`` that call
the library and return its answer."""
from __future__ import annotations

from roughness.design.tune import TuneResult
from roughness.prediction import Prediction
from roughness.studio.jobs import Report
from roughness.surface.heightmap import Heightmap

VERIFY_ENGINES = {"spectral": ("spectral", None), "FEM, coarse": ("fem", "coarse"), "FEM, default": ("fem", "default")}
"""What "Verify" can run: label -> (engine, FEM fidelity)."""


def verify(report: Report, name: str, heightmap: Heightmap, choice: str) -> Prediction:
    """V of the texture by the spectral engine or the FEM (``roughness.predict``)."""
    import roughness

    engine, fidelity = VERIFY_ENGINES[choice]
    report(None, f"the {choice} engine is solving")
    [p] = roughness.predict({name: heightmap}, engine=engine, options=roughness.PredictOptions(fidelity=fidelity),
                            units_ok=True)  # the units were checked as the texture was read
    return p


def tune(report: Report, heightmap: Heightmap, by: str, target_lambda_mm: float | None, jnd: float | None,
         verify: str) -> TuneResult:
    """The texture scaled to a target (``roughness.tune``): the surrogate searches, ``verify`` checks."""
    import roughness

    report(None, f"searching by {by}, verified by {verify}")
    return roughness.tune(heightmap, target_lambda_mm=target_lambda_mm, jnd=jnd, by=by, verify=verify, units_ok=True)
