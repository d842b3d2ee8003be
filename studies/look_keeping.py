"""Look-keeping tuning on three textures: the same feel target reached by height alone, lateral scale alone, and
the mix that changes the look least (``design.look_keeping``, ``tune --keep-look``), each look change measured.

Each texture (``texture make``'s names) is tuned 1 JND rougher on its spectral V (``--verify spectral``, tile)
and compared, whole, with itself (``design.look.look_difference``). Height alone is the search's lateral x 1
candidate; lateral alone is its first. Then the trade on the hidden-shapes base (``design.hidden_shapes
.default_base``: bumps 1 mm apart, 2.5 mm tall on 1 mm bases): for each feel change of ``TRADE_JND``, the least
look change the search finds, which says how much feel a "felt, not seen" plate can hide below 1 look JND.

    python studies/look_keeping.py          # ~15 min on 2 cores; writes studies/results/look_keeping.{md,json}
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

ROOT = Path(__file__).parents[1]
TEXTURES = ("standard-1.0", "standard-1.5", "flattop-0.3")
TARGET_JND = 1.0
TRADE_JND = (-2.0, -1.5, -1.0, -0.5, 0.5, 1.0)


def kept(name: str, jnd: float = TARGET_JND) -> dict:
    """The look-keeping search for ``name`` (or "hidden-shapes base"), ``jnd`` JND, spectral; its candidates and
    the plain knobs' looks."""
    from roughness.dataset.textures import named_texture
    from roughness.design.evaluation import Evaluator
    from roughness.design.hidden_shapes import default_base
    from roughness.design.look_keeping import keep_look
    from roughness.design.tune import target_of

    evaluator = Evaluator(fidelity="spectral")
    hm = default_base() if name == "hidden-shapes base" else named_texture(name)
    found = keep_look(hm, target_of(evaluator, jnd=jnd, heightmap=hm, tile=True), evaluator, tile=True)
    by_lateral = {c.lateral: c for c in found.candidates[1:]}
    alone = found.candidates[0]
    chosen = found.chosen
    return {"texture": name, "target_jnd": jnd, "lateral": chosen.lateral, "height": chosen.height,
            "look": chosen.look.as_dict(), "jnd_error": chosen.result.jnd_error,
            "height_alone": by_lateral[1.0].as_dict(), "lateral_alone": alone.as_dict(),
            "candidates": [c.as_dict() for c in found.candidates]}


def table(rows: list[dict], trade: list[dict]) -> str:
    def look(c: dict) -> str:
        if not c["reached"]:
            return "not reached" + (f" ({c['note']})" if c["note"] else "")
        return (f"{c['look']['difference_look_jnd']:.2f} (x {c['height_factor'] or c['lateral_factor']:.3g}, "
                f"texture {c['look']['texture_difference_look_jnd']:.2f})")

    lines = ["# Look-keeping tuning: the same feel, the least change of look", "",
             f"Written by `python studies/look_keeping.py`. Each texture tuned {TARGET_JND:+g} JND on its spectral V "
             "(tile), by height alone, lateral scale alone, and the mix that looks least changed "
             "(`tune --keep-look`); look change in look JND (design.look: the largest of the mean-luminance, "
             "distribution and band-texture terms; 'texture' is the band term alone).", "",
             "| texture | kept mix | look change (texture) | JND error | height alone | lateral alone |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['texture']} | lateral x {r['lateral']:.3g}, height x {r['height'] or 1:.3g} | "
                     f"{r['look']['difference_look_jnd']:.2f} ({r['look']['texture_difference_look_jnd']:.2f}) | "
                     f"{r['jnd_error']:+.2f} | {look(r['height_alone'])} | {look(r['lateral_alone'])} |")
    lines += ["", "The hidden-shapes base (bumps 1 mm apart, 2.5 mm tall on 1 mm bases): the least look change found "
              "for each feel change (a target no mix reaches is marked).", "",
              "| feel change (JND) | kept mix | look change (texture) | height alone | lateral alone |",
              "|---|---|---|---|---|"]
    for r in trade:
        if "refused" in r:
            lines.append(f"| {r['target_jnd']:+g} | not reached: {r['refused']} | | | |")
            continue
        lines.append(f"| {r['target_jnd']:+g} | lateral x {r['lateral']:.3g}, height x {r['height'] or 1:.3g} | "
                     f"{r['look']['difference_look_jnd']:.2f} ({r['look']['texture_difference_look_jnd']:.2f}) | "
                     f"{look(r['height_alone'])} | {look(r['lateral_alone'])} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "studies" / "results"), help="folder for look_keeping.*")
    out = Path(parser.parse_args(argv).out)
    rows = []
    for name in TEXTURES:
        rows.append(kept(name))
        print(f"{name}: lateral x {rows[-1]['lateral']:.3g}, height x {rows[-1]['height'] or 1:.3g}, "
              f"look {rows[-1]['look']['difference_look_jnd']:.2f}", flush=True)
    from roughness.core.errors import InputError

    trade = []
    for jnd in TRADE_JND:
        try:
            trade.append(kept("hidden-shapes base", jnd))
        except InputError as err:
            trade.append({"texture": "hidden-shapes base", "target_jnd": jnd, "refused": str(err)[:200]})
        print(f"base {jnd:+g} JND: {trade[-1].get('look', {}).get('difference_look_jnd', 'refused')}", flush=True)
        (out / "look_keeping.md").write_text(table(rows, trade))  # what is done so far survives an interruption
    (out / "look_keeping.json").write_text(json.dumps({"textures": rows, "hidden_shapes_base": trade}, indent=1,
                                                      default=float) + "\n")
    print(table(rows, trade))


if __name__ == "__main__":
    main()
