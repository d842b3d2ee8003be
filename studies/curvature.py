"""Roughness of textures on curved bases against the flat texture, as in the paper's Figure 20.

Standard bump textures (lambda 0.75, 1.0, 1.25 mm; several realisations each, tiled as the
periodic textures they are) on cylinders (or spheres) of radius 3, 5, 10, 20 and 40 mm, convex
and concave (plus concave 6 and 7.5 mm), and flat. Per texture, the percent difference of V on the curved base from V on the flat one,
against the 19% line, and the same difference in JND on the standard scale of the fidelity.
Heights are laid off along the base normal (the product's default) and, for the record of
that choice, along z. Concave bases narrower than the 10 mm skin footprint are refused by the
model and reported as such. Results are appended to a JSON-lines file keyed by the texture's
content and the configuration, so an interrupted run resumes where it stopped. From the
results it writes the range of curvatures where curved and flat V agree within the tolerance
for every texture (``models/curvature_range.json``, read by ``roughness predict``).

    nice -n 10 python studies/curvature.py --fidelity coarse   # about 20 min on a busy 2-core machine
    nice -n 10 python studies/curvature.py --fidelity coarse --base sphere --normal-only
    nice -n 10 python studies/curvature.py --fidelity default --seeds 1 --normal-only --no-range
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from dataclasses import asdict
from datetime import datetime, timezone
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "studies" / "results"
RANGE_PATH = ROOT / "models" / "curvature_range.json"
LAMBDAS_MM = (0.75, 1.0, 1.25)
RADII_MM = (3.0, 5.0, 10.0, 20.0, 40.0)
# Concave radii between the 10 mm footprint's limit (5 mm) and 10 mm probe the paper's concave claim.
EXTRA_CONCAVE_MM = (-6.0, -7.5)
CURVATURES_MM = tuple(sorted([*RADII_MM, *(-r for r in RADII_MM), *EXTRA_CONCAVE_MM], key=lambda r: 1 / r))
TOLERANCE = 0.19  # the paper's threshold on the relative difference of V (the Weber fraction)
ALONG = ("normal", "z")


def cases(seeds: int, base: str, along: tuple[str, ...]) -> list[dict]:
    """Every (texture, base) case of the study: flat first, then curved with heights along each of ``along``."""
    out = []
    for lam in LAMBDAS_MM:
        for seed in range(seeds):
            out.append({"lambda_mm": lam, "seed": seed, "curvature_mm": None, "texture_along": "normal"})
            for way in along:
                out += [{"lambda_mm": lam, "seed": seed, "curvature_mm": r, "texture_along": way, "base": base}
                        for r in CURVATURES_MM]
    return out


def run(fidelity: str, seeds: int, path: Path, base: str = "cylinder", along: tuple[str, ...] = ALONG) -> list[dict]:
    from roughness.core.errors import InputError, SimulationError
    from roughness.core.hashing import array_digest, digest
    from roughness.dataset.textures import standard_texture
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    done = {}
    if path.exists():
        for line in path.read_text().splitlines():
            row = json.loads(line)
            done[row["key"]] = row
    sim = Simulator(SimConfig(fidelity=fidelity))
    textures: dict[tuple, object] = {}
    rows = []
    with path.open("a") as f:
        for case in cases(seeds, base, along):
            hm = textures.setdefault((case["lambda_mm"], case["seed"]),
                                     standard_texture(case["lambda_mm"], seed=case["seed"]))
            overrides = {"curvature_mm": case["curvature_mm"], "texture_along": case["texture_along"],
                         "base": case.get("base", "cylinder")}
            try:
                config = SimConfig(**{**asdict(sim.config), **overrides}).resolved(hm)
            except InputError as err:
                config, refused = None, str(err)
            key = digest({"texture": array_digest(hm.heights), "pixel_mm": hm.pixel_mm, "tile": True,
                          "config": asdict(config) if config else {**asdict(sim.config), **overrides}})
            if key in done:
                rows.append(done[key])
                continue
            row = {"key": key, **case, "fidelity": fidelity}
            if config is None:
                row.update(refused=refused)
            else:
                try:
                    r = sim.run(hm, tile=True, **overrides)
                    row.update(V=r.roughness, V_stderr=r.roughness_stderr, contact_fraction=r.contact_fraction,
                               indentation_mm=r.indentation_mm, converged=r.converged, rounds=r.iterations,
                               seconds=r.seconds)
                except (InputError, SimulationError) as err:
                    row.update(refused=str(err))
            f.write(json.dumps(row) + "\n")
            f.flush()
            rows.append(row)
            print(f"lambda {case['lambda_mm']} seed {case['seed']} R {case['curvature_mm']} {base} {case['texture_along']}: "
                  + (f"V {row['V']:.4f}" if "V" in row else f"refused: {row['refused'][:90]}"), flush=True)
    return rows


def differences(rows: list[dict], fidelity: str, base: str = "cylinder") -> list[dict]:
    """Per (lambda, curvature, along) on ``base``: mean and range over seeds of the relative difference from flat, and JND."""
    from roughness.perceptual_scale import jnd, load_scale

    scale = load_scale(fidelity)
    flat = {(r["lambda_mm"], r["seed"]): r["V"] for r in rows if r["curvature_mm"] is None and "V" in r}
    out = []
    for along in ALONG:
        for lam in LAMBDAS_MM:
            for radius in CURVATURES_MM:
                group = [r for r in rows if r["lambda_mm"] == lam and r["curvature_mm"] == radius
                         and r["texture_along"] == along and r.get("base", "cylinder") == base]
                ok = [r for r in group if "V" in r and (lam, r["seed"]) in flat]
                entry = {"texture_along": along, "lambda_mm": lam, "curvature_mm": radius,
                         "curvature_per_mm": 1 / radius, "seeds": len(ok)}
                if not group:
                    continue
                if not ok:
                    entry["refused"] = group[0].get("refused", "no flat reference")
                else:
                    rel = np.array([r["V"] / flat[(lam, r["seed"])] - 1 for r in ok])
                    jnds = np.array([jnd(scale.place(r["V"]).equivalent_lambda_mm,
                                         scale.place(flat[(lam, r["seed"])]).equivalent_lambda_mm) for r in ok])
                    entry.update(relative_difference=float(rel.mean()), relative_min=float(rel.min()),
                                 relative_max=float(rel.max()), jnd=float(jnds.mean()),
                                 contact_fraction=float(np.mean([r["contact_fraction"] for r in ok])),
                                 indentation_mm=float(np.mean([r["indentation_mm"] for r in ok])),
                                 converged=all(r["converged"] for r in ok))
                out.append(entry)
    return out


def agreement_range(diffs: list[dict], tolerance: float) -> dict:
    """The interval of curvature (1/mm) around flat where every texture's |mean difference| stays within tolerance."""
    normal = [d for d in diffs if d["texture_along"] == "normal"]
    ok = {}
    for d in normal:
        good = "relative_difference" in d and abs(d["relative_difference"]) <= tolerance
        ok[d["curvature_mm"]] = ok.get(d["curvature_mm"], True) and good
    convex = sorted(r for r in ok if r > 0)[::-1]  # from gentle to sharp
    concave = sorted(r for r in ok if r < 0)  # from gentle (most negative) to sharp
    limits = {}
    for name, radii in (("convex", convex), ("concave", concave)):
        passed = []
        for r in radii:
            if not ok[r]:
                break
            passed.append(r)
        limits[name] = min(passed, key=abs) if passed else None
    return {"min_convex_radius_mm": limits["convex"], "min_concave_radius_mm": (
        abs(limits["concave"]) if limits["concave"] is not None else None)}


