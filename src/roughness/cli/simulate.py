"""`roughness simulate`: the FEM reference engine on one heightmap."""
from __future__ import annotations

import argparse
import math
import sys
from typing import TYPE_CHECKING

from roughness.core.limits import MAX_RADIUS_MM

from . import common
from .common import (
    FORCE,
    FRACTION,
    POISSON,
    SEED,
    Number,
    add_heightmap_args,
    json_text,
    load_input,
    log,
    readings,
)

if TYPE_CHECKING:
    from roughness.prediction import CurvedBase

SIGNED_RADIUS = Number(float, -MAX_RADIUS_MM, MAX_RADIUS_MM)  # a signed radius in mm; 0 is refused by SimConfig


def add_parser(sub) -> None:
    from roughness.simulate.config import CHOICES, FIDELITY_SPACING_MM, SimConfig

    d = SimConfig()
    spacing = ", ".join(f"{k} {v} mm" for k, v in FIDELITY_SPACING_MM.items())
    sim = sub.add_parser("simulate", help="FEM roughness of a heightmap (reference engine)")
    add_heightmap_args(sim)
    sim.add_argument("--fidelity", choices=CHOICES["fidelity"], default=d.fidelity,
                     help=f"contact-mesh spacing: {spacing}, auto from the feature size, converged: refined until "
                          "the estimated discretization error of V is below --tolerance (default: %(default)s)")
    sim.add_argument("--tolerance", type=FRACTION, default=d.tolerance,
                     help="--fidelity converged: target relative discretization error of V (default: %(default)s)")
    sim.add_argument("--force", type=FORCE, default=d.force_n, help="normal force in N (default: %(default)s)")
    sim.add_argument("--poisson", type=POISSON, default=d.poisson, help="tissue Poisson ratio (default: %(default)s)")
    sim.add_argument("--contact", choices=CHOICES["contact"], default=d.contact,
                     help="skin-texture contact: stick (no slip) or frictionless (default: %(default)s)")
    sim.add_argument("--element", choices=CHOICES["element"], default=d.element,
                     help="tetrahedra: p1 linear, p2 quadratic (for Poisson ratio close to 0.5) (default: %(default)s)")
    sim.add_argument("--bone", choices=CHOICES["bone"], default=d.bone,
                     help=f"bone under the tissue: rigid, or elastic {d.bone_mm} mm layer (default: %(default)s)")
    add_curvature_args(sim)
    sim.add_argument("--detrend", type=_detrend_spec, metavar="lowpass[:CUTOFF_MM]",
                     help="separate the texture from the object's shape in a scan of a curved object: a spectral "
                          "low-pass of the map (wavelengths above CUTOFF_MM; default: chosen from the map's texture) "
                          "is removed before simulating (default: off)")
    sim.add_argument("--seed", type=SEED, default=d.seed, help="seed of the disk-pair sampling of V (default: %(default)s)")
    sim.add_argument("--json", action="store_true",
                     help="print one JSON object: V, contact, solver counts and `notes` (default: a table)")
    sim.add_argument("--save-strain", metavar="PNG", help="image of the strain map at receptor depth (default: none)")
    sim.add_argument("--save-vtu", metavar="FILE", help="deformed mesh with strain for ParaView (default: none)")
    common.add_overwrite(sim)
    common.add_quiet(sim)
    common.finish(sim, run, force_n="--force")


def add_curvature_args(p: argparse.ArgumentParser) -> None:
    """The curved base under the texture (``SimConfig.curvature_mm`` and its companions)."""
    from roughness.simulate.config import CHOICES, SimConfig

    d = SimConfig()
    p.add_argument("--curvature-mm", type=SIGNED_RADIUS, metavar="R",
                   help="the texture lies on a curved base of radius R mm: R > 0 convex toward the finger, "
                        "R < 0 concave (default: flat)")
    p.add_argument("--base", choices=CHOICES["base"], default=d.base,
                   help="--curvature-mm: the base's shape, a cylinder or a spherical cap (default: %(default)s)")
    p.add_argument("--curvature-axis", choices=CHOICES["curvature_axis"], default=d.curvature_axis,
                   help="--curvature-mm with a cylinder: the direction the cylinder is straight along; it curves "
                        "across it (default: %(default)s)")
    p.add_argument("--texture-along", choices=CHOICES["texture_along"], default=d.texture_along,
                   help="--curvature-mm: lay the heights off along the base normal (a textured object) or along z "
                        "(a height map draped vertically) (default: %(default)s)")


def curvature_fields(args: argparse.Namespace) -> dict:
    """The SimConfig fields of the curvature options."""
    return {"curvature_mm": args.curvature_mm, "base": args.base, "curvature_axis": args.curvature_axis,
            "texture_along": args.texture_along}


