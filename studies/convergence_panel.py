"""Mesh-convergence panel: V of 24 textures at several discretisations, the FEM error estimate
and ``--fidelity converged`` checked against the h = 0.1 mm reference.

Every texture family plus small-feature, sparse-feature, low-relief and multi-scale textures of
our own making. Each (texture, level) result is appended to a JSONL file keyed by the texture's
content and the configuration, so the study resumes after any interruption and never mixes
results of changed inputs. The fine levels are slow (minutes per texture at h = 0.1 mm): run in
the background, one process at a time.

    python studies/convergence_panel.py --levels p1:0.3 p1:0.2 p1:0.14 p1:0.1   # fixed levels, resumable
    python studies/convergence_panel.py --converged [--tolerance 0.03]          # converged vs default, timed
    python studies/convergence_panel.py --table                                 # results/convergence_panel.md
    python studies/convergence_panel.py --list                                  # the panel

``--converged`` times, per texture and in one process with every block warm, a plain ``default``
solve and a ``converged`` run (which includes its coarser levels), so their cost ratio is
measured under the same load. ``--table`` reads only the JSONL.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

OUT = Path(__file__).parent / "results" / "convergence_panel.jsonl"
TABLE = Path(__file__).parent / "results" / "convergence_panel.md"
REFERENCE = ("p1", 0.1)
# SimConfig fields when the panel began: fields added later enter the result key only when they
# differ from their defaults, so adding a field does not invalidate the stored results.
KEY_FIELDS = frozenset({
    "young_mpa", "poisson", "tissue_mm", "width_mm", "bone", "bone_young_mpa", "bone_poisson", "bone_mm",
    "force_n", "contact", "fidelity", "element", "h_contact_mm", "depth_mm", "window_mm", "grid_mm", "pairs",
    "pair_distance_mm", "disk_radius_mm", "seed", "max_rounds"})


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
    from roughness.dataset.families import make

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


def config_key(config) -> str:
    """Digest of a SimConfig for the result key (see KEY_FIELDS)."""
    from roughness import SimConfig
    from roughness.core.hashing import digest

    defaults = asdict(SimConfig())
    return digest({k: v for k, v in config.as_dict().items() if k in KEY_FIELDS or v != defaults[k]})


def _rows(path: Path) -> list[dict]:
    if not path.exists():
        return []
    rows = []
    for line in path.read_text().splitlines():
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError:  # a torn last line: recomputed
            continue
    return rows


def _append(path: Path, row: dict) -> None:
    with open(path, "a") as f:
        f.write(json.dumps(row) + "\n")
        f.flush()
        os.fsync(f.fileno())


def run_levels(textures: dict, names: list[str], levels: list[tuple[str, float]], out: Path) -> None:
    """V of every texture at every fixed level (one solve each, no error estimate)."""
    from roughness import SimConfig, Simulator
    from roughness.core.hashing import array_digest

    done = {(r["texture_digest"], r["config_digest"]) for r in _rows(out)}
    for element, h in levels:
        config = SimConfig(element=element, h_contact_mm=h)
        sim = Simulator(config)
        for name in names:
            hm = textures[name]()
            key = (array_digest(hm.heights, hm.pixel_mm), config_key(config))
            if key in done:
                continue
            start = time.perf_counter()
            r = sim.run(hm, estimate_error=False)
            row = {"texture": name, "texture_digest": key[0], "config_digest": key[1], "element": element,
                   "h_contact_mm": h, "roughness": r.roughness, "roughness_stderr": r.roughness_stderr,
                   "contact_fraction": r.contact_fraction, "converged": bool(r.converged),
                   "iterations": int(r.iterations), "nodes": int(r.nodes), "seconds": time.perf_counter() - start}
            _append(out, row)
            done.add(key)
            print(f"{element} h={h}: {name}: V = {r.roughness:.5f} ({row['seconds']:.0f} s, {r.nodes} nodes)",
                  file=sys.stderr, flush=True)


def run_converged(textures: dict, names: list[str], tolerance: float, out: Path) -> None:
    """Per texture, timed in one warm process: a plain ``default`` solve and a ``converged`` run."""
    from roughness import SimConfig, Simulator
    from roughness.core.hashing import digest
    from roughness.simulate import discretization
    from roughness.simulate.discretization import LADDER_MM

    config = SimConfig(fidelity="converged", tolerance=tolerance)
    # the estimator's constants decide where the ladder stops: they are part of the key
    estimator = {k: getattr(discretization, k) for k in ("ORDER", "SAFETY", "LADDER_MM", "V_FLOOR")}
    key = digest({"config": config_key(config), "estimator": estimator})
    done = {(r["texture_digest"], r["config_digest"]) for r in _rows(out) if r.get("kind") == "converged"}
    todo = [n for n in names if (_digest(textures[n]()), key) not in done]
    if not todo:
        return
    sim = Simulator(config, max_blocks=len(LADDER_MM))
    for h in LADDER_MM:  # prepare every block first: the timings below are warm
        sim.block(replace(config, h_contact_mm=h)).base(config.force_n, config.contact, config.max_rounds)
    for name in todo:
        hm = textures[name]()
        start = time.perf_counter()
        default = sim.run(hm, estimate_error=False, fidelity="default")
        default_seconds = time.perf_counter() - start
        start = time.perf_counter()
        r = sim.run(hm)
        seconds = time.perf_counter() - start
        row = {"kind": "converged", "texture": name, "texture_digest": _digest(hm),
               "config_digest": key, "tolerance": tolerance, "roughness": r.roughness,
               "discretization_error": r.discretization_error, "element": r.config.element,
               "h_contact_mm": r.config.h_contact_mm, "ladder": r.summary()["ladder"],
               "tolerance_met": not any(n.code == "tolerance_not_met" for n in r.notes), "seconds": seconds,
               "default_roughness": default.roughness, "default_seconds": default_seconds,
               "auto_h_contact_mm": SimConfig(fidelity="auto").spacing_mm(hm)}
        _append(out, row)
        print(f"converged {tolerance:g}: {name}: V = {r.roughness:.5f} ± {100 * r.discretization_error:.1f}% at "
              f"h = {r.config.h_contact_mm} ({seconds:.1f} s; default {default_seconds:.1f} s)", file=sys.stderr,
              flush=True)


def _digest(hm) -> str:
    from roughness.core.hashing import array_digest

    return array_digest(hm.heights, hm.pixel_mm)


def _mean(values: list[float]) -> float:
    return sum(values) / len(values) if values else float("nan")


def _median(values: list[float]) -> float:
    return float(np.median(values)) if values else float("nan")


def _pct(x: float | None) -> str:
    return "–" if x is None else f"{100 * x:+.1f}%"


def write_table(rows: list[dict], names: list[str], path: Path) -> None:
    """The panel table (markdown) from the JSONL rows: errors against the h = 0.1 mm P1 reference."""
    from roughness.simulate.discretization import V_FLOOR, richardson

    fixed: dict[str, dict[tuple[str, float], dict]] = {}
    converged: dict[str, dict] = {}
    for r in rows:
        if r.get("kind") == "converged":
            converged[r["texture"]] = r
        else:
            fixed.setdefault(r["texture"], {})[(r["element"], r["h_contact_mm"])] = r
    lines = ["| texture | V ref (P1 h=0.1) | ref's own estimate | coarse | default | fine | auto: h, error | "
             "converged: h, error | default: estimated / actual | converged: estimated / actual | "
             "converged cost / default |", "|" + "---|" * 11]
    stats = {"n": 0, "conv_rel": 0, "conv_tol": 0, "conv_n": 0, "cov_default": 0, "cov_fine": 0, "cov_conv": 0,
             "cov_conv_n": 0, "cost": [], "seconds": [], "default_seconds": [], "auto_agree": 0, "auto_finer": 0, "auto_within": 0,
             "ref_unconverged": []}
    tol = None
    for name in names:
        levels = fixed.get(name, {})
        if REFERENCE not in levels:
            continue
        v = {h: levels[("p1", h)]["roughness"] for (e, h) in levels if e == "p1"}
        ref = v[0.1]
        err = {h: (v[h] - ref) / ref for h in v}
        stats["n"] += 1
        ref_est = richardson(ref, v[0.14], 0.1, 0.14) if 0.14 in v else None
        if ref_est is not None and ref_est > 0.03:
            stats["ref_unconverged"].append(name)
        est_default = richardson(v[0.2], v[0.3], 0.2, 0.3) if 0.3 in v and 0.2 in v else None
        est_fine = richardson(v[0.14], v[0.2], 0.14, 0.2) if 0.2 in v and 0.14 in v else None
        if est_default is not None:
            stats["cov_default"] += abs(err[0.2]) * abs(ref) <= est_default * abs(v[0.2])
        if est_fine is not None:
            stats["cov_fine"] += abs(err[0.14]) * abs(ref) <= est_fine * abs(v[0.14])
        c = converged.get(name)
        auto = conv = est_conv = cost = "–"
        if c is not None:
            tol = c["tolerance"]
            stats["conv_n"] += 1
            e = (c["roughness"] - ref) / ref
            stats["conv_rel"] += abs(e) <= tol
            stats["conv_tol"] += abs(c["roughness"] - ref) <= tol * max(abs(ref), V_FLOOR)
            conv = f"{c['h_contact_mm']:g}{'' if c['tolerance_met'] else ' (not met)'}, {_pct(e)}"
            if c["h_contact_mm"] != REFERENCE[1]:
                stats["cov_conv_n"] += 1
                stats["cov_conv"] += abs(c["roughness"] - ref) <= c["discretization_error"] * abs(c["roughness"])
                est_conv = f"{100 * c['discretization_error']:.1f}% / {100 * abs(c['roughness'] - ref) / abs(c['roughness']):.1f}%"
            else:
                est_conv = f"{100 * c['discretization_error']:.1f}% / (is the reference)"
            cost_ratio = c["seconds"] / c["default_seconds"]
            stats["cost"].append(cost_ratio)
            stats["seconds"].append(c["seconds"])
            stats["default_seconds"].append(c["default_seconds"])
            cost = f"{cost_ratio:.2f}"
            a = c["auto_h_contact_mm"]
            stats["auto_agree"] += a == c["h_contact_mm"]
            stats["auto_finer"] += a < c["h_contact_mm"]
            stats["auto_within"] += a in v and abs(v[a] - ref) <= tol * max(abs(ref), V_FLOOR)
            auto = f"{a:g}, {_pct(err.get(a))}"
        est_def = ("–" if est_default is None else
                   f"{100 * est_default:.1f}% / {100 * abs(v[0.2] - ref) / abs(v[0.2]):.1f}%")
        lines.append(f"| {name} | {ref:.5f} | {'–' if ref_est is None else f'{100 * ref_est:.1f}%'} | "
                     f"{_pct(err.get(0.3))} | {_pct(err.get(0.2))} | {_pct(err.get(0.14))} | {auto} | {conv} | "
                     f"{est_def} | {est_conv} | {cost} |")
    n, cn = stats["n"], stats["conv_n"]
    mean_cost = sum(stats["cost"]) / len(stats["cost"]) if stats["cost"] else float("nan")
    summary = [
        "# Convergence panel: V against the P1 h = 0.1 mm reference",
        "",
        "Regenerate: `python studies/convergence_panel.py --levels p1:0.3 p1:0.2 p1:0.14 p1:0.1`, then "
        "`--converged`, then `--table` (resumable; results in convergence_panel.jsonl).",
        "Errors are signed, relative to the reference. Estimated errors are the two-level Richardson estimates "
        "of simulate/discretization.py (default: from h = 0.3 and 0.2 mm; converged: from its last two levels); "
        "the interval V (1 ± estimate) contains the reference when estimated >= actual. "
        f"'ref's own estimate' is the same estimate for the reference (from h = 0.14 and 0.1 mm): above 3% "
        "the reference itself is not converged, and only the absolute criterion |V - ref| <= tolerance x "
        f"max(V, {V_FLOOR}) is meaningful (these textures have V far below the standard scale).",
        "Cost: wall time of a converged run (all its levels) over a plain default solve of the same texture, "
        "both warm, measured one after the other in one process on a 2-core machine (otherwise idle for the rows of 2026-11-22).",
        "",
        f"- textures: {n}; converged runs: {cn} (tolerance {tol})",
        f"- converged within {tol} (relative) of the reference: {stats['conv_rel']}/{cn}; within "
        f"tolerance x max(V, {V_FLOOR}): {stats['conv_tol']}/{cn}",
        f"- references whose own estimate exceeds 3%: {len(stats['ref_unconverged'])} "
        f"({', '.join(stats['ref_unconverged']) or 'none'})",
        f"- estimate's interval contains the reference: default {stats['cov_default']}/{n}, fine "
        f"{stats['cov_fine']}/{n}, converged {stats['cov_conv']}/{stats['cov_conv_n']} (those not at the reference level)",
        f"- converged cost / default: {sum(stats['seconds']) / max(sum(stats['default_seconds']), 1e-9):.2f} "
        f"(mean seconds per texture: {_mean(stats['seconds']):.1f} converged, {_mean(stats['default_seconds']):.1f} "
        f"default); per texture: median {_median(stats['cost']):.2f}, mean {mean_cost:.2f}, "
        f"max {max(stats['cost'], default=float('nan')):.2f}",
        f"- auto picks the level converged reached: {stats['auto_agree']}/{cn} (finer: {stats['auto_finer']}); "
        f"auto within tolerance x max(V, {V_FLOOR}) of the reference: {stats['auto_within']}/{cn}",
        "",
    ]
    path.write_text("\n".join(summary + lines) + "\n")
    print(f"wrote {path}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--levels", nargs="+", type=_level, metavar="pN:H",
                        help="fixed levels to run: element order and contact spacing in mm (e.g. p1:0.2 p1:0.1)")
    parser.add_argument("--converged", action="store_true", help="run fidelity converged (and default, timed)")
    parser.add_argument("--tolerance", type=float, default=0.03, help="--converged: tolerance (default 0.03)")
    parser.add_argument("--table", action="store_true", help=f"write the table {TABLE.name} from the JSONL")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="a subset of the panel")
    parser.add_argument("--out", type=Path, default=OUT, help=f"JSONL results (default {OUT})")
    parser.add_argument("--list", action="store_true", help="list the panel and exit")
    args = parser.parse_args(argv)
    textures = panel()
    if args.list:
        print("\n".join(textures))
        return 0
    names = args.only or list(textures)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    if args.levels:
        run_levels(textures, names, args.levels, args.out)
    if args.converged:
        run_converged(textures, names, args.tolerance, args.out)
    if args.table:
        write_table(_rows(args.out), list(textures), args.out.with_suffix(".md"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