def _table(diffs: list[dict], limits: dict, command: str, fidelity: str, seeds: int, base: str) -> str:
    shapes = "cylinders straight along x" if base == "cylinder" else "spherical caps"
    lines = [f"# V on curved bases against flat ({fidelity} fidelity, {seeds} realisations per lambda)", "",
             f"`{command}`; {shapes}, 10 N, stick, tiled standard textures.", "",
             ("Percent difference of V from the flat texture's (mean over realisations, [min, max]) and the same "
              "difference in JND on the standard scale. `refused`: the model refuses the base (reasons below)."), ""]
    for along in ALONG:
        rows = [d for d in diffs if d["texture_along"] == along]
        if not rows:
            continue
        lines += [f"## Heights along {along}", "", "| R (mm) | 1/R (1/mm) | " + " | ".join(
            f"lambda {lam} mm: %, JND" for lam in LAMBDAS_MM) + " | contact |", "|---" * (3 + len(LAMBDAS_MM)) + "|"]
        for radius in CURVATURES_MM:
            cells, contact = [], ""
            for lam in LAMBDAS_MM:
                found = [d for d in rows if d["lambda_mm"] == lam and d["curvature_mm"] == radius]
                if found and "relative_difference" in found[0]:
                    d = found[0]
                    cells.append(f"{100 * d['relative_difference']:+.1f} [{100 * d['relative_min']:+.1f}, "
                                 f"{100 * d['relative_max']:+.1f}], {d['jnd']:+.2f}")
                    contact = f"{100 * d['contact_fraction']:.0f}%"
                else:
                    cells.append("refused" if found else "not run")
            lines.append(f"| {radius:+g} | {1 / radius:+.3f} | " + " | ".join(cells) + f" | {contact} |")
        lines.append("")
    reasons = sorted({d["refused"] for d in diffs if "refused" in d})
    if reasons:
        lines += ["Refused:", ""] + [f"- {r}" for r in reasons] + [""]
    verdict = (f"Within {100 * TOLERANCE:.0f}% for every texture (heights along the normal): convex radius down to "
               f"{limits['min_convex_radius_mm']} mm, concave radius down to {limits['min_concave_radius_mm']} mm.")
    lines += [verdict, ""]
    return "\n".join(lines)


