"""A measured-like scan cleaned step by step: V before and after each step, against the clean texture.

The scan is made from the standard texture lambda = 1.0 mm (seed 0, 12 mm at 0.05 mm; bumps
1 mm tall, and 0.1 mm tall for a fine texture) as an instrument would deliver it: heights in
micrometres, tilted by 0.03 mm/mm along x and half that along y (1.9 degrees, 0.54 mm corner to
corner), 3% of the points missing (NaN: dropouts and a few blobs), 0.2% spikes of 0.3 to 2 mm. V is from the spectral engine; the JND distance is ln(lambda_eq / lambda_eq_clean) / ln(1.19).
The table goes to results/scan_cleanup.md and is linked from docs/how-to/real-surfaces.md.

    python studies/scan_cleanup.py
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

OUT = Path(__file__).parent / "results" / "scan_cleanup.md"
TILT = 0.03  # mm per mm, along x and half of it along y
MISSING = 0.03
SPIKES = 0.002
HEIGHTS_MM = (1.0, 0.1)  # the standard bumps, and the same ten times lower (a fine texture)


def measured_like(height_mm: float, seed: int = 0) -> tuple[object, np.ndarray]:
    """The clean texture (bumps ``height_mm`` tall) and its scan: micrometres, tilt, holes (NaN) and spikes."""
    from scipy.ndimage import binary_dilation

    from roughness.dataset.textures import standard_texture

    clean = standard_texture(1.0, height_mm=height_mm)
    rng = np.random.default_rng(seed)
    ny, nx = clean.shape
    y, x = np.mgrid[0:ny, 0:nx] * clean.pixel_mm
    scan = clean.heights + TILT * x + TILT / 2 * y
    spikes = rng.random(scan.shape) < SPIKES
    scan[spikes] += rng.choice([-1, 1], spikes.sum()) * rng.uniform(0.3, 2.0, spikes.sum())
    holes = binary_dilation(rng.random(scan.shape) < 0.002, iterations=2)  # blobs
    holes |= rng.random(scan.shape) < MISSING - holes.mean()  # and dropouts
    scan[holes] = np.nan
    return clean, scan * 1000  # micrometres


def rows(height_mm: float) -> list[tuple[str, str, str, str]]:
    """(state, what the tool says, V, JND from the clean texture) for bumps ``height_mm`` tall."""
    import tempfile

    from roughness.core.errors import InputError
    from roughness.perceptual_scale import jnd
    from roughness.prediction import predict
    from roughness.surface.cleanup import Cleanup
    from roughness.surface.cleanup import clean as cleanup
    from roughness.surface.heightmap import Heightmap
    from roughness.surface.loading import load_surface
    from roughness.surface.units import FileUnits

    clean, scan = measured_like(height_mm)
    reference = predict([clean], engine="spectral")[0]

    def answer(hm: Heightmap) -> tuple[str, str]:
        p = predict([hm], engine="spectral")[0]
        lam, ref = p.placement.equivalent_lambda_mm, reference.placement.equivalent_lambda_mm
        return f"{p.roughness:.4f}", ("below the scale" if lam is None or ref is None else
                                      f"{jnd(lam, ref):+.2f}")

    out = [("the clean texture (reference)", "-", f"{reference.roughness:.4f}", "0")]
    with tempfile.TemporaryDirectory() as folder:  # as read: micrometres, through the CLI's reading
        path = Path(folder) / "scan.npy"
        np.save(path, scan)
        try:
            load_surface(path, FileUnits(clean.pixel_mm), spec=Cleanup(fill=True))
        except InputError as err:
            said = str(err).replace(f"{path}: ", "")
            said = said.split(", e.g.")[0] + " (check the file's unit)" if "e.g." in said else said.split(":")[0]
            out.append(("as read (um), --fill", f"refused: {said}", "-", "-"))
    mm = scan / 1000
    try:
        cleanup(mm, clean.pixel_mm, Cleanup())
    except InputError as err:
        out.append(("converted to mm", "refused: " + str(err).split(": ", 1)[1], "-", "-"))
    out.append(("mm, holes set to 0 (what a tool without --fill might do)", "-",
                *answer(Heightmap(np.where(np.isnan(mm), 0.0, mm), clean.pixel_mm))))
    steps = [("--fill", Cleanup(fill=True)), ("--fill --despike 5", Cleanup(fill=True, despike=5.0)),
             ("--fill --despike 5 --level plane", Cleanup(fill=True, despike=5.0, level="plane")),
             ("--fill --level plane (no --despike)", Cleanup(fill=True, level="plane"))]
    for name, spec in steps:
        hm, done = cleanup(mm, clean.pixel_mm, spec)
        out.append((f"mm, {name}", "; ".join(done.lines()), *answer(hm)))
    return out


def main(argv: list[str] | None = None) -> int:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args(argv)
    results = {height: rows(height) for height in HEIGHTS_MM}
    compact = ["| scan | " + " | ".join(f"V, {h:g} mm bumps | JND" for h in HEIGHTS_MM) + " |",
               "| --- |" + " ---: | ---: |" * len(HEIGHTS_MM)]
    for i, (state, said, _, _) in enumerate(results[HEIGHTS_MM[0]]):
        refused = said.startswith("refused")
        cells = " | ".join(f"{'refused' if refused else results[h][i][2]} | {results[h][i][3]}" for h in HEIGHTS_MM)
        compact.append(f"| {state} | {cells} |")
    lines = ["\n".join(compact)]
    for height, found in results.items():
        lines += [f"\nBumps {height:g} mm tall, what the tool said:\n", "| scan | what the tool did | V (spectral) | "
                  "JND from clean |", "| --- | --- | ---: | ---: |"]
        lines += [f"| {state} | {said} | {v} | {j} |" for state, said, v, j in found]
    text = ("# A measured-like scan cleaned step by step\n\nRegenerate: `python studies/scan_cleanup.py`. "
            + __doc__.split("\n\n")[1].replace("\n", " ") + "\n\n" + "\n".join(lines) + "\n")
    OUT.parent.mkdir(exist_ok=True)
    OUT.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
