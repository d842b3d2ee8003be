"""FEM cost growth: seconds and peak memory of each stage against the number of DOFs.

Each contact spacing h (from coarse 0.3 mm down to 0.1 mm) runs in a fresh process with an
empty mesh cache and times, one after another: mesh generation, stiffness assembly, the
solver set-up (the AMG hierarchy for the flat block), the strain sampler, and for one
standard texture (lambda 1 mm, seed 0, default force) after the flat block's solve: the
contact solve and the strain recovery. Peak memory per stage is the largest memory traced
by Python's tracemalloc during the stage (numpy arrays and Python objects; compiled
libraries' scratch space is not traced), beside the process's RSS high-water mark at its
end. The exponent p of seconds ~ DOFs^p is a least-squares fit in log-log.

    python benchmarks/fem_scaling.py                 # writes benchmarks/results/fem_scaling.{md,json,png}
    python benchmarks/fem_scaling.py --spacings 0.3 0.2 --threads 1

On a shared machine the absolute seconds are contended; the note (``--note``) says so.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

OUT = Path(__file__).parent / "results"
SPACINGS = (0.3, 0.25, 0.2, 0.17, 0.14, 0.12, 0.1)
STAGES = ("mesh", "assembly", "solver_setup", "sampler", "contact", "strain")


def one_spacing(h: float) -> dict:
    """Every stage of one block with contact spacing ``h`` (mm), in this process."""
    import numpy as np

    from roughness.dataset.textures import standard_texture
    from roughness.simulate import mesh as meshing
    from roughness.simulate.config import SimConfig
    from roughness.simulate.contact import ContactProblem, solve_contact
    from roughness.simulate.elasticity import rigid_body_modes, stiffness
    from roughness.simulate.face import ContactFace
    from roughness.simulate.linsolve import AMGCache, constrain
    from roughness.simulate.model import texture_surface
    from roughness.simulate.strain import StrainSampler

    config = SimConfig(h_contact_mm=h).resolved()
    spec = config.block_spec()
    stages: dict[str, dict] = {}
    tracemalloc.start()

    def stage(name: str, fn):
        tracemalloc.reset_peak()
        t = time.perf_counter()
        out = fn()
        stages[name] = {"seconds": time.perf_counter() - t, "peak_mb": tracemalloc.get_traced_memory()[1] / 2**20,
                        "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
        return out

    mesh = stage("mesh", lambda: meshing.build(spec.mesh, cache=False))
    bone = mesh.region == meshing.BONE
    young = np.where(bone, spec.bone_young_mpa, spec.young_mpa)
    poisson = np.where(bone, spec.bone_poisson, spec.poisson)
    k = stage("assembly", lambda: stiffness(mesh, young, poisson).tocsr())
    bottom = mesh.bottom
    problem = ContactProblem(stiffness=k, amg=AMGCache(rigid_body_modes(mesh.points)), bottom=bottom,
                             bottom_xy=mesh.points[bottom, :2], top=mesh.top, n_dofs=3 * len(mesh.points),
                             face=ContactFace(mesh, bottom))
    everywhere = problem.constraints(np.ones(len(bottom), dtype=bool), frictionless=False)
    stage("solver_setup", lambda: constrain(k, everywhere, problem.amg, problem.rtol))
    sampler = stage("sampler", lambda: StrainSampler(mesh, spec.depth_mm, spec.window_mm, spec.grid_mm))
    flat = solve_contact(problem, lambda x, y: np.zeros_like(x), config.force_n)  # the base field, as Block.base
    texture = standard_texture(1.0, seed=0)
    centre = texture.centre_mm
    z0 = texture.max_in_footprint(config.width_mm, centre, periodic=False)
    surface = texture_surface(texture, centre, z0, False)
    initial = surface(*problem.bottom_xy.T) >= -flat.indentation_mm
    state = stage("contact", lambda: solve_contact(problem, surface, config.force_n, initial=initial, warm=flat.warm))
    stage("strain", lambda: sampler.max_compression(state.u))
    return {"h_contact_mm": h, "nodes": len(mesh.points), "dofs": 3 * len(mesh.points), "tets": len(mesh.tets),
            "stiffness_nnz": int(k.nnz), "contact_rounds": state.rounds, "cg_iterations": state.cg_iterations,
            "amg_setups_in_contact": state.amg_setups, "stages": stages}


def fit_exponent(dofs: list[int], seconds: list[float]) -> float:
    """Least-squares slope of log(seconds) against log(DOFs)."""
    import numpy as np

    return float(np.polyfit(np.log(dofs), np.log(seconds), 1)[0])


def plot(rows: list[dict], exponents: dict[str, float]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dofs = [r["dofs"] for r in rows]
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for name in STAGES:
        ax_t.loglog(dofs, [r["stages"][name]["seconds"] for r in rows], "o-", label=f"{name} (p = {exponents[name]:.2f})")
        ax_m.loglog(dofs, [r["stages"][name]["peak_mb"] for r in rows], "o-", label=name)
    ax_m.loglog(dofs, [r["stages"]["strain"]["rss_mb"] for r in rows], "k--", label="process RSS high-water")
    ax_t.set(xlabel="DOFs", ylabel="seconds", title="time per stage (seconds ~ DOFs^p)")
    ax_m.set(xlabel="DOFs", ylabel="MB", title="peak traced memory per stage")
    for ax in (ax_t, ax_m):
        ax.legend(fontsize=7)
        ax.grid(True, which="both", alpha=0.3)
    fig.savefig(OUT / "fem_scaling.png", dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--one", type=float, metavar="H", help="internal: measure one spacing in this process, print JSON")
    parser.add_argument("--spacings", type=float, nargs="+", default=list(SPACINGS), metavar="H",
                        help=f"contact spacings in mm (default: {' '.join(map(str, SPACINGS))})")
    parser.add_argument("--threads", type=int, default=2, help="OMP_NUM_THREADS of the measured processes (default 2)")
    parser.add_argument("--note", default="", help="a sentence on the machine's state, written above the table")
    args = parser.parse_args()
    if args.one is not None:
        print(json.dumps(one_spacing(args.one)))
        return
    OUT.mkdir(exist_ok=True)
    rows = []
    for h in sorted(args.spacings, reverse=True):
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "ROUGHNESS_CACHE": cache, "OMP_NUM_THREADS": str(args.threads)}
            out = subprocess.run([sys.executable, __file__, "--one", str(h)], env=env, check=True,
                                 capture_output=True, text=True).stdout
        rows.append(json.loads(out.strip().splitlines()[-1]))
        print(json.dumps(rows[-1]), flush=True)
    dofs = [r["dofs"] for r in rows]
    exponents = {name: fit_exponent(dofs, [r["stages"][name]["seconds"] for r in rows]) for name in STAGES}
    (OUT / "fem_scaling.json").write_text(json.dumps({"threads": args.threads, "note": args.note, "rows": rows,
                                                     "exponents": exponents}, indent=1))
    header = " | ".join(f"{name} (s / MB)" for name in STAGES)
    lines = ([args.note, ""] if args.note else []) + [
        (f"OMP_NUM_THREADS={args.threads}; each spacing in a fresh process with an empty mesh cache. Time and peak "
        "traced memory (tracemalloc) per stage; contact and strain for one standard texture (lambda 1 mm)."), "",
        f"| h (mm) | nodes | DOFs | {header} | contact rounds | RSS high-water (MB) |",
        "|" + "---|" * (len(STAGES) + 5)]
    for r in rows:
        cells = " | ".join(f"{r['stages'][n]['seconds']:.2f} / {r['stages'][n]['peak_mb']:.0f}" for n in STAGES)
        lines.append(f"| {r['h_contact_mm']} | {r['nodes']} | {r['dofs']} | {cells} | {r['contact_rounds']} "
                     f"| {r['stages']['strain']['rss_mb']:.0f} |")
    lines += ["", "Fitted exponent p (seconds ~ DOFs^p): "
              + ", ".join(f"{name} {p:.2f}" for name, p in exponents.items()) + "."]
    (OUT / "fem_scaling.md").write_text("\n".join(lines) + "\n")
    plot(rows, exponents)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
