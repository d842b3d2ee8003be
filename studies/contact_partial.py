"""Contact solve before and after issue 16: partial contact (0.1-2 N) and the standard scale at 10 N.

BEFORE is the active-set loop of commit cfb2493 (``--before``; its simulate/contact.py is that of
a653923: a node may change state at most twice, then it is held in contact), loaded from git
under another module name; AFTER is the current
simulate/contact.py (primal-dual active set with a damped step against cycling). Both run in
the same process, each on its own Simulator (own block, AMG hierarchy and base field), on
the same textures, interleaved (before, then after, per case); every state is measured by the same
``check_contact`` (tolerances GAP_TOL_MM and TENSION_TOL of simulate/contact.py). Seconds are
the contact stage only (``stage_seconds["contact"]``), measured on a shared, contended machine:
compare them as ratios within one run.

Part 1, partial contact: a periodic egg-crate texture and random rough fBm surfaces at
0.1, 0.5 and 2 N, stick and frictionless. Part 2: the 13 standard textures at 10 N, stick.
Part 3 (``--p2-criteria``): the P2 contact pressure that decides tension, on small P2 blocks
(4 mm, h 0.6 mm, fBm at 0.02 and 0.1 N): today's modified quadratic basis (simulate/face.py)
against the face-mass recovery M^-1 r of BEFORE's simulate/face.py and the lumped r / area,
all with today's active-set loop.

    python studies/contact_partial.py                        # coarse; writes studies/results/contact_partial.{md,json}
    python studies/contact_partial.py --fidelity coarse default --standard-fidelity coarse default
    python studies/contact_partial.py --fidelity --standard-fidelity coarse --p2-criteria --out /tmp/rerun
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np

ROOT = Path(__file__).parents[1]
OUT = ROOT / "studies" / "results"
BEFORE_COMMIT = "cfb2493"
P2_CRITERIA = ("modified basis", "mass matrix", "lumped")
FORCES_N = (0.1, 0.5, 2.0)
CONTACTS = ("stick", "frictionless")


def egg_crate(period_mm: float = 2.0, amplitude_mm: float = 0.1, size_mm: float = 12.0, pixel_mm: float = 0.05):
    """A periodic texture: h = amplitude (1 + sin(2 pi x / period) sin(2 pi y / period)) (mm)."""
    from roughness.surface.heightmap import Heightmap

    x = (np.arange(round(size_mm / pixel_mm)) + 0.5) * pixel_mm
    k = 2 * np.pi / period_mm
    return Heightmap(amplitude_mm * (1 + np.sin(k * x)[None, :] * np.sin(k * x)[:, None]), pixel_mm)


def partial_textures() -> dict:
    from roughness.dataset.fractal import fbm_surface

    return {"egg-crate 2 mm, 0.2 mm p-v": egg_crate(),
            "fBm H=0.8 rms 0.15 mm seed 0": fbm_surface(seed=0),
            "fBm H=0.8 rms 0.15 mm seed 1": fbm_surface(seed=1)}


def load_before(commit: str = BEFORE_COMMIT, module: str = "contact"):
    """simulate/<module>.py as of ``commit``, imported as roughness.simulate._<module>_before."""
    source = subprocess.run(["git", "-C", str(ROOT), "show", f"{commit}:simulate/{module}.py"],
                            check=True, capture_output=True, text=True).stdout
    name = f"roughness.simulate._{module}_before"
    spec = importlib.util.spec_from_loader(name, loader=None)
    loaded = importlib.util.module_from_spec(spec)
    loaded.__package__ = "roughness.simulate"
    sys.modules[name] = loaded  # dataclasses look their module up while the source runs
    exec(compile(source, f"{commit}:simulate/{module}.py", "exec"), loaded.__dict__)  # noqa: S102 (our own code, from git)
    return loaded


def before_solver(old):
    """The old solve_contact, its result re-expressed as today's ContactResult (measured by check_contact)."""
    from roughness.simulate import contact

    def solve(problem, surface, force_n, frictionless=False, **kwargs):
        r = old.solve_contact(problem, surface, force_n, frictionless, **kwargs)
        check = contact.check_contact(problem, surface, force_n, r.u, r.in_contact, r.normal_reaction)
        return contact.ContactResult(
            u=r.u, indentation_mm=r.indentation_mm, in_contact=r.in_contact, normal_reaction=r.normal_reaction,
            success=r.success, message=r.message, rounds=r.rounds, linear_solves=r.linear_solves,
            cg_iterations=r.cg_iterations, amg_setups=r.amg_setups, unresolved=check.violations, cycled=r.cycled,
            contact_history=r.contact_history, max_penetration_mm=check.max_penetration_mm,
            max_tension_mpa=check.max_tension_mpa, warm=r.warm, check=check)

    return solve


