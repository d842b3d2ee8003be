"""Speed of the spectral engine, with FEM ``default`` timed in the same run (one thread, warm).

Measures: a full-contact and two partial-contact 240 x 240 textures (median of repeated warm runs,
FEM default on the same textures for the ratio), a fresh ``roughness predict --engine spectral``
process, a 100 x 100 mm map at 0.05 mm pixels from one solve, and the cost's growth with the pixel
count (fitted exponent). Run on an idle machine; writes results/spectral_speed.{json,md,png}.

    python benchmarks/spectral_speed.py
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

os.environ["OMP_NUM_THREADS"] = "1"
os.environ["OPENBLAS_NUM_THREADS"] = "1"

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUT = Path(__file__).parent / "results" / "spectral_speed"
REPEATS = 7


def _median_seconds(run, repeats: int = REPEATS) -> float:
    run()  # warm: transfer functions, flat state, FEM block
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def textures() -> dict:
    from roughness.dataset.recipe import expand, load_recipe, realise
    from roughness.dataset.textures import standard_texture

    validation = expand(load_recipe(ROOT / "recipes" / "validation.json"), 71)
    return {"standard-1.5": standard_texture(1.5, seed=1), "standard-1.0": standard_texture(1.0, seed=1),
            "validation knit #46": realise(validation[46]), "validation cellular #70": realise(validation[70])}


def single_textures() -> list[dict]:
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator
    from roughness.simulate.spectral.engine import SpectralSimulator

    spectral, fem = SpectralSimulator(), Simulator(SimConfig(fidelity="default"))
    rows = []
    for name, hm in textures().items():
        result = spectral.run(hm)
        s = _median_seconds(lambda: spectral.run(hm))
        f = _median_seconds(lambda: fem.run(hm, estimate_error=False), repeats=3)
        rows.append({"texture": name, "shape": list(hm.shape), "contact": result.contact.message,
                     "contact_fraction": result.contact_fraction, "iterations": result.iterations,
                     "spectral_s": s, "fem_default_s": f, "ratio": f / s})
        print(rows[-1], flush=True)
    return rows


def fresh_predict() -> float:
    example = ROOT / "examples" / "standard-1.0mm.png"
    command = [sys.executable, "-m", "roughness.cli", "predict", str(example), "--pixel-mm", "0.05", "--height-mm",
               "1", "--engine", "spectral"]
    times = []
    for _ in range(3):
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def big_map(lambda_mm: float) -> dict:
    """One spectral solve over a 100 x 100 mm map of a standard texture tiled, V at 1 mm steps."""
    from roughness.dataset.textures import standard_texture
    from roughness.simulate.spectral.maps import spectral_map
    from roughness.surface.heightmap import Heightmap

    tile = standard_texture(lambda_mm, seed=1)  # 240 x 240 at 0.05 mm
    reps = int(np.ceil(2000 / tile.shape[0]))
    hm = Heightmap(tile.tiled(reps, reps).heights[:2000, :2000], tile.pixel_mm)
    start = time.perf_counter()
    result, notes = spectral_map(hm, step_mm=1.0)
    row = {"texture": f"standard-{lambda_mm:g} tiled", "size_mm": 100.0, "pixel_mm": 0.05,
           "positions": int(result.roughness.size), "seconds": time.perf_counter() - start, "notes": notes}
    print(row, flush=True)
    return row


def growth() -> dict:
    from roughness.dataset.textures import standard_texture
    from roughness.simulate.spectral.engine import SpectralSimulator

    base = standard_texture(1.5, seed=1)
    spectral = SpectralSimulator()
    rows = []
    for pixel in (0.1, 0.05, 0.025, 0.0125):
        hm = base.resampled(pixel)
        seconds = _median_seconds(lambda: spectral.run(hm), repeats=3)
        rows.append({"pixel_mm": pixel, "footprint_pixels": round(10 / pixel) ** 2, "seconds": seconds})
        print(rows[-1], flush=True)
    slope = np.polyfit(np.log([r["footprint_pixels"] for r in rows]), np.log([r["seconds"] for r in rows]), 1)[0]
    return {"rows": rows, "exponent": float(slope)}


def write(results: dict) -> None:
    OUT.with_suffix(".json").write_text(json.dumps(results, indent=1) + "\n")
    lines = ["# Spectral engine speed (one thread, warm; FEM default timed in the same run)", "",
             "| texture | contact | spectral | FEM default | FEM / spectral |", "|---|---|---|---|---|"]
    for r in results["single"]:
        lines.append(f"| {r['texture']} | {r['contact']} ({100 * r['contact_fraction']:.2f}%, {r['iterations']} it.) | "
                     f"{1000 * r['spectral_s']:.0f} ms | {r['fem_default_s']:.2f} s | {r['ratio']:.0f}x |")
    lines += ["", f"Fresh process `roughness predict --engine spectral` on the bundled example: "
              f"{results['fresh_predict_s']:.2f} s (median of 3).", "",
              "Maps of 100 x 100 mm at 0.05 mm pixels (one solve, V at 1 mm steps):", "",
              "| texture | footprints | seconds | contact |", "|---|---|---|---|",
              *(f"| {m['texture']} | {m['positions']:,} | {m['seconds']:.1f} | "
                f"{'; '.join(m['notes']) or 'full contact'} |" for m in results["maps"]), "",
              "Cost against footprint pixels (full contact):", "", "| pixel mm | footprint pixels | seconds |",
              "|---|---|---|"]
    for r in results["growth"]["rows"]:
        lines.append(f"| {r['pixel_mm']} | {r['footprint_pixels']:,} | {r['seconds']:.3f} |")
    lines += ["", f"Fitted exponent: seconds ~ pixels^{results['growth']['exponent']:.2f}.", ""]
    OUT.with_suffix(".md").write_text("\n".join(lines))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = results["growth"]["rows"]
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.loglog([r["footprint_pixels"] for r in rows], [r["seconds"] for r in rows], "o-")
    ax.set(xlabel="footprint pixels", ylabel="seconds (warm, 1 thread)",
           title=f"spectral cost ~ pixels^{results['growth']['exponent']:.2f}")
    fig.tight_layout()
    fig.savefig(OUT.with_suffix(".png"), dpi=110)


def main(argv: list[str] | None = None) -> int:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args(argv)
    results = {"single": single_textures(), "growth": growth(), "maps": [big_map(1.5), big_map(1.25)],
               "fresh_predict_s": fresh_predict()}
    write(results)
    print(OUT.with_suffix(".md").read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
