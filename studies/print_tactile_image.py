"""A four-colour tactile picture designed for a 0.4 mm FDM printer, verified as printed (issue 40).

The picture (``examples/design/four-colours.png``, written here if missing) is four flat colours in a 2 x 2 grid,
each block 30 mm square on a 60 mm plate: large enough for whole 10 mm footprints. The palette is
``roughness.palette(k=4, min_jnd=2, printer=P, verify="spectral")``: four variants of standard-1.0 that the printer
can make, verified >= 2 JND apart as printed by the spectral engine. The plate is ``roughness.tactile_image`` with
those textures and the printer: its roughness map (surrogate) is of the plate as printed, and each region's
median is compared with the others. Last, the closest pair of the palette as printed is solved by the FEM at the
shipped model's label fidelity (V with its Monte Carlo standard error; the pair's distance with a +-2 sigma band).

    python studies/print_tactile_image.py      # a few minutes on one shared core (the two FEM solves)

Writes results/print_tactile_image.json and .md.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[1]
PICTURE = ROOT / "examples" / "design" / "four-colours.png"
RESULTS = Path(__file__).parent / "results"
PRINTER = "fdm-0.4-0.2"
COLOURS = [(245, 240, 225), (220, 120, 30), (30, 40, 110), (60, 150, 70)]  # cream, orange, navy, green
LOG_JND = math.log(1.19)


def make_picture(path: Path) -> None:
    """Four flat colours, 2 x 2 blocks of 20 x 20 pixels."""
    import numpy as np
    from PIL import Image

    rgb = np.zeros((40, 40, 3), np.uint8)
    for i, colour in enumerate(COLOURS):
        rgb[20 * (i // 2):20 * (i // 2 + 1), 20 * (i % 2):20 * (i % 2 + 1)] = colour
    Image.fromarray(rgb).save(path)


def jnd_apart(evaluator, v_lo: float, v_hi: float) -> float:
    return math.log(evaluator.lambda_of(v_hi) / evaluator.lambda_of(v_lo)) / LOG_JND


def main() -> None:
    argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
    import roughness
    from roughness.design.evaluation import Evaluator
    from roughness.surface.printing import PROFILES

    if not PICTURE.exists():
        make_picture(PICTURE)
    t = time.perf_counter()
    palette = roughness.palette(k=4, min_jnd=2.0, printer=PRINTER, verify="spectral")
    palette_seconds = time.perf_counter() - t
    members = [{"name": m.name, "height_factor": m.recipe["height_factor"],
                "lateral_factor": m.recipe["lateral_factor"], "spectral_V_printed": m.fem.roughness,
                "spectral_V_stderr": m.fem.roughness_stderr, "spectral_lambda_mm": m.fem.equivalent_lambda_mm}
               for m in palette.members]
    plates = {}
    for pixel in (None, 0.1):  # the default (with a printer: the textures' pixel), and the digital default's 0.1 mm
        t = time.perf_counter()
        plate = roughness.tactile_image(str(PICTURE), [m.heightmap for m in palette.members], size_mm=60.0,
                                        texture_pixel_mm=palette.members[0].heightmap.pixel_mm, printer=PRINTER,
                                        background=None, pixel_mm=pixel)
        regions = [{"colour": list(r.colour), "texture": r.texture, "plate_V_printed": r.plate_roughness,
                    "plate_V_digital": r.digital_plate_roughness, "plate_lambda_mm": r.plate_lambda_mm,
                    "footprints": r.footprints} for r in plate.regions]
        lams = sorted(r["plate_lambda_mm"] for r in regions if r["plate_lambda_mm"])
        plates[pixel] = {"pixel_mm": plate.heightmap.pixel_mm, "regions": regions, "notes": list(plate.notes),
                         "closest_jnd": min(math.log(b / a) / LOG_JND for a, b in zip(lams, lams[1:])),
                         "seconds": time.perf_counter() - t}
    regions, plate_closest, plate_seconds = plates[None]["regions"], plates[None]["closest_jnd"], plates[None]["seconds"]
    gaps = [math.log(b.fem.equivalent_lambda_mm / a.fem.equivalent_lambda_mm) / LOG_JND
            for a, b in zip(palette.members, palette.members[1:])]
    i = gaps.index(min(gaps))
    fem = Evaluator(printer=PROFILES[PRINTER])
    solved = []
    for m in palette.members[i:i + 2]:
        t = time.perf_counter()
        r = fem.verify(m.heightmap)
        solved.append({"name": m.name, "V": r.roughness, "V_stderr": r.roughness_stderr,
                       "lambda_mm": r.equivalent_lambda_mm, "seconds": time.perf_counter() - t})
    lo, hi = solved
    record = {"picture": str(PICTURE.relative_to(ROOT)), "printer": PRINTER, "palette": members,
              "palette_closest_jnd_spectral": palette.closest_jnd, "palette_seconds": palette_seconds,
              "plate_pixel_mm": plates[None]["pixel_mm"], "regions": regions,
              "plate_closest_jnd_surrogate": plate_closest, "plate_seconds": plate_seconds,
              "plate_at_0.1mm": plates[0.1],
              "fem": {"verifier": fem.verifier, "pair": solved, "jnd": jnd_apart(fem, lo["V"], hi["V"]),
                      "jnd_2sigma": [jnd_apart(fem, lo["V"] + 2 * lo["V_stderr"], hi["V"] - 2 * hi["V_stderr"]),
                                     jnd_apart(fem, lo["V"] - 2 * lo["V_stderr"], hi["V"] + 2 * hi["V_stderr"])]}}
    (RESULTS / "print_tactile_image.json").write_text(json.dumps(record, indent=1) + "\n")
    f = record["fem"]
    lines = ["# A four-colour tactile picture for fdm-0.4-0.2, verified as printed", "",
             f"`python studies/print_tactile_image.py`: `{record['picture']}` (2 x 2 flat colours) on a 60 mm plate.",
             "", "| texture | height x | spectral V as printed (± s.e.) | lambda mm |", "|---|---|---|---|",
             *(f"| {m['name']} | {m['height_factor']:.3f} | {m['spectral_V_printed']:.4f} ± "
               f"{m['spectral_V_stderr']:.4f} | {m['spectral_lambda_mm']:.3f} |" for m in members), "",
             f"Palette: closest pair {palette.closest_jnd:.2f} JND apart as printed (spectral), "
             f"{palette_seconds:.0f} s.", "",
             "| region colour | texture | plate V as printed (digital) | lambda mm | footprints |", "|---|---|---|---|---|",
             *(f"| #{''.join(f'{c:02x}' for c in r['colour'])} | {r['texture']} | {r['plate_V_printed']:.4f} "
               f"({r['plate_V_digital']:.4f}) | {r['plate_lambda_mm']:.3f} | {r['footprints']} |" for r in regions), "",
             f"The plate as printed at {plates[None]['pixel_mm']:g} mm pixels (the default with a printer: the "
             f"textures' pixel; surrogate map, medians over footprints wholly inside a region): closest regions "
             f"{plate_closest:.2f} JND apart; {plate_seconds:.0f} s. At 0.1 mm pixels (the default without a printer, "
             f"and before): {plates[0.1]['closest_jnd']:.2f} JND.", "",
             f"FEM ({f['verifier']}) on the palette's closest pair as printed: {lo['name']} V {lo['V']:.4f} ± "
             f"{lo['V_stderr']:.4f}, {hi['name']} V {hi['V']:.4f} ± {hi['V_stderr']:.4f}: {f['jnd']:.2f} JND apart "
             f"(±2σ: {f['jnd_2sigma'][0]:.2f}..{f['jnd_2sigma'][1]:.2f})."]
    (RESULTS / "print_tactile_image.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
