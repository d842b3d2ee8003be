"""`roughness object texture MESH --texture FILE|NAME --out OUT`: put a texture on a 3D model (STL, OBJ, PLY, 3MF)."""
from __future__ import annotations

import argparse
import sys

from roughness.core.limits import MAX_LENGTH_MM

from .common import (
    LENGTH,
    Number,
    add_overwrite,
    add_quiet,
    add_reading_args,
    finish,
    json_text,
    log,
    readings,
    write_stdout,
)
from .object_inputs import MAPPING_FLAGS, add_mesh_and_texture_args, check_mapping_args, mapping_for, read_texture
from .printer import add_printer_arg, printer_of


def add_parser(actions) -> None:
    from roughness.objects.sharp_edges import DEFAULT_SHARP_DEG
    from roughness.objects.texturing import DEFAULT_BORDER_MM, DEFAULT_MIN_FACE_MM, DEFAULT_NORMAL_RADIUS_MM

    p = actions.add_parser("texture", help="put a texture on a mesh: remesh the textured faces to the texture's pixel, "
                                           "displace them, write a watertight STL or 3MF")
    add_mesh_and_texture_args(p, "the object: .stl, .obj, .ply or .3mf (mm unless the file states units; a largest extent "
                                 "outside 2 mm to 1 m is refused unless --units-ok)")
    p.add_argument("--region", default="all", metavar="REGION",
                   help="faces to texture: all, cone:AX,AY,AZ,DEG (normal within DEG of the axis), "
                        "angle:AX,AY,AZ,MIN,MAX (normal MIN to MAX degrees from the direction: 0,0,1,45,135 the walls, "
                        "0,0,1,0,170 all but the bottom), box:X0,Y0,Z0,X1,Y1,Z1 (centre in the box, mm), "
                        "colour:R,G,B[,TOL] (painted vertex or face colours, 0-255), faces:FILE (a text file of face "
                        "numbers from 0 and ranges A-B) (default: all)")
    p.add_argument("--sharp-deg", type=Number(float, low=0, high=180, low_open=True), default=DEFAULT_SHARP_DEG, metavar="DEG",
                   help="edges where the faces' normals turn by more than this are sharp: the texture ramps to 0 at "
                        "them, as at the region's border (40: above the 30 degrees between the facets of a coarsely "
                        "exported fillet, below a 45-degree chamfer; 180: no edge is sharp) "
                        f"(default {DEFAULT_SHARP_DEG:g})")
    p.add_argument("--min-face-mm", type=Number(float, low=0, high=MAX_LENGTH_MM), default=DEFAULT_MIN_FACE_MM,
                   metavar="MM",
                   help="faces between sharp edges narrower than this (twice the area over the perimeter) are left "
                        "untextured: engraving, small holes (0: none) "
                        f"(default {DEFAULT_MIN_FACE_MM:g})")
    p.add_argument("--edge-mm", type=LENGTH, metavar="MM",
                   help="longest edge of a textured triangle (default: with --printer, the larger of half the FDM "
                        "line width or the SLA pixel and sqrt(2) x the texture's pixel on the surface; without, "
                        "sqrt(2) x the texture's pixel on the surface)")
    p.add_argument("--normal-radius-mm", type=Number(float, low=0, high=MAX_LENGTH_MM), default=DEFAULT_NORMAL_RADIUS_MM, metavar="MM",
                   help="smooth the displacement's normals over about this radius (default 0: area-weighted vertex "
                        "normals)")
    p.add_argument("--border-mm", type=Number(float, low=0, high=MAX_LENGTH_MM), default=DEFAULT_BORDER_MM, metavar="MM",
                   help="the heights ramp from 0 on the region's border to full height over this distance, so the "
                        f"border and the faces beside it keep their shape (0: no ramp) (default {DEFAULT_BORDER_MM:g})")
    p.add_argument("--decimate-mm", type=Number(float, low=0, high=MAX_LENGTH_MM, low_open=True), metavar="MM",
                   help="decimate the textured mesh to the fewest triangles whose surface is measured within MM of "
                        "the full one (two-sided, e.g. 0.005: well under a print's resolution), checked closed and not "
                        "crossing itself; reports triangles and sizes before and after and the change of V (default: "
                        "not decimated)")
    p.add_argument("--no-feel-check", action="store_true",
                   help="with --decimate-mm: do not compare V of the decimated and the full mesh (minutes on a large "
                        "part; reported as not checked)")
    p.add_argument("--no-intersection-check", action="store_true",
                   help="skip the test for faces crossing each other (the slowest step on large meshes; reported)")
    p.add_argument("--out", required=True, metavar="FILE", help="the textured mesh: .stl (binary) or .3mf")
    p.add_argument("--preview", metavar="PNG", help="also write a picture of the textured object")
    p.add_argument("--json", action="store_true", help="one JSON object (default: text)")
    add_printer_arg(p, "sets the default --edge-mm from what the printer reproduces, and reports the texture's V "
                       "as printed beside its digital V (the mesh written is the digital design)")
    add_reading_args(p)
    add_quiet(p)
    add_overwrite(p)
    finish(p, run, edge_mm="--edge-mm", region="--region", sharp_deg="--sharp-deg", min_face_mm="--min-face-mm",
           decimate_mm="--decimate-mm",
           **MAPPING_FLAGS)