@contextmanager
def algorithm(solver):
    """Run the FEM model with ``solver`` as its contact solve (None: today's)."""
    from roughness.simulate import model

    today = model.solve_contact
    model.solve_contact = solver or today
    try:
        yield
    finally:
        model.solve_contact = today


def row(label: str, r) -> dict:
    """One run's record; ``max_tension_rel``: the largest tension over the mean pressure force / face area."""
    from roughness.simulate.contact import TENSION_TOL

    state = r.state
    check = state.check
    return {"algorithm": label, "rounds": r.iterations, "reported_converged": bool(r.converged),
            "satisfied": check.satisfied, "tension_nodes": check.tension_nodes,
            "penetrating_nodes": check.penetrating_nodes, "mismatched_nodes": check.mismatched_nodes,
            "max_tension_mpa": check.max_tension_mpa,
            "max_tension_rel": check.max_tension_mpa / (check.tension_tol_mpa / TENSION_TOL),
            "tension_fraction": check.tension_fraction, "max_penetration_mm": check.max_penetration_mm,
            "contact_fraction": r.contact_fraction, "V": r.roughness, "indentation_mm": r.indentation_mm,
            "cycled": bool(r.cycled), "damped_rounds": state.damped_rounds, "cg_iterations": r.cg_iterations,
            "seconds": r.stage_seconds["contact"]}


def compare(cases, fidelity: str, solvers: dict, rows: list, part: str, old_face=None) -> None:
    """Run every (name, heightmap, overrides) case with every solver on its own Simulator. With
    ``old_face`` (P2 only) BEFORE also recovers the contact pressure as it did (its simulate/face.py),
    and each case solves one mesh level (no discretization-error estimate)."""
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    element = "p1" if old_face is None else "p2"
    sims = {label: Simulator(SimConfig(fidelity=fidelity, element=element)) for label in solvers}
    if old_face is not None:
        block = sims["before"].block(sims["before"].config.resolved())
        block.problem.face.pressure = old_face.ContactFace(block.mesh, block.mesh.bottom).pressure
    for name, hm, overrides in cases:
        for label, solver in solvers.items():
            with algorithm(solver):
                r = sims[label].run(hm, estimate_error=old_face is None, **overrides)
            rows.append({"part": part, "texture": name, "fidelity": fidelity, "element": element, **overrides,
                         **row(label, r)})
            print(json.dumps(rows[-1]), flush=True)


def p2_criteria(commit: str, rows: list) -> None:
    """Part 3: one P2 block per criterion of the contact pressure, today's loop, the same small fBm cases."""
    from roughness.dataset.fractal import fbm_surface
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator

    old_face = load_before(commit, "face")
    config = SimConfig(h_contact_mm=0.6, width_mm=4.0, window_mm=3.0, pair_distance_mm=0.4, disk_radius_mm=0.4,
                       element="p2", pairs=2000)
    sims = {}
    for criterion in P2_CRITERIA:
        sims[criterion] = sim = Simulator(config)
        block = sim.block(config.resolved())
        if criterion != "modified basis":  # the block's own face is today's
            face = old_face.ContactFace(block.mesh, block.mesh.bottom)
            block.problem.face.pressure = (face.pressure if criterion == "mass matrix"
                                           else lambda r, area=face.area: r / area)
    for seed in (0, 1):
        for force in (0.02, 0.1):
            for mode in CONTACTS:
                for criterion, sim in sims.items():
                    r = sim.run(fbm_surface(seed=seed), force_n=force, contact=mode, estimate_error=False)
                    rows.append({"part": "p2", "texture": f"fBm H=0.8 rms 0.15 mm seed {seed}", "fidelity": "h 0.6 P2",
                                 "force_n": force, "contact": mode, **row(criterion, r)})
                    print(json.dumps(rows[-1]), flush=True)


