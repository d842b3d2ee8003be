"""`roughness object feel MESH [--texture FILE|NAME]`: how each part of the textured object feels (a roughness map
over its surface, curvature included), per region, with a picture. Without --texture the mesh is judged as it is
(textured elsewhere): its own relief over its smoothed base (roughness.objects.relief)."""
from __future__ import annotations

import argparse
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from .common import (
    LENGTH,
    add_overwrite,
    add_quiet,
    add_reading_args,
    finish,
    json_text,
    log,
    readings,
    show_notes,
)
from .object_inputs import MAPPING_FLAGS, add_mesh_and_texture_args, check_mapping_args, mapping_for, read_texture
from .printer import add_printer_arg, printer_of

if TYPE_CHECKING:
    import trimesh

    from roughness.surface.heightmap import Heightmap


def add_object_args(p: argparse.ArgumentParser, texture_help: str | None = None) -> None:
    """The textured object: the mesh, the texture, its mapping (as object texture's) and the regions (shared by feel
    and tune; ``texture_help``: --texture is optional, as ``add_mesh_and_texture_args``)."""
    add_mesh_and_texture_args(p, "the object, untextured (or, without --texture, textured as it is): STL, OBJ, OFF, "
                                 "PLY, 3MF, GLB or glTF (mm unless the file states units; glTF is metres; a largest "
                                 "extent outside 2 mm to 1 m is refused unless --units-ok)", texture_help)
    p.add_argument("--region", action="append", metavar="SPEC",
                   help="faces to texture, repeatable (each a row of the table): all, cone:AX,AY,AZ,DEG (normals within "
                        "DEG of the axis), box:X0,Y0,Z0,X1,Y1,Z1 (mm), colour:R,G,B[,TOL] (painted) (default: all)")
    p.add_argument("--spacing-mm", type=LENGTH, metavar="MM",
                   help="distance between evaluation points (default: 5, half the 10 mm footprint; object feel widens "
                        "it on a large part to fit its budget of footprints, and says so)")
    p.add_argument("--engine", choices=("spectral", "surrogate"), default="spectral",
                   help="the flat engine judging the texture under each footprint (default: spectral)")
    add_reading_args(p)


@dataclass
class ObjectInputs:
    """What the object commands read: the mesh, the texture, the regions (name -> face mask) and notes."""

    mesh: trimesh.Trimesh
    texture: Heightmap | None  # None: the mesh's own relief is judged
    texture_name: str | None
    regions: dict
    notes: list[str] = field(default_factory=list)
    base: object = None  # without a texture: the base's samples, if a cone region needed them (SurfaceSamples)

    @property
    def textured(self):
        import numpy as np

        return np.logical_or.reduce(list(self.regions.values()))


def read_object(args: argparse.Namespace) -> ObjectInputs:
    """The mesh, texture and regions the options name (errors name their flags)."""
    from roughness.objects.meshes import read_mesh
    from roughness.objects.regions import parse_region

    check_mapping_args(args)
    read = read_mesh(args.mesh, units_ok=args.units_ok)
    texture, texture_notes = read_texture(args) if args.texture is not None else (None, [])
    regions = {}
    parsed = [(text, parse_region(text)) for text in args.region or ["all"]]
    by_normal, base = read.mesh, None
    if texture is None and any(region.kind == "cone" for _, region in parsed):  # by the base's normals, not the relief's
        from roughness.objects.feel_budget import feel_budget
        from roughness.objects.relief import BaseFaces, base_samples

        spacing = feel_budget(float(read.mesh.area), float(read.mesh.area), relief=True).sample_spacing_mm
        base = base_samples(read.mesh, spacing)
        by_normal = BaseFaces.of(read.mesh, base)
    for text, region in parsed:
        mask = region.faces(by_normal if region.kind == "cone" else read.mesh)
        if not mask.any():
            from roughness.core.errors import InputError

            raise InputError(f"region {text!r} selects no face of the mesh", parameter="region")
        regions[text] = mask
    return ObjectInputs(read.mesh, texture, args.texture, regions, [*read.notes, *texture_notes], base)


def mapping_of(args: argparse.Namespace, texture, inputs: ObjectInputs):
    """The mapping the options name for ``texture`` on the textured faces (a wrap's axis and radius fitted to them
    unless given)."""
    return mapping_for(args, texture, inputs.mesh, inputs.textured)


RELIEF_FLAGS = ("--mapping", "--axis", "--radius-mm", "--blend-deg", "--uv-mm", "--seed", "--pixel-mm", "--height-mm",
                "--printer")
"""Options that apply to a texture given by --texture only."""