def run(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct, check_output
    from roughness.objects.meshes import read_mesh, require_mesh_format, write_mesh
    from roughness.objects.progress import StageMeter
    from roughness.objects.regions import parse_region
    from roughness.objects.texturing import texture_mesh

    from .object_printing import texture_print

    check_distinct({"--out": args.out, "--preview": args.preview}, {"MESH": args.mesh, "--texture": args.texture, "--printer": args.printer})
    out = require_mesh_format(check_output(args.out, args.overwrite, "out"), "out")
    preview = check_output(args.preview, args.overwrite, "preview") if args.preview else None
    if preview is not None and preview.suffix.lower() != ".png":
        raise InputError(f"the preview is a PNG picture, got {preview.name}", "preview")
    region = parse_region(args.region)
    check_mapping_args(args)
    printer = printer_of(args)
    texture, texture_notes = read_texture(args)
    read = read_mesh(args.mesh, units_ok=args.units_ok)
    mapping = mapping_for(args, texture, read.mesh, region.faces(read.mesh))
    printing = texture_print(texture, printer, mapping.pixel_mm) if printer is not None else None
    for line in printing.lines() if printing else []:
        log(args, line)
    edge_mm, plan, plan_notes = _plan(args, read.mesh, region, mapping, printer)
    log(args, f"object texture: {read.triangles:,} triangles in {args.mesh}")
    for note in plan_notes:
        if note == plan.warning():
            print(f"roughness: warning: {note}", file=sys.stderr, flush=True)  # even with --quiet
        else:
            log(args, f"  {note}")
    log(args, "object texture: texturing")
    meter = StageMeter("  ")

    def step_done(line: str) -> None:
        meter.close()
        log(args, line)

    stage = None if args.quiet else meter.stage
    result = texture_mesh(read.mesh, mapping, region, edge_mm, args.normal_radius_mm,
                          check_intersections=not args.no_intersection_check, progress=step_done,
                          border_mm=args.border_mm, meter=stage, sharp_deg=args.sharp_deg,
                          min_face_mm=args.min_face_mm, decimate_mm=args.decimate_mm)
    change = _feel_change(args, result, meter)
    written = write_mesh(result.mesh, out, args.overwrite, progress=stage and stage(f"writing {out.name}"))
    meter.close()
    if preview is not None:
        from roughness.core.figures import save_figure
        from roughness.objects.preview import preview_figure

        save_figure(preview_figure(result, f"{args.mesh} with {args.texture}",
                                   progress=stage and stage(f"preview {preview.name}")), preview, dpi=100,
                    overwrite=args.overwrite)
        meter.close()
    notes = [*read.notes, *texture_notes, *plan_notes, *result.notes]
    if args.json:
        write_stdout(json_text({"mesh": args.mesh, "texture": args.texture, "mapping": args.mapping,
                                "region": region.describe(), "out": written.path, "triangles": written.triangles,
                                "bytes": written.bytes, "check": written.check.as_dict(), "preview": None if preview is None else str(preview),
                                "plan": plan.as_dict(),
                                "printing": None if printing is None else printing.as_dict(),
                                "result": result.as_dict(), "full": _full(result),
                                "feel_change": None if change is None else change.as_dict(),
                                "notes": notes, "readings": readings(args)}))
    else:
        lines = [written.line(), *_decimation_lines(result, change),
                 f"textured {result.textured_faces_in:,} of {result.triangles_in:,} faces "
                 f"({result.textured_area_mm2:.1f} mm^2); heights up to {result.max_height_mm:.3f} mm, mean "
                 f"{result.mean_height_mm:.3f} mm; volume {result.volume_in_mm3:.1f} -> {result.volume_out_mm3:.1f} mm^3",
                 *(printing.lines() if printing else []),
                 *(f"note: {n}" for n in notes)]
        if preview is not None:
            lines.append(f"wrote {preview}")
        write_stdout("\n".join(lines))
    return 0


def _feel_change(args: argparse.Namespace, result, meter):
    """V of the decimated against the full mesh (``objects.feel_change``), or None if not decimated or not asked."""
    if result.decimation is None or args.no_feel_check:
        return None
    from roughness.objects.feel_change import feel_change

    log(args, "object texture: V of the decimated mesh against the full one")
    stage = None if args.quiet else meter.stage("feel, both meshes")
    change = feel_change(result.full_mesh, result.mesh, progress=stage and (lambda done, total: stage(done / total)))
    meter.close()
    return change


def _full(result) -> dict | None:
    """The full (undecimated) mesh's triangles and binary STL size, if the mesh written was decimated."""
    from roughness.objects.meshes import stl_bytes

    if result.decimation is None:
        return None
    return {"triangles": result.triangles_out, "stl_bytes": stl_bytes(result.triangles_out)}


def _decimation_lines(result, change) -> list[str]:
    """What decimating did: the full mesh's size, the measured distance, the change of V (or that it was not checked)."""
    from roughness.objects.meshes import stl_bytes

    if result.decimation is None:
        return []
    return [f"before decimating: {result.triangles_out:,} triangles, {stl_bytes(result.triangles_out) / 1e6:.1f} MB "
            "as binary STL", result.decimation.line(),
            change.line() if change is not None else "feel: V of the decimated mesh NOT compared (--no-feel-check)"]


def _plan(args: argparse.Namespace, mesh, region, mapping, printer):
    """The edge length (mm: --edge-mm, else from --printer, else sqrt(2) x the texture's pixel on the surface), the
    ``MeshPlan`` of refining to it, and notes: the plan, then the slicer warning if the mesh would be too large."""
    import numpy as np

    from roughness.objects.print_plan import chosen_edge, mesh_plan, require_within

    edge_mm, rule = chosen_edge(args.edge_mm, printer, mapping.pixel_mm)
    notes = [rule] if rule else []
    selected = np.asarray(region.faces(mesh), dtype=bool)
    vertices, faces = np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces)
    plan = mesh_plan(vertices, faces, selected, edge_mm, not args.no_intersection_check)
    require_within(plan, vertices, faces, selected, not args.no_intersection_check)
    notes.append(plan.line())
    if plan.warning():
        notes.append(plan.warning())
    return edge_mm, plan, notes
