"""FEM against the spectral engine on single sinusoids of 0.5 to 4 mm wavelength, in full contact.

A sinusoid H = h cos(2 pi x / lambda) of small relief (h = 0.05 mm) keeps the skin in full contact,
so the two engines differ only by what separates a 10 mm block from an infinite layer (its free
sides, its flat state, the mesh) and not by contact. The FEM runs converged to 1% (and at
``default`` for scale); results append to results/spectral_sinusoids.jsonl (resumable) and the
table goes to results/spectral_sinusoids.md.

    python studies/spectral_sinusoids.py
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

OUT = Path(__file__).parent / "results" / "spectral_sinusoids"
WAVELENGTHS_MM = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0)
AMPLITUDE_MM = 0.05
PIXEL_MM = 0.025
SIZE_MM = 12.0


def sinusoid(wavelength: float):
    from roughness.surface.heightmap import Heightmap

    n = round(SIZE_MM / PIXEL_MM)
    x = (np.arange(n) + 0.5) * PIXEL_MM - SIZE_MM / 2
    return Heightmap(np.tile(AMPLITUDE_MM * np.cos(2 * np.pi * x / wavelength), (n, 1)), PIXEL_MM)


def main(argv: list[str] | None = None) -> int:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args(argv)
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator
    from roughness.simulate.spectral.engine import SpectralSimulator

    jsonl = OUT.with_suffix(".jsonl")
    done = {json.loads(line)["wavelength_mm"]: json.loads(line) for line in jsonl.read_text().splitlines()} \
        if jsonl.exists() else {}
    converged = Simulator(SimConfig(fidelity="converged", tolerance=0.01))
    default = Simulator(SimConfig(fidelity="default"))
    for wavelength in WAVELENGTHS_MM:
        if wavelength in done:
            continue
        hm = sinusoid(wavelength)
        spectral = {name: SpectralSimulator(flat_state=name).run(hm) for name in ("block", "layer")}
        fem = converged.run(hm)
        row = {"wavelength_mm": wavelength, "fem_converged": fem.roughness,
               "fem_converged_h_mm": fem.config.h_contact_mm, "fem_discretization_error": fem.discretization_error,
               "fem_default": default.run(hm, estimate_error=False).roughness,
               "fem_contact_fraction": fem.contact_fraction,
               **{f"spectral_{k}": r.roughness for k, r in spectral.items()},
               "spectral_contact": spectral["block"].contact.message}
        done[wavelength] = row
        with jsonl.open("a") as f:
            f.write(json.dumps(row) + "\n")
        print(row, flush=True)
    lines = ["# FEM against the spectral engine on sinusoids (full contact)", "",
             f"H = {AMPLITUDE_MM} mm cos(2 pi x / lambda), pixel {PIXEL_MM} mm; FEM converged to 1% (its mesh "
             "spacing and estimated error given). Regenerate: `python studies/spectral_sinusoids.py`.", "",
             "| lambda mm | FEM converged | h mm | FEM est. error | FEM default | spectral (block) | vs converged | "
             "spectral (layer) | vs converged |", "|---|---|---|---|---|---|---|---|---|"]
    for wavelength in sorted(done):
        r = done[wavelength]
        ref = r["fem_converged"]
        lines.append(f"| {wavelength:g} | {ref:.5f} | {r['fem_converged_h_mm']:g} | "
                     f"{100 * (r['fem_discretization_error'] or 0):.1f}% | {r['fem_default']:.5f} | "
                     f"{r['spectral_block']:.5f} | {100 * (r['spectral_block'] / ref - 1):+.1f}% | "
                     f"{r['spectral_layer']:.5f} | {100 * (r['spectral_layer'] / ref - 1):+.1f}% |")
    OUT.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
