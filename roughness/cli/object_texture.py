"""`roughness object texture MESH --texture FILE|NAME --out OUT`: put a texture on a 3D model (STL, OBJ, PLY, 3MF)."""
from __future__ import annotations

import argparse

from .common import (
    POSITIVE,
    SEED,
    Number,
    add_overwrite,
    add_quiet,
    add_reading_args,
    finish,
    json_text,
    load_input,
    log,
    readings,
    write_stdout,
)


def add_parser(actions) -> None:
    from roughness.objects.layout import MAPPINGS
    from roughness.objects.mapping import BLEND_RANGE_DEG, DEFAULT_BLEND_DEG
    from roughness.objects.texturing import DEFAULT_BORDER_MM, DEFAULT_NORMAL_RADIUS_MM
    p = actions.add_parser("texture", help="put a texture on a mesh: remesh the textured faces to the texture's pixel, "
                                           "displace them, write a watertight STL or 3MF")
    p.add_argument("mesh", metavar="MESH", help="the object: .stl, .obj, .ply or .3mf (mm unless the file states units)")
    p.add_argument("--texture", required=True, metavar="FILE|NAME",
                   help="heightmap file (as for predict) or a named texture (standard-<lambda>, flattop-<d>: see "
                        "roughness texture list); it is tiled periodically, its lowest point on the surface")
    p.add_argument("--seed", type=SEED, default=0, help="seed of a named texture (default 0)")
    p.add_argument("--mapping", choices=MAPPINGS, default="triplanar",
                   help="how the texture lies on the surface: triplanar projection (any shape), cylinder or sphere "
                        "wrap with a whole number of tiles around, or the mesh's own UVs (default: triplanar)")
    p.add_argument("--axis", metavar="PX,PY,PZ,DX,DY,DZ",
                   help="cylinder: its axis (a point and a direction, mm); sphere: its centre and polar axis "
                        "(default: fitted to the textured faces)")
    p.add_argument("--radius-mm", type=POSITIVE, metavar="MM",
                   help="cylinder/sphere: the radius to fit whole tiles around (default: fitted)")
    p.add_argument("--blend-deg", type=Number(float, *BLEND_RANGE_DEG), default=DEFAULT_BLEND_DEG, metavar="DEG",
                   help=f"width (degrees of the normal) over which two projections are blended at a seam "
                        f"(default {DEFAULT_BLEND_DEG:g})")
    p.add_argument("--uv-mm", type=POSITIVE, metavar="MM",
                   help="uv: mm per UV unit (default: the texture at its own size on average)")
    p.add_argument("--region", default="all", metavar="REGION",
                   help="faces to texture: all, cone:AX,AY,AZ,DEG (normal within DEG of the axis), "
                        "box:X0,Y0,Z0,X1,Y1,Z1 (centre in the box, mm), colour:R,G,B[,TOL] (painted vertex or face "
                        "colours, 0-255) (default: all)")
    p.add_argument("--edge-mm", type=POSITIVE, metavar="MM",
                   help="longest edge of a textured triangle (default: sqrt(2) x the texture's pixel on the surface)")
    p.add_argument("--normal-radius-mm", type=Number(float, low=0), default=DEFAULT_NORMAL_RADIUS_MM, metavar="MM",
                   help="smooth the displacement's normals over about this radius (default 0: area-weighted vertex "
                        "normals)")
    p.add_argument("--border-mm", type=Number(float, low=0), default=DEFAULT_BORDER_MM, metavar="MM",
                   help="the heights ramp from 0 on the region's border to full height over this distance, so the "
                        f"border and the faces beside it keep their shape (0: no ramp) (default {DEFAULT_BORDER_MM:g})")
    p.add_argument("--no-intersection-check", action="store_true",
                   help="skip the test for faces crossing each other (the slowest step on large meshes; reported)")
    p.add_argument("--out", required=True, metavar="FILE", help="the textured mesh: .stl (binary) or .3mf")
    p.add_argument("--preview", metavar="PNG", help="also write a picture of the textured object")
    p.add_argument("--json", action="store_true", help="one JSON object (default: text)")
    add_reading_args(p)
    add_quiet(p)
    add_overwrite(p)
    finish(p, run, edge_mm="--edge-mm", mesh="MESH", texture="--texture", region="--region", mapping="--mapping",
           axis="--axis", blend_deg="--blend-deg", radius_mm="--radius-mm", uv_mm="--uv-mm", origin="--axis")


