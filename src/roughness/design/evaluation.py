"""One evaluator for the design tools: the surrogate for searches, a physics engine to verify, on one standard scale.

The surrogate runs through ``roughness.predict``. The verifier is the engines' ``FemEngine`` with
the model's simulation parameters at the fidelity of its training labels (prepared once, reused for
every verification), or at another FEM fidelity, or the ``SpectralEngine`` (``VERIFIERS``); its answers
are placed on its own standard scale, and distances are JNDs of the equivalent wavelength
(``roughness.perceptual_scale``).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from roughness.surface.heightmap import Heightmap

if TYPE_CHECKING:
    from roughness.core.provenance import Provenance
    from roughness.engines import FemEngine, SpectralEngine
    from roughness.surface.printing import PrintProfile
    from roughness.surrogate.predictor import SurrogateModel

ENGINES = ("surrogate", "fem")
VERIFIERS = ("coarse", "default", "fine", "spectral")  # FEM fidelities, or the spectral engine


@dataclass(frozen=True)
class Verified:
    """One FEM answer: V, its Monte Carlo standard error, and the equivalent wavelength (mm)."""

    roughness: float
    roughness_stderr: float
    equivalent_lambda_mm: float
    on_scale: bool
    seconds: float


@dataclass
class Evaluator:
    """The shipped (or a given) surrogate and the verifier (default: the FEM at the model's label fidelity),
    loaded on first use."""

    model_path: str | None = None
    fidelity: str | None = None  # the verifier: a FEM fidelity or "spectral" (default: the model's training labels')
    printer: PrintProfile | None = None  # every texture is judged as printed (roughness.surface.printing)
    _model: SurrogateModel | None = field(default=None, repr=False)
    _fem: FemEngine | SpectralEngine | None = field(default=None, repr=False)
    fem_runs: int = 0  # FEM verifications so far

    @property
    def model(self) -> SurrogateModel:
        from roughness.surrogate.predictor import DEFAULT_MODEL, SurrogateModel

        if self._model is None:
            self._model = SurrogateModel(self.model_path or DEFAULT_MODEL)
        return self._model

    @property
    def fem(self) -> FemEngine | SpectralEngine:
        """The verifying engine (``FemEngine`` or ``SpectralEngine``), prepared on first use."""
        from roughness.engines import FemEngine, SpectralEngine

        if self._fem is None:
            simulation = self.model.meta.simulation
            self._fem = (SpectralEngine.of(simulation) if self.fidelity == "spectral" else
                         FemEngine.of(self.fidelity or self.model.fidelity, simulation))
        return self._fem

    @property
    def provenance(self) -> Provenance:
        """The ``Provenance`` of the design's verified answers: the verifier's engine, fidelity and configuration,
        and the surrogate that searched."""
        from roughness.core.provenance import make_provenance

        return make_provenance(self.fem.kind, getattr(self.fem, "fidelity", None), self.fem.identity, self.model)

    @property
    def verifier(self) -> str:
        """The verifier in words: ``FEM fine``, ``spectral``."""
        fidelity = self.fidelity or self.model.fidelity
        return "spectral" if fidelity == "spectral" else f"FEM {fidelity}"

    @property
    def scale(self):
        """The standard scale of the verifier (the surrogate's labels share the default one)."""
        from roughness.perceptual_scale import load_scale

        return load_scale(self.fidelity or self.model.fidelity)

    @property
    def footprint_mm(self) -> float:
        return self.model.footprint_mm

    def surrogate(self, heightmaps: Sequence[Heightmap], tile: bool = False,
                  centres_mm: Sequence[tuple[float, float]] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Surrogate V of each heightmap (at each centre, if given) and whether it was in the model's domain."""
        from roughness.prediction import PredictOptions, predictions

        heightmaps = [self.as_printed(hm, tile) for hm in heightmaps]
        if centres_mm is None or all(c is None for c in centres_mm):
            results = predictions([(f"heightmap {i}", hm) for i, hm in enumerate(heightmaps)], "surrogate",
                                  self.model, PredictOptions(tile=tile))  # the tools' own variants of checked maps
        else:  # one footprint centre per map: batched through the model directly
            model = self.model
            values, reasons = model.run(np.stack([model.patch(hm, c, tile) for hm, c in zip(heightmaps, centres_mm)]))
            return np.asarray(values, dtype=float), np.array([not r for r in reasons])
        return np.array([p.roughness for p in results]), np.array([p.in_domain for p in results])

    def as_printed(self, heightmap: Heightmap, tile: bool = False) -> Heightmap:
        """``heightmap`` as the ``printer`` would print it (unchanged without a printer)."""
        from roughness.surface.printing import printed

        return heightmap if self.printer is None else printed(heightmap, self.printer, tile).heightmap

    def verify(self, heightmap: Heightmap, tile: bool = False, centre_mm: tuple[float, float] | None = None,
               digital: bool = False) -> Verified:
        """The verifier's V of one heightmap (as printed, if there is a ``printer``, unless ``digital``),
        placed on its standard scale."""
        fem = self.fem
        fem.centre_mm, fem.tile = centre_mm, tile
        result = fem.simulate(heightmap if digital else self.as_printed(heightmap, tile))
        self.fem_runs += 1
        lam, on_scale = self.scale.equivalent_lambda(result.roughness)
        return Verified(result.roughness, result.roughness_stderr, lam, on_scale, result.seconds)

    def lambda_of(self, roughness: float) -> float:
        """Equivalent wavelength (mm) of V on the standard scale (extrapolated off its ends)."""
        return self.scale.equivalent_lambda(max(float(roughness), 1e-12))[0]


