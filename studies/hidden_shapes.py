"""The paper's Fig. 25 on this model: the four shapes, seen-not-felt and felt-not-seen (design.hidden_shapes).

Each shape (circle, square, triangle, cross; half the plate's side across) is hidden in a 40 mm plate of the
default base (bumps 1 mm apart, 2.5 mm tall on 1 mm bases: the standard textures leave no floor clear of the skin
at 10 N) in both modes. The table gives, per plate, the feel difference between shape and background (spectral
engine over the whole plate, footprints 2 mm apart) and the look difference (design.look), with the checks. The
felt plates' look-keeping search tries lateral factors around the best found on the full grid (0.8 for this base:
``LATERALS``) to keep the run short. With ``--fem``, the coarse FEM answers on a few footprints of both circle
plates (inside the shape, across its outline, outside), each against the same footprint on the unchanged base.

    python studies/hidden_shapes.py --fem     # ~25 min on 2 cores; writes studies/results/hidden_shapes.{md,json,png}
"""
from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

ROOT = Path(__file__).parents[1]
PLATE_MM = 40.0
STEP_MM = 2.0
LATERALS = (0.75, 0.8, 0.85, 0.9)
KINDS = {"seen": ("seen", None), "felt": ("felt", 2.0), "felt 1 JND": ("felt", 1.0)}  # label: mode, felt JND
FEM_CENTRES_MM = {"inside": (20.0, 20.0), "across the outline": (30.0, 20.0), "outside": (6.0, 6.0)}


def plates(out: Path) -> dict:
    from roughness.design.hidden_shapes import default_base, hidden_plate
    from roughness.design.shapes import SHAPES, builtin_mask

    tile = default_base()
    n = round(PLATE_MM / tile.pixel_mm)
    made = {}
    for shape in SHAPES:
        for label, (mode, felt_jnd) in KINDS.items():
            start = time.perf_counter()
            made[shape, label] = hidden_plate(tile, builtin_mask(shape, (n, n)), mode, step_mm=STEP_MM,
                                              laterals=LATERALS, felt_jnd=felt_jnd or 2.0)
            print(f"{shape} {label}: {made[shape, label]!r} ({time.perf_counter() - start:.0f} s)", flush=True)
            (out / "hidden_shapes.md").write_text(table(made, []))  # what is done so far survives an interruption
    return made


def fem_footprints(plate, label: str) -> list[dict]:
    """Coarse FEM V of a circle plate and of its base at FEM_CENTRES_MM, and their distance in JND."""
    from roughness.design.evaluation import Evaluator
    from roughness.design.hidden_shapes import default_base, lay
    from roughness.perceptual_scale import jnd_distance
    from roughness.surface.heightmap import Heightmap

    evaluator = Evaluator(fidelity="coarse")
    base = lay(default_base(), plate.mask.shape)
    recess = plate.change["recess_mm"] if plate.mode == "seen" else 0.0
    finished = Heightmap(plate.heightmap.heights - recess, plate.heightmap.pixel_mm)  # the base's datum
    rows = []
    for where, centre in FEM_CENTRES_MM.items():
        a, b = evaluator.verify(finished, centre_mm=centre), evaluator.verify(base, centre_mm=centre)
        d = jnd_distance(evaluator.scale, a.roughness, b.roughness, a.roughness_stderr, b.roughness_stderr)
        rows.append({"mode": label, "where": where, "centre_mm": centre, "plate_roughness": a.roughness,
                     "plate_roughness_stderr": a.roughness_stderr, "base_roughness": b.roughness,
                     "base_roughness_stderr": b.roughness_stderr, "jnd": d.jnd, "jnd_stderr": d.jnd_stderr})
        print(f"FEM {label} {where}: {rows[-1]}", flush=True)
    return rows


