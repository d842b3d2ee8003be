"""What every `roughness object` action reads alike: the mesh, the texture (a file or a named texture) and the
mapping that lays it on the surface, with the same options and checks in each action."""
from __future__ import annotations

import argparse

from .common import LENGTH, SEED, Number, load_input

# Python names of the mapping's parameters -> the flags that give them (for error messages)
MAPPING_FLAGS = {"mesh": "MESH", "texture": "--texture", "mapping": "--mapping", "axis": "--axis",
                 "origin": "--axis", "radius_mm": "--radius-mm", "blend_deg": "--blend-deg", "uv_mm": "--uv-mm"}


def add_mesh_and_texture_args(p: argparse.ArgumentParser, mesh_help: str, texture_help: str | None = None) -> None:
    """MESH, --texture, --seed and the mapping's options (--mapping, --axis, --radius-mm, --blend-deg, --uv-mm).
    ``texture_help``: --texture is optional, and this says what leaving it out does."""
    from roughness.objects.layout import MAPPINGS
    from roughness.objects.mapping import BLEND_RANGE_DEG, DEFAULT_BLEND_DEG

    p.add_argument("mesh", metavar="MESH", help=mesh_help)
    p.add_argument("--texture", required=texture_help is None, metavar="FILE|NAME",
                   help="heightmap file (as for predict) or a named texture (standard-<lambda>, flattop-<d>: see "
                        "roughness texture list); it is tiled periodically, its lowest point on the surface"
                        + (f"; {texture_help}" if texture_help else ""))
    p.add_argument("--seed", type=SEED, default=0, help="seed of a named texture (default 0)")
    p.add_argument("--mapping", choices=MAPPINGS, default="triplanar",
                   help="how the texture lies on the surface: triplanar projection (any shape), cylinder or sphere "
                        "wrap with a whole number of tiles around (knobs, handles), or the mesh's own UVs "
                        "(default: triplanar)")
    p.add_argument("--axis", metavar="PX,PY,PZ,DX,DY,DZ",
                   help="cylinder: its axis (a point and a direction, mm); sphere: its centre and polar axis "
                        "(default: fitted to the textured faces)")
    p.add_argument("--radius-mm", type=LENGTH, metavar="MM",
                   help="cylinder/sphere: the radius to fit whole tiles around (default: fitted)")
    p.add_argument("--blend-deg", type=Number(float, *BLEND_RANGE_DEG), default=DEFAULT_BLEND_DEG, metavar="DEG",
                   help=f"width (degrees of the normal) over which two projections are blended at a seam "
                        f"(default {DEFAULT_BLEND_DEG:g})")
    p.add_argument("--uv-mm", type=LENGTH, metavar="MM",
                   help="uv: mm per UV unit (default: the texture at its own size on average)")


def check_mapping_args(args: argparse.Namespace) -> None:
    """InputError for mapping options that do not apply to the chosen mapping (before anything is read)."""
    from roughness.core.errors import InputError

    if args.mapping in ("triplanar", "uv") and (args.axis is not None or args.radius_mm is not None):
        raise InputError("--axis and --radius-mm apply to the cylinder and sphere mappings only", "axis")
    if args.mapping != "uv" and args.uv_mm is not None:
        raise InputError("applies to the uv mapping only", "uv_mm")
    if args.axis is not None:
        parse_axis(args.axis)


def mapping_for(args: argparse.Namespace, texture, mesh, faces):
    """The mapping the options name, for ``texture`` on the ``faces`` (mask) of ``mesh`` (a wrap's axis and radius
    fitted to those faces unless given)."""
    from roughness.objects.layout import make_mapping

    axis = parse_axis(args.axis) if args.axis else None
    return make_mapping(args.mapping, texture, mesh, faces, axis, args.radius_mm, args.blend_deg, args.uv_mm)


def parse_axis(text: str):
    """--axis PX,PY,PZ,DX,DY,DZ as an ``Axis``."""
    from roughness.core.errors import InputError
    from roughness.objects.mapping import axis_of

    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 6:
        raise InputError(f"expected PX,PY,PZ,DX,DY,DZ (six numbers), got {text!r}", "axis")
    return axis_of(values[:3], values[3:])


def read_texture(args: argparse.Namespace):
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
