"""The 13-texture standard reference scale: V -> equivalent bump wavelength and JND distance.

The table holds, per FEM fidelity, the mean FEM V of each standard texture (cap-topped bumps at
the paper's lambdas) over several seeds. A roughness V is placed on the scale by interpolating
lambda in log V (V rises with lambda on this scale); its distance from the nearest standard
texture is counted in just-noticeable differences of Weber fraction 0.19: ln(V / V_ref) / ln(1.19).

Regenerate the shipped table (``models/standard_scale.json``, a few minutes on 2 cores)::

    python -m roughness.surrogate.calibration --fidelities coarse default          # 5 seeds each
"""
from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.core.files import atomic_write
from roughness.models import MODELS_DIR

WEBER_FRACTION = 0.19
SCALE_PATH = MODELS_DIR / "standard_scale.json"


@dataclass(frozen=True)
class Placement:
    """Where a roughness V sits on the standard scale."""

    equivalent_lambda_mm: float  # interpolated; clipped to the scale's ends
    on_scale: bool  # False if V lies below the finest or above the coarsest standard texture
    nearest_standard: str  # e.g. "standard-1.0"
    jnd_from_nearest: float  # signed: positive = rougher than the nearest standard texture

    def as_dict(self) -> dict:
        return {"equivalent_lambda_mm": self.equivalent_lambda_mm, "on_scale": self.on_scale,
                "nearest_standard": self.nearest_standard, "jnd_from_nearest": self.jnd_from_nearest}


@dataclass(frozen=True)
class StandardScale:
    """Mean FEM V (dimensionless strain variation) of the standard textures at one fidelity."""

    lambdas_mm: tuple[float, ...]
    roughness: tuple[float, ...]
    fidelity: str

    def __post_init__(self) -> None:
        v = np.asarray(self.roughness)
        if len(v) != len(self.lambdas_mm) or len(v) < 2 or not np.all(v > 0) or not np.all(np.diff(v) > 0):
            raise ValueError(f"standard scale ({self.fidelity}) must be positive and rise with lambda: {self.roughness}")

    def place(self, roughness: float) -> Placement:
        """Equivalent lambda (mm) and signed JND distance from the nearest standard texture."""
        if not math.isfinite(roughness) or roughness < 0:
            raise ValueError(f"roughness must be finite and >= 0, got {roughness}")
        log_v = np.log(self.roughness)
        x = math.log(max(roughness, 1e-12))
        lam = float(np.interp(x, log_v, self.lambdas_mm))
        nearest = int(np.argmin(np.abs(log_v - x)))
        jnd = (x - log_v[nearest]) / math.log(1 + WEBER_FRACTION)
        return Placement(lam, bool(log_v[0] <= x <= log_v[-1]), f"standard-{self.lambdas_mm[nearest]:g}", float(jnd))


@lru_cache(maxsize=8)
def load_scale(fidelity: str, path: str | Path = SCALE_PATH) -> StandardScale:
    """The shipped standard scale for a FEM fidelity ("coarse", "default", "fine")."""
    tables = json.loads(Path(path).read_text())["tables"]
    if fidelity not in tables:
        raise InputError(f"no standard-scale table for fidelity {fidelity!r} in {path}; has {sorted(tables)}")
    table = tables[fidelity]
    return StandardScale(tuple(table["lambda_mm"]), tuple(table["V_mean"]), fidelity)


def measure(fidelity: str, seeds: range) -> dict:
    """Run the FEM on every standard texture and seed; mean and spread of V per lambda."""
    from roughness.dataset.textures import STANDARD_LAMBDAS_MM, standard_texture
    from roughness.simulate import SimConfig, Simulator

    sim = Simulator(SimConfig(fidelity=fidelity))
    values = np.array([[sim.run(standard_texture(lam, seed=s)).roughness for s in seeds]
                       for lam in STANDARD_LAMBDAS_MM])
    return {"lambda_mm": list(STANDARD_LAMBDAS_MM), "seeds": list(seeds), "V_mean": values.mean(1).round(6).tolist(),
            "V_std": values.std(1, ddof=1).round(6).tolist(), "V": values.round(6).tolist()}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(SCALE_PATH))
    parser.add_argument("--fidelities", nargs="+", default=["coarse", "default"])
    parser.add_argument("--seeds", type=int, default=5, help="realisations per lambda (seeds 100, 101, ...)")
    args = parser.parse_args(argv)
    out = Path(args.out)
    tables = json.loads(out.read_text())["tables"] if out.exists() else {}  # other fidelities are kept
    for fidelity in args.fidelities:
        tables[fidelity] = measure(fidelity, range(100, 100 + args.seeds))
        print(fidelity, tables[fidelity]["V_mean"], flush=True)
    note = ("Mean FEM V of the 13 standard cap-topped bump textures (paper parameters, 10 N, stick) over "
            "the seeds listed; regenerate with: python -m roughness.surrogate.calibration")
    text = json.dumps({"note": note, "weber_fraction": WEBER_FRACTION, "tables": tables}, indent=1)
    atomic_write(out, lambda tmp: Path(tmp).write_text(text))


if __name__ == "__main__":
    main()
