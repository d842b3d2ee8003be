"""Palettes as printed: the default tactile-image palette and a printer-aware palette per profile, digital and printed.

The default palette of ``tactile-image`` for a four-colour picture is ``family_palette(4, 2.0)`` of the default family
(standard-1.0 scaled in height), designed digitally. A printer-aware palette is the same call with the evaluator
judging prints of that profile (issue 40: ``palette --k 4 --min-jnd 2 --printer P``). Every member of every palette
is printed by every shipped profile (``roughness.surface.printing``, periodic tile) and its V is computed with the
spectral engine (the paper's parameters, its Monte Carlo standard error beside V); the JND lost is the difference of
equivalent wavelengths on the spectral standard scale, printed against digital (None below the scale's floor: a
print that is flat or nearly). The closest pair of each palette, as each profile prints it, says whether its
members stay >= 2 JND apart. The standard scale as printed is studies/print_profiles.py's table.

    python studies/print_palettes.py            # about two minutes on one shared core

Writes results/print_palettes.json and .md.
"""
from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

OUT = Path(__file__).parent / "results" / "print_palettes"
K, MIN_JND = 4, 2.0


def palettes() -> dict:
    """The default (digital) palette and a printer-aware palette per shipped profile: name -> Palette (or the
    reason it could not be made)."""
    from roughness.core.errors import InputError
    from roughness.design.evaluation import Evaluator
    from roughness.design.palette import family_palette
    from roughness.surface.printing import PROFILES, printer_profile

    made = {"default (digital)": family_palette(K, MIN_JND, evaluator=Evaluator(fidelity="spectral"))}
    for name in PROFILES:
        try:
            made[f"for {name}"] = family_palette(K, MIN_JND, evaluator=Evaluator(fidelity="spectral",
                                                                                 printer=printer_profile(name)))
        except InputError as err:
            made[f"for {name}"] = str(err)
    return made


def measure(made: dict) -> dict:
    """Each member's spectral V digital and as printed by every profile, and the JND lost."""
    from roughness.perceptual_scale import jnd, load_scale
    from roughness.simulate.spectral.engine import SpectralSimulator
    from roughness.surface.printing import PROFILES, printed, printer_profile

    engine, scale = SpectralSimulator(), load_scale("spectral")

    def v_of(hm):
        result = engine.run(hm, tile=True)
        placed = scale.place(result.roughness)
        return {"V": result.roughness, "V_stderr": result.roughness_stderr,
                "lambda_mm": None if placed.below_scale else placed.equivalent_lambda_mm}

    out = {}
    for palette_name, palette in made.items():
        if isinstance(palette, str):
            out[palette_name] = {"refused": palette}
            continue
        members = []
        for member in palette.members:
            digital = v_of(member.heightmap)
            prints = {}
            for profile in PROFILES:
                p = v_of(printed(member.heightmap, printer_profile(profile), periodic=True).heightmap)
                lost = None if digital["lambda_mm"] is None or p["lambda_mm"] is None else \
                    jnd(p["lambda_mm"], digital["lambda_mm"])
                prints[profile] = {**p, "jnd": lost}
            members.append({"name": member.name, "recipe": member.recipe, "digital": digital, "printed": prints})
        closest = {profile: _closest([m["printed"][profile]["lambda_mm"] for m in members]) for profile in PROFILES}
        out[palette_name] = {"members": members, "closest_jnd_digital": _closest(
            [m["digital"]["lambda_mm"] for m in members]), "closest_jnd_printed": closest}
    return out


def _closest(lambdas: list) -> float | None:
    """The smallest JND distance between any two of ``lambdas`` (None if one is below the scale: flat)."""
    from roughness.perceptual_scale import jnd

    if any(lam is None for lam in lambdas):
        return None
    return min(abs(jnd(a, b)) for i, a in enumerate(lambdas) for b in lambdas[i + 1:])


def table(results: dict) -> str:
    """The Markdown report."""
    from roughness.surface.printing import PROFILES

    lines = ["# Palettes as printed", "",
             f"K = {K} textures, >= {MIN_JND:g} JND apart; V by the spectral engine (± its Monte Carlo standard "
             "error), JND lost printed against digital on the spectral standard scale (\"flat\": below the scale's "
             "floor). Regenerate: `python studies/print_palettes.py`.", ""]
    for name, entry in results.items():
        lines += [f"## {name}", ""]
        if "refused" in entry:
            lines += [f"Refused: {entry['refused']}", ""]
            continue
        lines += ["| member | digital V | " + " | ".join(f"{p}: V, JND" for p in PROFILES) + " |",
                  "|---|---|" + "---|" * len(PROFILES)]
        for m in entry["members"]:
            cells = [f"{m['printed'][p]['V']:.4f}, " + ("flat" if m["printed"][p]["jnd"] is None else
                                                       f"{m['printed'][p]['jnd']:+.2f}") for p in PROFILES]
            lines.append(f"| {m['name']} | {m['digital']['V']:.4f} ± {m['digital']['V_stderr']:.4f} | "
                         + " | ".join(cells) + " |")
        closest = ["none (a member prints flat)" if v is None else f"{v:.2f}"
                   for v in entry["closest_jnd_printed"].values()]
        lines += ["", f"Closest pair (JND): digital {entry['closest_jnd_digital']:.2f}; printed "
                  + ", ".join(f"{p} {c}" for p, c in zip(PROFILES, closest)), ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--render", action="store_true", help="the table again from results/print_palettes.json")
    args = parser.parse_args()
    path = OUT.with_suffix(".json")
    if args.render:
        results = json.loads(path.read_text())
    else:
        start = time.perf_counter()
        results = measure(palettes())
        OUT.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(results, indent=1) + "\n")
        print(f"measured in {time.perf_counter() - start:.0f} s")
    OUT.with_suffix(".md").write_text(table(results) + "\n")


if __name__ == "__main__":
    main()
