"""Mesh convergence of V: coarse, default and fine fidelity on a standard bump texture
(lambda = 1.0 mm, 0.3 mm caps) and a rough random fBm surface.

    python studies/mesh_convergence.py   # writes studies/results/mesh_convergence.{md,json}
"""
from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

OUT = Path(__file__).parent / "results"


def main() -> None:
    argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "2")
    from roughness.dataset.fractal import fbm_surface
    from roughness.dataset.textures import standard_texture
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    textures = {
        "standard lambda=1.0 mm (seed 0)": lambda: standard_texture(1.0, seed=0),
        "fBm H=0.8, rms 0.15 mm (seed 0)": lambda: fbm_surface(seed=0),
    }
    rows = []
    for name, make in textures.items():
        hm = make()
        for fidelity in ("coarse", "default", "fine"):
            sim = Simulator(SimConfig(fidelity=fidelity))
            t = time.perf_counter()
            r = sim.run(hm, estimate_error=False)
            rows.append({"texture": name, "fidelity": fidelity, "h_contact_mm": r.config.h_contact_mm,
                         "nodes": r.nodes, "V": r.roughness, "V_stderr": r.roughness_stderr,
                         "contact_fraction": r.contact_fraction, "indentation_mm": r.indentation_mm,
                         "rounds": r.iterations, "converged": r.converged, "seconds_cold": time.perf_counter() - t})
            print(rows[-1], flush=True)
    for row in rows:
        fine = next(r["V"] for r in rows if r["texture"] == row["texture"] and r["fidelity"] == "fine")
        row["rel_diff_to_fine"] = row["V"] / fine - 1
    OUT.mkdir(exist_ok=True)
    (OUT / "mesh_convergence.json").write_text(json.dumps(rows, indent=1))
    lines = ["| texture | fidelity | h (mm) | nodes | V | V vs fine | contact | indentation (mm) | rounds |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['texture']} | {r['fidelity']} | {r['h_contact_mm']} | {r['nodes']} | {r['V']:.5f} "
                     f"± {r['V_stderr']:.5f} | {100 * r['rel_diff_to_fine']:+.1f}% | {100 * r['contact_fraction']:.1f}% "
                     f"| {r['indentation_mm']:.2f} | {r['rounds']} |")
    (OUT / "mesh_convergence.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