def curved_base(args: argparse.Namespace) -> CurvedBase | None:
    """The curvature options as ``predict``'s ``CurvedBase`` (None: a flat base)."""
    from roughness.prediction import CurvedBase

    if args.curvature_mm is None:
        return None
    return CurvedBase(args.curvature_mm, args.base, args.curvature_axis, args.texture_along)


def _detrend_spec(text: str):
    from roughness.core.errors import InputError
    from roughness.surface.detrend import parse_detrend

    try:
        return parse_detrend(text)
    except InputError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def run(args: argparse.Namespace) -> int:
    from roughness.core.files import check_distinct, check_output
    from roughness.core.provenance import make_provenance
    from roughness.simulate import prepared
    from roughness.simulate.config import SimConfig

    check_distinct({"--save-strain": args.save_strain, "--save-vtu": args.save_vtu}, {"HEIGHTMAP": args.heightmap})
    for name in ("save_strain", "save_vtu"):
        if getattr(args, name):
            check_output(getattr(args, name), args.overwrite, name)
    hm = load_input(args, args.heightmap)
    config = SimConfig(fidelity=args.fidelity, force_n=args.force, poisson=args.poisson, contact=args.contact,
                       element=args.element, bone=args.bone, seed=args.seed,
                       tolerance=args.tolerance, **curvature_fields(args))
    if args.detrend:
        from roughness.surface.detrend import detrend

        hm, removed = detrend(hm, args.detrend)
        log(args, f"detrended: {removed.describe()}")
    hm.require_footprint(config.width_mm, args.centre, args.tile)  # a bad --centre, before the skin block is made
    log(args, f"{args.heightmap}: {hm.shape[1]} x {hm.shape[0]} px of {hm.pixel_mm} mm; "
              f"{config.fidelity} fidelity, contact spacing {config.spacing_mm(hm)} mm, "
              f"{config.base_shape().describe()}; "
              "preparing the skin block (cached after the first run) ...")
    result = prepared.simulate(config, hm, args.centre, args.tile)
    if args.save_strain:
        from roughness.simulate.output import save_strain_png

        save_strain_png(result, args.save_strain, args.overwrite)
        log(args, f"strain map written to {args.save_strain}")
    if args.save_vtu:
        from roughness.simulate.output import save_vtu

        save_vtu(result, prepared.SHARED.block(result.config), args.save_vtu, args.overwrite)
        log(args, f"deformed mesh written to {args.save_vtu}")
    if args.json:
        provenance = make_provenance("fem", config.fidelity, config.identity())
        print(json_text({"input": args.heightmap, **result.summary(), "readings": readings(args),
                         "provenance": provenance.as_dict()}))
    else:
        _print_result(result)
    for note in result.unusual_notes:
        log(args, f"note: {note.message}")
    if not result.converged:
        print(contact_warning(result), file=sys.stderr, flush=True)
    return 0


def contact_warning(r) -> str:
    """One line on what is left of the contact conditions of an unconverged result (shown even with --quiet)."""
    c = r.contact_check
    return (f"warning: contact NOT converged after {r.iterations} rounds: {c.violations} nodes violate contact "
            f"({c.tension_nodes} held under tension, largest {c.max_tension_mpa:.2e} MPa, tensile force "
            f"{100 * c.tension_fraction:.2g}% of the {r.config.force_n:g} N load; {c.penetrating_nodes} penetrating, "
            f"largest {c.max_penetration_mm:.2e} mm); V is not reliable")


def _print_result(r) -> None:
    error = r.discretization_error
    discretization = (f"± {error * abs(r.roughness):.5f} (discretization, {100 * error:.1f}%)" if math.isfinite(error)
                      else "(discretization error undefined: V is 0 at this mesh but not at the coarser one)")
    print(f"roughness V        {r.roughness:.5f} ± {r.roughness_stderr:.5f} (Monte Carlo) {discretization}")
    print(f"                   strain variation at {r.config.depth_mm} mm depth, d = r = {r.config.pair_distance_mm} mm")
    print(f"contact fraction   {100 * r.contact_fraction:.1f}%")
    print(f"indentation        {r.indentation_mm:.3f} mm at {r.config.force_n} N")
    if r.converged:
        c = r.contact_check
        status = (f"converged: no penetration beyond {c.gap_tol_mm:g} mm, no tension beyond "
                  f"{c.tension_tol_mpa:.1e} MPa")
    else:
        status = f"NOT converged; {r.unresolved_nodes} nodes violate contact"
    print(f"contact rounds     {r.iterations} ({status})")
    print(f"mesh               {r.nodes} nodes, {r.config.element.upper()}, h = {r.config.h_contact_mm} mm ({_level(r)})")
    print(f"time               {r.seconds:.2f} s")


def _level(r) -> str:
    """The fidelity, and the levels solved for the error estimate."""
    solved = ", ".join(f"{level.h_contact_mm:g}" for level in r.ladder)
    reached = "level reached by converged" if r.config.fidelity == "converged" else f"fidelity {r.config.fidelity}"
    return f"{reached}; error estimated from h = {solved} mm"
