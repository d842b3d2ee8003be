"""The paper's "seen but not felt / felt but not seen" plates, tried on this model (coarse FEM, 10 N).

Seen but not felt: change only the valleys the skin does not reach. The lowest q% of a standard
texture's pixels are deepened by 0.5 mm (a visible change of shading) and the FEM says how much of
it is felt, in JNDs. Felt but not seen: the texture's heights scaled (``tune``, by height) to one
JND rougher, the bumps' positions and outlines unchanged; the relief grows by the factor reported.
Writes a Markdown table.

    python examples/design/seen_not_felt.py --out examples/design/seen_not_felt.md     # ~1 min on 2 cores
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

DEEPEN_MM = 0.5
QUANTILES = (0.02, 0.05, 0.10)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="seen_not_felt.md", help="Markdown table to write")
    args = parser.parse_args(argv)
    from roughness.core.files import atomic_write
    from roughness.dataset.textures import standard_texture
    from roughness.design.evaluation import Evaluator
    from roughness.design.tune import target_of, tune
    from roughness.perceptual_scale import jnd
    from roughness.surface.heightmap import Heightmap

    evaluator = Evaluator()
    hm = standard_texture(1.0, seed=0)
    contact = evaluator.fem.simulate(hm).contact_fraction
    base = evaluator.verify(hm)
    rows = []
    for q in QUANTILES:
        level = float(np.quantile(hm.heights, q))
        deeper = Heightmap(np.where(hm.heights < level, hm.heights - DEEPEN_MM, hm.heights), hm.pixel_mm)
        fem = evaluator.verify(deeper)
        rows.append(f"| lowest {100 * q:.0f}% of pixels (below {level:.3f} mm) deepened by {DEEPEN_MM} mm | "
                    f"{fem.roughness:.4f} | {jnd(fem.equivalent_lambda_mm, base.equivalent_lambda_mm):+.2f} |")
    felt = tune(hm, target_of(evaluator, lambda_mm=base.equivalent_lambda_mm * 1.19), "height", evaluator)
    rows.append(f"| heights x {felt.factor:.3f} (relief {np.ptp(hm.heights):.2f} -> {np.ptp(felt.heightmap.heights):.2f}"
                f" mm), tuned to +1 JND | {felt.achieved.roughness:.4f} | "
                f"{jnd(felt.achieved.equivalent_lambda_mm, base.equivalent_lambda_mm):+.2f} |")
    text = "\n".join([
        "# Seen but not felt, felt but not seen (standard-1.0, seed 0, coarse FEM, 10 N)", "",
        f"The skin touches {100 * contact:.1f}% of the footprint; unchanged V = {base.roughness:.4f} "
        f"± {base.roughness_stderr:.4f}.", "",
        "| change | FEM V | felt (JND) |", "|---|---|---|", *rows, ""])
    atomic_write(Path(args.out), lambda tmp: Path(tmp).write_text(text))
    print(text)


if __name__ == "__main__":
    main()