def add_parser(sub) -> None:
    p = sub.add_parser("feel", help="how each part of a textured object feels: a roughness map over its surface "
                                    "(curvature included), per-region table and picture; without --texture, the "
                                    "mesh as it is (textured elsewhere)")
    add_object_args(p, "without it, the mesh is judged as it is (textured elsewhere: Blender, a texturing tool, a "
                       "slicer's bake): its own relief over its surface smoothed at 1 mm, the base's curvature "
                       "included")
    p.add_argument("--curved", choices=("correction", "fem"), default="correction",
                   help="where curvature matters: the curvature study's measured correction, or the curved FEM "
                        "(seconds per point; cylinders and spheres only) (default: correction)")
    p.add_argument("--reference", metavar="NAME",
                   help="count JNDs from this texture (a name, e.g. standard-1.0, judged flat by the same engine)")
    p.add_argument("--colour-by", choices=("roughness", "jnd"),
                   help="--picture: colour by V or by JND from --reference (default: jnd with --reference, else V)")
    p.add_argument("--picture", metavar="PNG", help="write a picture of the object coloured by how it feels")
    p.add_argument("--json", action="store_true", help="one JSON object: table, refusals, every point (default: text)")
    add_printer_arg(p, "the map is of the printed object (the texture tile printed before it is mapped), the "
                       "digital object's table beside it")
    add_quiet(p)
    add_overwrite(p)
    finish(p, run, regions="--region", spacing_mm="--spacing-mm", curved="--curved", **MAPPING_FLAGS)


def run(args: argparse.Namespace) -> int:
    from roughness.core.errors import InputError
    from roughness.core.figures import save_figure
    from roughness.core.files import check_distinct, check_output
    from roughness.objects.feel import feel_map
    from roughness.objects.feel_figure import feel_figure

    if args.colour_by == "jnd" and not args.reference:
        raise InputError("colouring by JND needs --reference", parameter="colour_by")
    if args.picture:
        check_distinct({"--picture": args.picture}, {"MESH": args.mesh, "--texture": args.texture, "--printer": args.printer})
        check_output(args.picture, args.overwrite, "picture")
    if args.texture is None:
        _check_relief_args(args)
    printer = printer_of(args)
    inputs = read_object(args)
    mapping = None if inputs.texture is None else mapping_of(args, inputs.texture, inputs)
    notes = inputs.notes + list(getattr(mapping, "notes", lambda: [])())
    show_notes(args, notes)
    printing = _printed(args, inputs, mapping, printer) if printer is not None else None

    def progress(done: int, total: int) -> None:
        log(args, f"feel: {done}/{total} footprints judged" + (" (as printed)" if printing else ""))

    if printing is not None:
        mapping = mapping_of(args, printing.result.heightmap, inputs)
    feel = feel_map(inputs.mesh, mapping, inputs.regions, args.spacing_mm, args.engine, args.curved, args.reference,
                    inputs.base, progress)
    show_notes(args, list(feel.notes))
    if args.picture:
        by = args.colour_by or ("jnd" if args.reference else "roughness")
        save_figure(feel_figure(inputs.mesh, feel, inputs.textured, by, Path(args.mesh).name), args.picture, 120,
                    args.overwrite)
    if args.json:
        print(json_text({"mesh": args.mesh, "texture": inputs.texture_name,
                         "mapping": args.mapping if mapping is not None else None, "notes": [*notes, *feel.notes],
                         "picture": args.picture, "readings": readings(args), **feel.as_dict(),
                         "printing": None if printing is None else printing.as_dict(feel)}))
    else:
        print("\n".join(map_lines(feel, args.mesh, printing, args.picture)))
    return 0


@dataclass(frozen=True)
class PrintedFeel:
    """--printer: the tile's print (``result``, a ``PrintResult``) and the map of the digital object (``digital``,
    a ``FeelMap``), to set beside the printed object's."""

    result: object
    digital: object

    def lines(self, printed) -> list[str]:
        """Each region's median V as printed beside digital (uncertainty: the map's median ± V), and the print's
        steps."""
        name = self.result.profile.name
        out = [f"printer {self.result.profile.describe()}; each region's median V as printed beside digital:"]
        for p, d in zip(printed.table(), self.digital.table()):
            out.append(f"  {p.name}: as printed ({name}) {_median(p)}; digital {_median(d)}{_jnd_change(p, d)}")
        return [*out, *(f"print: {step}" for step in self.result.steps),
                *(f"print note: {note}" for note in self.result.notes)]

    def as_dict(self, printed) -> dict:
        return {**self.result.as_dict(), "digital_regions": [row.as_dict() for row in self.digital.table()],
                "printed_regions": [row.as_dict() for row in printed.table()]}