def table(made: dict, fem: list[dict]) -> str:
    lines = ["# Hidden shapes: seen, not felt; felt, not seen (the paper's Fig. 25)", "",
             f"Written by `python studies/hidden_shapes.py{' --fem' if fem else ''}`. Plates {PLATE_MM:g} mm, the "
             "default base (bumps 1 mm apart, 2.5 mm tall on 1 mm bases), shapes half the plate's side across. Feel: "
             f"spectral engine over the whole plate, footprints {STEP_MM:g} mm apart, mean V of the positions whose "
             "8 mm sampling window lies in the shape against those clear of it, in JND (± its standard error over "
             "the positions, a lower bound: neighbours overlap). Look: design.look, in units of the assumed 2% "
             "contrast threshold and, for the texture of light and dark, of the assumed 15% contrast-discrimination "
             "fraction (the base plate's same regions in brackets: the texture's own variation); 'texture' is the "
             "part of the look from the bands alone.", "",
             "| shape | mode | change | feel (JND) | look (look JND) | texture (look JND) | checks |",
             "|---|---|---|---|---|---|---|"]
    for (shape, mode), p in made.items():
        if mode == "seen":
            change = f"recess {p.change['recess_mm']:g} mm on {100 * p.change['changed_fraction_of_shape']:.1f}% of it"
        else:
            steps = p.change["target_jnd"]
            kept = p.change[f"{steps:+g} JND"]
            change = f"lateral x {kept['lateral_factor']:.3g}, height x {kept['height_factor']:.3g} ({steps:+g} JND)"
        feel = "-" if p.feel is None or p.feel.jnd is None else f"{p.feel.jnd:+.2f} ± {p.feel.jnd_stderr:.2f}"
        passed = sum(c.passed for c in p.checks)
        failed = "; ".join(c.claim.split(":")[0] for c in p.checks if not c.passed)
        lines.append(f"| {shape} | {mode} | {change} | {feel} | {p.look.difference:.2f} ({p.base_look.difference:.2f}) "
                     f"| {p.look.texture_difference:.2f} "
                     f"| {passed}/{len(p.checks)}{' (fails: ' + failed + ')' if failed else ''} |")
    if fem:
        lines += ["", "FEM (coarse) on footprints of the circle plates against the same footprints on the base:",
                  "", "| plate | footprint | centre (mm) | V plate | V base | JND |", "|---|---|---|---|---|---|"]
        lines += [f"| {r['mode']} | {r['where']} | {r['centre_mm'][0]:g}, {r['centre_mm'][1]:g} | {r['plate_roughness']:.4f} ± "
                  f"{r['plate_roughness_stderr']:.4f} | {r['base_roughness']:.4f} ± {r['base_roughness_stderr']:.4f} | "
                  f"{r['jnd']:+.3f} ± {r['jnd_stderr']:.3f} |" for r in fem]
    return "\n".join(lines) + "\n"


def figure(made: dict, path: Path) -> None:
    """The rendered look of all eight plates, shapes across, modes down."""
    from roughness.core.figures import new_figure
    from roughness.design.look import photograph

    fig = new_figure(figsize=(16, 12.6), layout="constrained")
    axes = fig.subplots(len(KINDS), 4)
    for col, shape in enumerate(dict.fromkeys(s for s, _ in made)):
        for row, mode in enumerate(KINDS):
            p = made[shape, mode]
            axes[row, col].imshow(photograph(p.luminance), cmap="gray", vmin=0, vmax=1, interpolation="antialiased",
                                  extent=(0, PLATE_MM, PLATE_MM, 0))
            feel = "-" if p.feel is None or p.feel.jnd is None else f"{p.feel.jnd:+.2f}"
            axes[row, col].set_title(f"{shape}, {mode}: feel {feel} JND, look {p.look.difference:.1f}", fontsize=10)
    fig.suptitle("rendered look, as photographed (rows: seen, not felt; felt, not seen at 2 JND; at 1 JND)")
    fig.savefig(path, dpi=120)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fem", action="store_true",
                        help="also the coarse FEM on three footprints of each circle plate")
    parser.add_argument("--out", default=str(ROOT / "studies" / "results"), help="folder for hidden_shapes.*")
    args = parser.parse_args(argv)
    from roughness.design.hidden_shapes import figure as plate_figure

    out = Path(args.out)
    made = plates(out)
    fem = [row for label in KINDS for row in fem_footprints(made["circle", label], label)] if args.fem else []
    (out / "hidden_shapes.md").write_text(table(made, fem))
    (out / "hidden_shapes.json").write_text(json.dumps({f"{s} {m}": p.summary() for (s, m), p in made.items()}
                                                       | {"fem": fem}, indent=1, default=float) + "\n")
    figure(made, out / "hidden_shapes.png")
    for label in KINDS:
        plate_figure(made["circle", label]).savefig(out / f"hidden_shapes_circle_{label.replace(' ', '_')}.png",
                                                    dpi=90)
    print((out / "hidden_shapes.md").read_text())


if __name__ == "__main__":
    main()