def run(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct, check_output
    from roughness.objects.layout import make_mapping
    from roughness.objects.mapping import axis_of
    from roughness.objects.meshes import WRITE_SUFFIXES, read_mesh, write_mesh
    from roughness.objects.regions import parse_region
    from roughness.objects.texturing import texture_mesh

    check_distinct({"--out": args.out, "--preview": args.preview}, {"MESH": args.mesh, "--texture": args.texture})
    out = check_output(args.out, args.overwrite, "out")
    if out.suffix.lower() not in WRITE_SUFFIXES:
        raise InputError(f"cannot write {out}: unsupported mesh format {out.suffix or '(no suffix)'!r}; supported: "
                         f"{', '.join(WRITE_SUFFIXES)}", "out")
    preview = check_output(args.preview, args.overwrite, "preview") if args.preview else None
    if preview is not None and preview.suffix.lower() != ".png":
        raise InputError(f"the preview is a PNG picture, got {preview.name}", "preview")
    region = parse_region(args.region)
    axis = _axis(args.axis, axis_of) if args.axis else None
    if args.mapping in ("triplanar", "uv") and (axis is not None or args.radius_mm is not None):
        raise InputError("--axis and --radius-mm apply to the cylinder and sphere mappings only", "axis")
    if args.mapping != "uv" and args.uv_mm is not None:
        raise InputError("applies to the uv mapping only", "uv_mm")
    texture, texture_notes = _texture(args)
    read = read_mesh(args.mesh)
    mapping = make_mapping(args.mapping, texture, read.mesh, region.faces(read.mesh), axis, args.radius_mm,
                           args.blend_deg, args.uv_mm)
    log(args, f"object texture: {read.triangles:,} triangles in {args.mesh}; texturing")
    result = texture_mesh(read.mesh, mapping, region, args.edge_mm, args.normal_radius_mm,
                          check_intersections=not args.no_intersection_check, progress=lambda line: log(args, line),
                          border_mm=args.border_mm)
    written = write_mesh(result.mesh, out, args.overwrite)
    if preview is not None:
        from roughness.core.figures import save_figure
        from roughness.objects.preview import preview_figure

        save_figure(preview_figure(result, f"{args.mesh} with {args.texture}"), preview, dpi=100,
                    overwrite=args.overwrite)
    notes = [*read.notes, *texture_notes, *result.notes]
    if args.json:
        write_stdout(json_text({"mesh": args.mesh, "texture": args.texture, "mapping": args.mapping,
                                "region": region.describe(), "out": written.path, "triangles": written.triangles,
                                "bytes": written.bytes, "preview": None if preview is None else str(preview),
                                "result": result.as_dict(), "notes": notes, "readings": readings(args)}))
    else:
        lines = [written.line(),
                 f"textured {result.textured_faces_in:,} of {result.triangles_in:,} faces "
                 f"({result.textured_area_mm2:.1f} mm^2); heights up to {result.max_height_mm:.3f} mm, mean "
                 f"{result.mean_height_mm:.3f} mm; volume {result.volume_in_mm3:.1f} -> {result.volume_out_mm3:.1f} mm^3",
                 *(f"note: {n}" for n in notes)]
        if preview is not None:
            lines.append(f"wrote {preview}")
        write_stdout("\n".join(lines))
    return 0


def _axis(text: str, axis_of):
    from roughness.core.errors import InputError

    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 6:
        raise InputError(f"expected PX,PY,PZ,DX,DY,DZ (six numbers), got {text!r}", "axis")
    return axis_of(values[:3], values[3:])


def _texture(args: argparse.Namespace):
    """The texture heightmap (a file, else a named texture) and notes on what was done to it."""
    from pathlib import Path

    from roughness.core.errors import InputError
    from roughness.dataset.textures import named_texture, texture_names
    from roughness.surface.heightmap import Heightmap

    text = args.texture
    path = text.split(":", 1)[0] if ":" in text and not Path(text).exists() else text
    if Path(path).exists() or text not in texture_names():
        if not Path(path).exists():
            raise InputError(f"{text!r} is neither a file nor a named texture ({', '.join(texture_names())})",
                             "texture")
        hm = load_input(args, text)
        notes = []
    else:
        if args.pixel_mm is not None:
            raise InputError("applies to a texture file; a named texture has its own pixel", "pixel_mm")
        hm = named_texture(text, args.seed)
        notes = [f"texture {text} (seed {args.seed}): {hm.size_mm[0]:g} mm tile, pixel {hm.pixel_mm:g} mm, relief "
                 f"{hm.heights.max() - hm.heights.min():.3g} mm"]
        if args.height_mm is not None:
            relief = float(hm.heights.max() - hm.heights.min())
            if relief > 0:
                hm = Heightmap((hm.heights - hm.heights.min()) * (args.height_mm / relief), hm.pixel_mm)
                notes.append(f"texture {text}: heights scaled by {args.height_mm / relief:.4g} to a relief of "
                             f"{args.height_mm:g} mm (--height-mm)")
    low = float(hm.heights.min())
    notes.append(f"texture {text}: tiled periodically, its lowest point laid on the surface"
                 + (f" (heights shifted by {-low:+.4g} mm)" if low != 0 else ""))
    return hm, notes
