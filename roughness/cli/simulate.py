"""`roughness simulate`: the FEM reference engine on one heightmap."""
from __future__ import annotations

import argparse
import json
import os

from .common import add_heightmap_args, log


def add_parser(sub) -> None:
    from roughness.simulate.config import BONE_MODELS, CONTACT_MODES, ELEMENTS, FIDELITIES

    sim = sub.add_parser("simulate", help="FEM roughness of a heightmap (reference engine)")
    add_heightmap_args(sim)
    sim.add_argument("--fidelity", choices=FIDELITIES, default="default",
                     help="mesh resolution: coarse 0.3 mm, default 0.2 mm, fine 0.14 mm, auto from feature size")
    sim.add_argument("--force", type=float, default=10.0, help="normal force in N (default 10)")
    sim.add_argument("--poisson", type=float, default=0.45, help="tissue Poisson ratio (default 0.45)")
    sim.add_argument("--contact", choices=CONTACT_MODES, default="stick")
    sim.add_argument("--element", choices=ELEMENTS, default="p1", help="p2 for Poisson ratio close to 0.5")
    sim.add_argument("--bone", choices=BONE_MODELS, default="rigid")
    sim.add_argument("--seed", type=int, default=0, help="seed of the disk-pair sampling")
    sim.add_argument("--json", action="store_true", help="print one JSON object")
    sim.add_argument("--save-strain", metavar="PNG", help="image of the strain map at receptor depth")
    sim.add_argument("--save-vtu", metavar="FILE", help="deformed mesh with strain for ParaView")
    sim.add_argument("--quiet", action="store_true", help="no progress messages on stderr")
    sim.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from roughness.simulate.config import SimConfig
    from roughness.simulate.io import load_heightmap
    from roughness.simulate.model import Simulator

    hm = load_heightmap(args.heightmap, pixel_mm=args.pixel_mm, height_mm=args.height_mm)
    config = SimConfig(fidelity=args.fidelity, force_n=args.force, poisson=args.poisson, contact=args.contact,
                       element=args.element, bone=args.bone, seed=args.seed)
    for path in (args.save_strain, args.save_vtu):
        if path and not os.path.isdir(os.path.dirname(os.path.abspath(path))):
            from roughness.core.errors import InputError

            raise InputError(f"cannot write {path}: its folder does not exist")
    log(args, f"{args.heightmap}: {hm.shape[1]} x {hm.shape[0]} px of {hm.pixel_mm} mm; "
               f"{config.resolved(hm).fidelity} fidelity, contact spacing {config.spacing_mm(hm)} mm; "
               "preparing the skin block (cached after the first run) ...")
    sim = Simulator(config)
    result = sim.run(hm, centre_mm=args.centre, tile=args.tile)
    if args.save_strain:
        from roughness.simulate.output import save_strain_png

        save_strain_png(result, args.save_strain)
        log(args, f"strain map written to {args.save_strain}")
    if args.save_vtu:
        from roughness.simulate.output import save_vtu

        save_vtu(result, sim.block(result.config), args.save_vtu)
        log(args, f"deformed mesh written to {args.save_vtu}")
    if args.json:
        print(json.dumps({"input": args.heightmap, **result.summary()}))
    else:
        _print_result(result)
    for w in result.warnings:
        log(args, f"note: {w}")
    return 0


def _print_result(r) -> None:
    print(f"roughness V        {r.roughness:.5f} ± {r.roughness_stderr:.5f} (strain variation at "
          f"{r.config.depth_mm} mm depth, d = r = {r.config.pair_distance_mm} mm)")
    print(f"contact fraction   {100 * r.contact_fraction:.1f}%")
    print(f"indentation        {r.indentation_mm:.3f} mm at {r.config.force_n} N")
    if r.converged:
        status = "converged" + (f"; {r.unresolved_nodes} nodes held in contact under slight tension"
                                if r.unresolved_nodes else "")
    else:
        status = f"NOT converged; {r.unresolved_nodes} nodes unresolved"
    print(f"contact rounds     {r.iterations} ({status})")
    print(f"mesh               {r.nodes} nodes, {r.config.element.upper()}, h = {r.config.h_contact_mm} mm")
    print(f"time               {r.seconds:.2f} s")
