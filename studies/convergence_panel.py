"""Mesh-convergence panel: V of 24 textures at several discretisations (reference for the FEM error estimate).

Every texture family plus small-feature, sparse-feature, low-relief and multi-scale textures of
our own making. Each (texture, level) result is appended to a JSONL file keyed by the texture's
content and the configuration, so the study resumes after any interruption and never mixes
results of changed inputs. The fine levels are slow (minutes per texture at h = 0.1 mm): run in
the background, one process per core.

    python studies/convergence_panel.py --levels p1:0.14 p1:0.1 p2:0.2     # resumable
    python studies/convergence_panel.py --list                              # the panel
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

OUT = Path(__file__).parent / "results" / "convergence_panel.jsonl"


def _on_flat(features: Callable[[np.ndarray, np.ndarray], np.ndarray], size_mm: float = 12.0,
             pixel_mm: float = 0.05):
    from roughness import Heightmap

    n = round(size_mm / pixel_mm)
    c = (np.arange(n) + 0.5) * pixel_mm
    return Heightmap(features(c[None, :], c[:, None]), pixel_mm)


def _dome(x, y, cx, cy, radius, height):
    r2 = ((x - cx) ** 2 + (y - cy) ** 2) / radius**2
    return height * np.sqrt(np.clip(1 - r2, 0, None))


def panel() -> dict[str, Callable[[], object]]:
    """Name -> maker of the heightmap (mm); deterministic."""
    from roughness import Heightmap, named_texture
    from roughness.dataset.natural import make

    def fam(family, seed=1, **p):
        return lambda: make(family, seed=seed, **p)

    def low_relief():
        hm = named_texture("standard-1.0", seed=3)
        return Heightmap(hm.heights * 0.1, hm.pixel_mm)

    def multi_scale():
        base = named_texture("standard-1.25", seed=4)
        fine = make("fbm", seed=4, hurst=0.6, rms_mm=0.03, cutoff_mm=0.2)
        return Heightmap(base.heights + fine.heights, base.pixel_mm)

    return {
        "standard-0.625": lambda: named_texture("standard-0.625", seed=1),
        "standard-1.0": lambda: named_texture("standard-1.0", seed=1),
        "standard-1.625": lambda: named_texture("standard-1.625", seed=1),
        "flattop-0.1": lambda: named_texture("flattop-0.1", seed=1),
        "cellular-dome": fam("cellular", cell_mm=0.8, profile="dome", height_mm=0.3),
        "cellular-wall": fam("cellular", cell_mm=2.0, profile="wall", height_mm=0.5, wall_mm=0.3),
        "woven": fam("woven", pitch_mm=1.0, width_mm=0.8, height_mm=0.3),
        "woven-low": fam("woven", pitch_mm=0.6, width_mm=0.5, height_mm=0.08),
        "knit": fam("knit"),
        "knit-low": fam("knit", wale_mm=0.8, course_mm=0.7, yarn_mm=0.25, height_mm=0.1),
        "grating-sine-1.0": fam("grating", period_mm=1.0, profile="sine", height_mm=0.3),
        "grating-square-2.0": fam("grating", period_mm=2.0, duty=0.2, profile="square", height_mm=0.5),
        "grating-sine-0.5-low": fam("grating", period_mm=0.5, profile="sine", height_mm=0.1),
        "grains": fam("grains"),
        "grains-small": fam("grains", grain_min_mm=0.2, grain_max_mm=0.5, density=1.5, height_mm=0.2),
        "dots-small-low-domes": fam("dots", pitch_mm=0.6, diameter_mm=0.4, shape="dome", height_mm=0.1),
        "dots-grid": fam("dots", pitch_mm=1.5, diameter_mm=0.8, shape="flat", height_mm=0.5, lattice="square"),
        "dots-sparse-cones": fam("dots", pitch_mm=2.5, diameter_mm=1.0, shape="cone", height_mm=0.6),
        "fbm-fine-low": fam("fbm", hurst=0.7, rms_mm=0.05, cutoff_mm=0.3),
        "fbm-coarse": fam("fbm", hurst=0.5, rms_mm=0.2, cutoff_mm=1.0),
        "single-dome": lambda: _on_flat(lambda x, y: _dome(x, y, 6.0, 6.0, 0.6, 0.4)),
        "single-ridge": lambda: _on_flat(lambda x, y: 0.3 * np.exp(-((x - 6.2) / 0.15) ** 2) + 0 * y),
        "low-relief-standard": low_relief,
        "multi-scale": multi_scale,
    }


def _level(text: str) -> tuple[str, float]:
    element, _, h = text.partition(":")
    if element not in ("p1", "p2") or not h:
        raise argparse.ArgumentTypeError(f"a level is p1:H or p2:H (H in mm), got {text!r}")
    return element, float(h)


def _done(path: Path) -> set[tuple[str, str]]:
    if not path.exists():
        return set()
    keys = set()
    for line in path.read_text().splitlines():
        try:
            row = json.loads(line)
        except json.JSONDecodeError:  # a torn last line: recomputed
            continue
        keys.add((row["texture_digest"], row["config_digest"]))
    return keys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--levels", nargs="+", type=_level, default=[("p1", 0.14), ("p1", 0.1), ("p2", 0.2)],
                        metavar="pN:H", help="element order and contact spacing in mm (default p1:0.14 p1:0.1 p2:0.2)")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="a subset of the panel")
    parser.add_argument("--out", type=Path, default=OUT, help=f"JSONL results (default {OUT})")
    parser.add_argument("--list", action="store_true", help="list the panel and exit")
    args = parser.parse_args(argv)
    textures = panel()
    if args.list:
        print("\n".join(textures))
        return 0
    from roughness import SimConfig, Simulator
    from roughness.core.hashing import array_digest, digest

    names = args.only or list(textures)
    done = _done(args.out)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    for element, h in args.levels:
        config = SimConfig(element=element, h_contact_mm=h)
        sim = Simulator(config)
        for name in names:
            hm = textures[name]()
            key = (array_digest(hm.heights, hm.pixel_mm), digest(config.as_dict()))
            if key in done:
                continue
            start = time.perf_counter()
            r = sim.run(hm)
            row = {"texture": name, "texture_digest": key[0], "config_digest": key[1], "element": element,
                   "h_contact_mm": h, "roughness": r.roughness, "roughness_stderr": r.roughness_stderr,
                   "contact_fraction": r.contact_fraction, "converged": bool(r.converged),
                   "iterations": int(r.iterations), "nodes": int(r.nodes), "seconds": time.perf_counter() - start}
            with open(args.out, "a") as f:
                f.write(json.dumps(row) + "\n")
                f.flush()
                os.fsync(f.fileno())
            done.add(key)
            print(f"{element} h={h}: {name}: V = {r.roughness:.5f} ({row['seconds']:.0f} s, {r.nodes} nodes)",
                  file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