def _plot(diffs: list[dict], path: Path, fidelity: str, base: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ways = [a for a in ALONG if any(d["texture_along"] == a for d in diffs)]
    fig, axes = plt.subplots(1, len(ways), figsize=(5 * len(ways), 4), sharey=True, squeeze=False)
    for ax, along in zip(axes[0], ways):
        for lam in LAMBDAS_MM:
            ds = [d for d in diffs if d["texture_along"] == along and d["lambda_mm"] == lam
                  and "relative_difference" in d]
            k = np.array([d["curvature_per_mm"] for d in ds])
            y = 100 * np.array([d["relative_difference"] for d in ds])
            lo = 100 * np.array([d["relative_min"] for d in ds])
            hi = 100 * np.array([d["relative_max"] for d in ds])
            ax.errorbar(k, y, yerr=[y - lo, hi - y], marker="o", capsize=3, label=f"lambda {lam} mm")
        for level in (-100 * TOLERANCE, 100 * TOLERANCE):
            ax.axhline(level, color="k", ls="--", lw=0.8)
        ax.axhline(0, color="grey", lw=0.5)
        ax.set_xlabel("curvature 1/R (1/mm): < 0 concave, > 0 convex")
        ax.set_title(f"heights along {along}")
    axes[0][0].set_ylabel("V difference from flat (%)")
    axes[0][0].legend()
    fig.suptitle(f"Textures on {base}s vs flat ({fidelity} fidelity; dashed: {100 * TOLERANCE:.0f}%)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _write_range(limits: dict, command: str, fidelity: str, seeds: int, base: str, results: Path) -> None:
    """Record this base's range in models/curvature_range.json, keeping the other bases' entries."""
    from roughness.core.hashing import file_sha256

    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True,
                            check=False).stdout.strip()
    data = json.loads(RANGE_PATH.read_text()) if RANGE_PATH.exists() else {}
    data = {"tolerance": TOLERANCE,
            "meaning": ("the flat-trained surrogate may answer for a base of radius R when R >= min_convex_radius_mm "
                        "(convex) or |R| >= min_concave_radius_mm (concave): there every studied texture's V on the "
                        "base differs from its flat V by at most `tolerance` (mean over realisations); null: no "
                        "studied radius qualified"),
            "bases": {**data.get("bases", {}), base: {
                **limits,
                "provenance": {"study": "studies/curvature.py", "command": command, "fidelity": fidelity,
                               "seeds": seeds, "lambdas_mm": list(LAMBDAS_MM), "curvatures_mm": list(CURVATURES_MM),
                               "texture_along": "normal", "results": str(results.relative_to(ROOT)),
                               "results_sha256": file_sha256(results), "commit": commit,
                               "written": datetime.now(timezone.utc).isoformat(timespec="seconds")}}}}
    RANGE_PATH.write_text(json.dumps(data, indent=1) + "\n")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fidelity", choices=("coarse", "default"), default="coarse",
                        help="FEM fidelity (default: %(default)s)")
    parser.add_argument("--seeds", type=int, default=3, help="realisations per lambda (default: %(default)s)")
    parser.add_argument("--base", choices=("cylinder", "sphere"), default="cylinder",
                        help="curved base (default: %(default)s)")
    parser.add_argument("--normal-only", action="store_true",
                        help="lay heights along the normal only, skipping the z comparison (default: both)")
    parser.add_argument("--no-range", action="store_true",
                        help="do not record the range in models/curvature_range.json (default: record it)")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error("--seeds must be >= 1")
    OUT.mkdir(parents=True, exist_ok=True)
    along = ("normal",) if args.normal_only else ALONG
    rows = run(args.fidelity, args.seeds, OUT / f"curvature_{args.fidelity}.jsonl", args.base, along)
    diffs = differences(rows, args.fidelity, args.base)
    limits = agreement_range(diffs, TOLERANCE)
    command = (f"python studies/curvature.py --fidelity {args.fidelity} --seeds {args.seeds} --base {args.base}"
               + (" --normal-only" if args.normal_only else ""))
    stem = OUT / "_".join(["curvature"] + ([args.base] if args.base != "cylinder" else [])
                          + ([args.fidelity] if args.fidelity != "coarse" else []))
    summary = {"command": command, "fidelity": args.fidelity, "seeds": args.seeds, "base": args.base,
               "lambdas_mm": list(LAMBDAS_MM), "curvatures_mm": list(CURVATURES_MM), "tolerance": TOLERANCE,
               "limits": limits, "differences": diffs}
    stem.with_suffix(".json").write_text(json.dumps(summary, indent=1) + "\n")
    stem.with_suffix(".md").write_text(_table(diffs, limits, command, args.fidelity, args.seeds, args.base))
    _plot(diffs, stem.with_suffix(".png"), args.fidelity, args.base)
    if not args.no_range:
        _write_range(limits, command, args.fidelity, args.seeds, args.base, stem.with_suffix(".json"))
    print(json.dumps(limits))
    return 0


if __name__ == "__main__":
    sys.exit(main())
