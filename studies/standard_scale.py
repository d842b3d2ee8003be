"""Measure the standard reference scale (``models/standard_scale.json``, read by ``roughness.perceptual_scale``).

Per fidelity, the mean V of each standard texture (cap-topped bumps at the paper's lambdas, 10 N,
stick) over several seeds, with its spread; for the FEM also the mean estimated discretization error
of V per lambda (from the next coarser mesh level, ``simulate.discretization``). Tables of fidelities
not asked for are kept. A few minutes on 2 cores::

    python studies/standard_scale.py --fidelities coarse default          # 5 seeds each
    python studies/standard_scale.py --fidelities fine                    # adds fine (~15 min)
    python studies/standard_scale.py --fidelities spectral                # the spectral engine (~1 min)
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from roughness.core.files import atomic_write
from roughness.perceptual_scale import SCALE_PATH, WEBER_FRACTION


def measure(fidelity: str, seeds: range) -> dict:
    """Run the FEM (or, for ``spectral``, the spectral engine) on every standard texture and seed; mean and
    spread of V per lambda (the FEM's mean estimated discretization error too)."""
    from roughness.dataset.textures import STANDARD_LAMBDAS_MM, standard_texture
    from roughness.simulate import SimConfig, Simulator

    if fidelity == "spectral":
        from roughness.simulate.spectral.engine import SpectralSimulator

        sim = SpectralSimulator()
    else:
        sim = Simulator(SimConfig(fidelity=fidelity))
    results = [[sim.run(standard_texture(lam, seed=s)) for s in seeds] for lam in STANDARD_LAMBDAS_MM]
    values = np.array([[r.roughness for r in row] for row in results])
    out = {"lambda_mm": list(STANDARD_LAMBDAS_MM), "seeds": list(seeds), "V_mean": values.mean(1).round(6).tolist(),
           "V_std": values.std(1, ddof=1).round(6).tolist(), "V": values.round(6).tolist()}
    if fidelity != "spectral":
        errors = np.array([[r.discretization_error for r in row] for row in results], dtype=float)
        out["discretization_error_mean"] = errors.mean(1).round(4).tolist()
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(SCALE_PATH))
    parser.add_argument("--fidelities", nargs="+", default=["coarse", "default"],
                        help="FEM fidelities to tabulate; tables of others in --out are kept (default: coarse default)")
    parser.add_argument("--seeds", type=int, default=5, help="realisations per lambda (seeds 100, 101, ...)")
    args = parser.parse_args(argv)
    out = Path(args.out)
    tables = json.loads(out.read_text())["tables"] if out.exists() else {}  # other fidelities are kept
    for fidelity in args.fidelities:
        tables[fidelity] = measure(fidelity, range(100, 100 + args.seeds))
        print(fidelity, tables[fidelity]["V_mean"], flush=True)
    note = ("Mean FEM V of the 13 standard cap-topped bump textures (paper parameters, 10 N, stick) over "
            "the seeds listed; regenerate with: python studies/standard_scale.py")
    text = json.dumps({"note": note, "weber_fraction": WEBER_FRACTION, "tables": tables}, indent=1)
    atomic_write(out, lambda tmp: Path(tmp).write_text(text))


if __name__ == "__main__":
    main()
