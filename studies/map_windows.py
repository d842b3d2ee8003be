"""How far inside a window's edge a spectral map's V stops feeling the edge (simulate/spectral/windows.py).

For each texture (40 mm maps at 0.05 mm: printed bumps, and fBm surfaces whose long wavelengths reach the
map's size, the hardest case), the whole map is solved once (mirrored across its edges, as
``spectral_map`` does) and its left half alone (mirrored across the cut, as a window is); V of footprint
positions at distances d from the cut (the distance from the cut to the nearest strain the position samples,
i.e. its centre's distance less half the 8 mm sampling window) is compared between the two, over a column of
positions 0.5 mm apart. The guard band is then chosen where the largest relative error has fallen well below
the Monte Carlo error of V (a few percent) and the one-solve map's own agreement with single footprints (1e-3).

    python studies/map_windows.py          # writes studies/results/map_windows.{md,json}
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np

ROOT = Path(__file__).parents[1]
DISTANCES_MM = (0.0, 0.5, 1.0, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 7.5, 9.0, 10.0)


def textures():
    from roughness.dataset.fractal import fbm_surface
    from roughness.dataset.textures import standard_texture

    return {"standard 1.5 mm bumps (tiled 4 x 4)": standard_texture(1.5, seed=1).tiled(4, 4),
            "fBm rms 0.05 mm, Hurst 0.8": fbm_surface(40, 0.05, rms_mm=0.05, seed=1),
            "fBm rms 0.15 mm, Hurst 0.8": fbm_surface(40, 0.05, seed=2),
            "fBm rms 0.15 mm, Hurst 0.5": fbm_surface(40, 0.05, hurst=0.5, seed=3)}


def errors(hm) -> tuple[list[float], str]:
    """Largest relative |V(window) / V(map) - 1| at each of DISTANCES_MM from the cut, and the contact."""
    from roughness.simulate.config import SimConfig
    from roughness.simulate.spectral.maps import MapTask, solve

    config, pixel = SimConfig(), hm.pixel_mm
    heights = np.asarray(hm.heights)
    cut = heights.shape[1] // 2
    xs = cut * pixel - config.window_mm / 2 - np.array(DISTANCES_MM)
    ys = np.arange(config.width_mm / 2, heights.shape[0] * pixel - config.width_mm / 2 + 1e-9, 0.5)
    whole = solve(MapTask(heights, pixel, xs, ys, False, config))
    half = solve(MapTask(heights[:, :cut], pixel, xs, ys, False, config))
    rel = np.abs(half.sums / whole.sums - 1).max(axis=0)
    return [float(r) for r in rel], f"{whole.message}; window: {half.message}"


def main(argv: list[str] | None = None) -> int:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from roughness.simulate.config import SimConfig
    from roughness.simulate.spectral.windows import GUARD_TISSUES

    results = {name: errors(hm) for name, hm in textures().items()}
    tissue = SimConfig().tissue_mm
    lines = ["# Spectral map windows: the error of V near a window's edge",
             "",
             "`python studies/map_windows.py`: each 40 x 40 mm map (0.05 mm pixels) solved whole and as its left half; "
             "the largest relative difference of V over a column of positions (0.5 mm apart) whose sampled strain "
             f"comes within d of the cut (tissue thickness {tissue:g} mm).",
             "",
             "| d (mm) | " + " | ".join(results) + " |",
             "|---|" + "---|" * len(results)]
    for i, d in enumerate(DISTANCES_MM):
        lines.append(f"| {d:g} | " + " | ".join(f"{r[0][i]:.1e}" for r in results.values()) + " |")
    lines += ["", "Contact: " + "; ".join(f"{name}: {r[1]}" for name, r in results.items()), "",
              f"Guard band chosen: {GUARD_TISSUES:g} tissue thicknesses ({GUARD_TISSUES * tissue:g} mm) beyond the "
              "sampled strain (simulate/spectral/windows.py GUARD_TISSUES)."]
    out = ROOT / "studies" / "results"
    (out / "map_windows.md").write_text("\n".join(lines) + "\n")
    (out / "map_windows.json").write_text(json.dumps({"distances_mm": DISTANCES_MM, "results": results}, indent=1))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