def markdown(rows: list) -> str:
    from roughness.simulate.contact import GAP_TOL_MM, TENSION_TOL

    legend = (f"Both algorithms' final states are measured by `check_contact`: *satisfied* means no contact node "
              f"under tension beyond {TENSION_TOL:g} x the mean pressure (force / face area), no node deeper than "
              f"{GAP_TOL_MM:g} mm into the texture, no pressure off contact. *reported converged* is what the "
              "algorithm itself said. *tension nodes*: contact nodes under tension beyond the tolerance; "
              "*largest tension / mean p*: the largest tension at a contact node over F / face area; "
              "*tensile force / F*: the force all contact nodes under tension pull with, over F.")
    lines = [legend, ""]
    partial = [r for r in rows if r["part"] == "partial"]
    if partial:
        header = ("| texture | fidelity | force (N) | contact | algorithm | rounds | reported converged | satisfied | "
                  "tension nodes | largest tension / mean p | tensile force / F | largest penetration (mm) | "
                  "contact fraction | seconds |")
        lines += ["## Partial contact (0.1-2 N)", "", header, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in partial:
            lines.append(
                f"| {r['texture']} | {r['fidelity']} | {r['force_n']:g} | {r['contact']} | {r['algorithm']} | "
                f"{r['rounds']} | {r['reported_converged']} | {r['satisfied']} | {r['tension_nodes']} | "
                f"{r['max_tension_rel']:.3g} | {100 * r['tension_fraction']:.2g}% | {r['max_penetration_mm']:.1e} | "
                f"{100 * r['contact_fraction']:.1f}% | {r['seconds']:.2f} |")
        lines += ["", summary_lines(partial), ""]
    standard = [r for r in rows if r["part"] == "standard"]
    if standard:
        header = ("| lambda (mm) | fidelity | V before | V after | V change | rounds before/after | "
                  "satisfied before/after | seconds before/after | time ratio |")
        lines += ["## Standard scale at 10 N (stick)", "", header, "|---|---|---|---|---|---|---|---|---|"]
        for before, after in pairs(standard):
            level = before["fidelity"] + (", P2" if before.get("element") == "p2" else "")
            lines.append(
                f"| {before['texture']} | {level} | {before['V']:.5f} | {after['V']:.5f} | "
                f"{100 * (after['V'] / before['V'] - 1):+.3f}% | {before['rounds']}/{after['rounds']} | "
                f"{before['satisfied']}/{after['satisfied']} | {before['seconds']:.2f}/{after['seconds']:.2f} | "
                f"{after['seconds'] / before['seconds']:.2f} |")
        lines += ["", standard_summary(standard), ""]
    p2 = [r for r in rows if r["part"] == "p2"]
    if p2:
        header = ("| texture | force (N) | contact | P2 pressure | rounds | satisfied | violating nodes | "
                  "largest tension / mean p | largest penetration (mm) | damped rounds | V | seconds |")
        lines += ["## P2 contact pressure criterion (4 mm block, h 0.6 mm, today's loop)", "", header,
                  "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in p2:
            lines.append(
                f"| {r['texture']} | {r['force_n']:g} | {r['contact']} | {r['algorithm']} | {r['rounds']} | "
                f"{r['satisfied']} | {r['tension_nodes'] + r['penetrating_nodes'] + r['mismatched_nodes']} | "
                f"{r['max_tension_rel']:.3g} | {r['max_penetration_mm']:.1e} | {r['damped_rounds']} | "
                f"{r['V']:.5f} | {r['seconds']:.2f} |")
        lines.append("")
        for criterion in P2_CRITERIA:
            sel = [r for r in p2 if r["algorithm"] == criterion]
            lines.append(f"- {criterion}: {sum(r['satisfied'] for r in sel)}/{len(sel)} satisfied; rounds "
                         f"{min(r['rounds'] for r in sel)}-{max(r['rounds'] for r in sel)}; contact seconds in all "
                         f"{sum(r['seconds'] for r in sel):.1f}")
        lines.append("")
    return "\n".join(lines)


def pairs(rows: list) -> list:
    before = [r for r in rows if r["algorithm"] == "before"]
    after = [r for r in rows if r["algorithm"] == "after"]
    return list(zip(before, after))


def summary_lines(rows: list) -> str:
    out = []
    for label in ("before", "after"):
        sel = [r for r in rows if r["algorithm"] == label]
        if not sel:
            continue
        false_ok = sum(r["reported_converged"] and not r["satisfied"] for r in sel)
        out.append(f"- {label}: {sum(r['satisfied'] for r in sel)}/{len(sel)} runs satisfy the conditions; "
                   f"{false_ok} report converged without satisfying them; tension nodes up to "
                   f"{max(r['tension_nodes'] for r in sel)}, tensile force up to "
                   f"{100 * max(r['tension_fraction'] for r in sel):.2g}% of F; rounds "
                   f"{min(r['rounds'] for r in sel)}-{max(r['rounds'] for r in sel)} (median "
                   f"{np.median([r['rounds'] for r in sel]):g}); contact seconds in all "
                   f"{sum(r['seconds'] for r in sel):.1f}")
    return "\n".join(out)


def standard_summary(rows: list) -> str:
    out = []
    for fidelity, element in dict.fromkeys((r["fidelity"], r.get("element", "p1")) for r in rows):
        p = pairs([r for r in rows if r["fidelity"] == fidelity and r.get("element", "p1") == element])
        change = [abs(a["V"] / b["V"] - 1) for b, a in p]
        ratio = sum(a["seconds"] for _, a in p) / sum(b["seconds"] for b, _ in p)
        out.append(f"- {fidelity}{', P2 (one level)' if element == 'p2' else ''}: largest |V change| {100 * max(change):.3f}%; contact time after/before "
                   f"(sum over textures) {ratio:.2f}; satisfied before {sum(b['satisfied'] for b, _ in p)}/{len(p)}, "
                   f"after {sum(a['satisfied'] for _, a in p)}/{len(p)}")
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fidelity", nargs="*", default=["coarse"],
                        help="fidelities of the partial-contact part (none: skip it)")
    parser.add_argument("--standard-fidelity", nargs="*", default=["coarse"],
                        help="fidelities of the 10 N standard-scale part (none: skip it)")
    parser.add_argument("--before", default=BEFORE_COMMIT, help="git commit whose contact solve is BEFORE")
    parser.add_argument("--p2-standard", type=int, default=0,
                        help="also run this many standard textures (spread over the 13) with P2 at coarse, one level")
    parser.add_argument("--p2-criteria", action="store_true", help="run part 3, the P2 contact-pressure criteria")
    parser.add_argument("--out", default=str(OUT / "contact_partial"),
                        help="output path without suffix (.md and .json are written)")
    args = parser.parse_args()
    from roughness.dataset.textures import STANDARD_LAMBDAS_MM, standard_texture

    solvers = {"before": before_solver(load_before(args.before)), "after": None}
    rows: list = []
    t = time.perf_counter()
    textures = partial_textures()
    for fidelity in args.fidelity:
        cases = [(name, hm, {"force_n": f, "contact": c}) for name, hm in textures.items()
                 for c in CONTACTS for f in FORCES_N]
        compare(cases, fidelity, solvers, rows, "partial")
    for fidelity in args.standard_fidelity:
        cases = [(f"{lam:g}", standard_texture(lam, seed=0), {"force_n": 10.0, "contact": "stick"})
                 for lam in STANDARD_LAMBDAS_MM]
        compare(cases, fidelity, solvers, rows, "standard")
    if args.p2_standard > 0:
        picked = np.linspace(0, len(STANDARD_LAMBDAS_MM) - 1, args.p2_standard).round().astype(int)
        cases = [(f"{STANDARD_LAMBDAS_MM[i]:g}", standard_texture(STANDARD_LAMBDAS_MM[i], seed=0),
                  {"force_n": 10.0, "contact": "stick"}) for i in dict.fromkeys(picked)]
        compare(cases, "coarse", solvers, rows, "standard", old_face=load_before(args.before, "face"))
    if args.p2_criteria:
        p2_criteria(args.before, rows)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(rows, indent=1))
    text = markdown(rows)
    out.with_suffix(".md").write_text(f"# Contact solve before ({args.before}) and after issue 16\n\n"
                                      f"Generated by studies/contact_partial.py in {time.perf_counter() - t:.0f} s "
                                      f"(contended 2-core machine; compare seconds as ratios).\n\n{text}")
    print(text)


if __name__ == "__main__":
    main()