def _printed(args: argparse.Namespace, inputs: ObjectInputs, mapping, printer) -> PrintedFeel:
    """The tile printed at its pixel on the surface, and the digital object's map (judged first, logged)."""
    from roughness.objects.feel import feel_map
    from roughness.objects.printed import printed_tile

    result = printed_tile(inputs.texture, printer, mapping.pixel_mm)
    log(args, f"feel: the digital object first, then as printed by {printer.name}")
    digital = feel_map(inputs.mesh, mapping, inputs.regions, args.spacing_mm, args.engine, args.curved,
                       args.reference)
    return PrintedFeel(result, digital)


def _check_relief_args(args: argparse.Namespace) -> None:
    """InputError for an option of a --texture given without one (the mesh's own relief is judged)."""
    from roughness.core.errors import InputError
    from roughness.objects.mapping import DEFAULT_BLEND_DEG

    defaults = {"mapping": "triplanar", "seed": 0, "blend_deg": DEFAULT_BLEND_DEG}
    for flag in RELIEF_FLAGS:
        name = flag[2:].replace("-", "_")
        value = getattr(args, name, None)
        if value is not None and value != defaults.get(name):
            raise InputError(f"{flag} applies to a texture given by --texture; without --texture the mesh's own "
                             "relief is judged", parameter="texture")


def _median(row) -> str:
    """A region's median V ± its median uncertainty, or that none was judged."""
    if row.roughness_median is None:
        return "no point judged"
    return f"V {row.roughness_median:.4f} ± {row.uncertainty_median:.4f}"


def _jnd_change(printed, digital) -> str:
    """The printed region's median against the digital's, in JND of equivalent wavelength (empty if undefined)."""
    from roughness.perceptual_scale import jnd

    if printed.lambda_median_mm is None or digital.lambda_median_mm is None:
        return ""
    return f" ({jnd(printed.lambda_median_mm, digital.lambda_median_mm):+.2f} JND)"


def map_lines(feel, mesh: str, printing: PrintedFeel | None = None, picture: str | None = None) -> list[str]:
    """``feel_lines``; with ``printing`` the map said to be of the printed object, each region's median V beside the
    digital object's and the print's steps after it."""
    lines = feel_lines(feel, mesh, picture)
    if printing is None:
        return lines
    return [f"as printed ({printing.result.profile.name}): {lines[0]}", *lines[1:], *printing.lines(feel)]


def feel_lines(feel, mesh: str, picture: str | None = None) -> list[str]:
    """The map in words: a summary, the per-region table and each reason for refusing."""
    ref = feel.reference
    head = (f"{mesh}: {len(feel.points)} footprints {feel.spacing_mm:g} mm apart, {feel.engine} engine, curvature by "
            f"{feel.curved}; {feel.method.count('flat')} flat, {feel.method.count('corrected')} corrected, "
            f"{feel.method.count('fem')} curved FEM, {feel.method.count('refused')} refused; {feel.seconds:.1f} s")
    lines = [head, f"{'region':<28} {'area mm2':>9} {'points':>6} {'refused':>7} {'V median':>9} {'V range':>17} "
                   f"{'± V':>7} {'lambda mm':>9}" + (f" {'JND from ' + ref.name:>22}" if ref else "")]
    for row in feel.table():
        if row.roughness_median is None:
            values = f"{'-':>9} {'-':>17} {'-':>7} {'-':>9}" + (f" {'-':>22}" if ref else "")
        else:
            lam = "below" if row.lambda_median_mm is None else f"{row.lambda_median_mm:.3f}"
            jnd = f"{'<= ' if row.jnd_is_bound else ''}{row.jnd_median:+.2f}" if ref else ""
            values = (f"{row.roughness_median:>9.4f} {row.roughness_min:>8.4f}..{row.roughness_max:<7.4f} "
                      f"{row.uncertainty_median:>7.4f} {lam:>9}" + (f" {jnd:>22}" if ref else ""))
        lines.append(f"{row.name[:28]:<28} {row.area_mm2:>9.0f} {row.points:>6} {100 * row.refused_fraction:>6.0f}% "
                     + values)
    if any(row.below_scale_fraction for row in feel.table()):
        lines.append(f"below: the region's judged points are all below the standard scale (V < {feel.scale.floor:.4f}),"
                     " too smooth for an equivalent lambda; '<=': most are, counted at the floor, so the JND is a bound")
    if ref:
        lines.append(f"reference {ref.name}: V {ref.roughness:.4f} flat, lambda {ref.lambda_mm:.3f} mm")
    lines += [f"refused at {n} point(s): {why}" for why, n in feel.refusals().items()]
    if picture:
        lines.append(f"picture written to {picture}")
    return lines
