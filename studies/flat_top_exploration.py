"""Does V fall as the flat-top diameter grows (the paper's finding)? Explore force and bump geometry.

Five flat-top textures (top 0.1..0.5 mm, lambda 1.0 mm, 1 mm tall), three realisations each,
coarse fidelity, stick contact; Spearman of top diameter vs mean V (the paper: negative).

    python studies/flat_top_exploration.py [--forces 2,5,10]   # writes studies/results/flat_top.{md,json}

Settings already in flat_top.json are kept (resumable); the table lists every measured setting.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy.stats import spearmanr  # noqa: E402

from roughness.dataset.textures import FLAT_TOP_DIAMETERS_MM, flat_top_texture  # noqa: E402
from roughness.simulate.config import SimConfig  # noqa: E402
from roughness.simulate.model import Simulator  # noqa: E402

OUT = Path(__file__).parent / "results"
GEOMETRIES = {"base 1.5 mm": lambda d: 1.5, "base = top + 0.6 mm": lambda d: d + 0.6,
              "base = top + 1.2 mm": lambda d: d + 1.2, "base = top + 1.6 mm (default)": lambda d: d + 1.6,
              "base = top + 2.0 mm": lambda d: d + 2.0}


def main() -> None:
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--forces", default="2,5,10", help="comma-separated forces (N)")
    forces = [float(f) for f in ap.parse_args().forces.split(",")]
    sim = Simulator(SimConfig(fidelity="coarse"))
    path = OUT / "flat_top.json"
    done = {(r["force_n"], r["geometry"]): r for r in json.loads(path.read_text())} if path.exists() else {}
    rows = []
    for force in forces:
        for geometry, base in GEOMETRIES.items():
            if (force, geometry) in done:  # resume: settings already measured are kept
                rows.append(done[(force, geometry)])
                continue
            means = [float(np.mean([sim.run(flat_top_texture(d, seed=s, base_diameter_mm=base(d)), force_n=force, estimate_error=False).roughness
                                    for s in (0, 1, 2)])) for d in FLAT_TOP_DIAMETERS_MM]
            rho = float(spearmanr(FLAT_TOP_DIAMETERS_MM, means).statistic)
            rows.append({"force_n": force, "geometry": geometry, "mean_V": means, "spearman": rho})
            print(rows[-1], flush=True)
            path.write_text(json.dumps(rows + [r for r in done.values() if r not in rows], indent=1))
    order = list(GEOMETRIES)
    rows = sorted(rows + [r for r in done.values() if r not in rows],
                  key=lambda r: (r["force_n"], order.index(r["geometry"])))
    lines = ["Flat-top textures (lambda 1.0 mm): Spearman of top diameter vs mean V (paper: negative)", "",
             "| force (N) | geometry | V at top 0.1 / 0.2 / 0.3 / 0.4 / 0.5 mm | Spearman |", "|---|---|---|---|"]
    lines += [f"| {r['force_n']:g} | {r['geometry']} | {' / '.join(f'{v:.4f}' for v in r['mean_V'])} | {r['spearman']:+.2f} |"
              for r in rows]
    (OUT / "flat_top.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
