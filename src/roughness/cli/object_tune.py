"""`roughness object tune MESH --texture FILE|NAME --target-lambda L | --jnd N --reference NAME --out TEXTURE`: scale
a texture so that it feels as wanted on the object's curved parts."""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from .common import (
    FACTOR,
    JND,
    WAVELENGTH,
    Number,
    add_overwrite,
    add_quiet,
    finish,
    json_text,
    log,
    readings,
    show_notes,
)
from .object_feel import ObjectInputs, add_object_args, feel_lines, mapping_of, read_object
from .object_inputs import MAPPING_FLAGS
from .printer import add_printer_arg, printer_of

if TYPE_CHECKING:
    from roughness.objects.tuning import ObjectTuneResult


def add_parser(sub) -> None:
    from roughness.design.tune import FACTOR_RANGE, KNOBS, MAX_RELATIVE_JND
    from roughness.objects.tuning import TOLERANCE_JND

    p = sub.add_parser("tune", help="scale a texture so that the object's curved parts feel like the target "
                                    "(not only the flat texture); reports both")
    add_object_args(p)
    target = p.add_mutually_exclusive_group(required=True)
    target.add_argument("--target-lambda", type=WAVELENGTH, metavar="MM",
                        help="target equivalent wavelength on the standard scale (mm)")
    target.add_argument("--jnd", type=Number(float, low=-MAX_RELATIVE_JND, high=MAX_RELATIVE_JND), metavar="N",
                        help="N JNDs rougher than --reference (negative: smoother)")
    p.add_argument("--reference", metavar="NAME", help="--jnd: the texture the JNDs count from (e.g. standard-1.0)")
    p.add_argument("--by", choices=KNOBS, default="height",
                   help="scale the heights or the lateral size (default: height)")
    ranges = ", ".join(f"{k} {lo:g}..{hi:g}" for k, (lo, hi) in FACTOR_RANGE.items())
    p.add_argument("--min-factor", type=FACTOR, help=f"smallest scale factor searched (default: {ranges})")
    p.add_argument("--max-factor", type=FACTOR, help="largest scale factor searched (default: see --min-factor)")
    p.add_argument("--tolerance-jnd", type=JND, default=TOLERANCE_JND,
                   help=f"stop when the curved parts are this close to the target, in JND (default {TOLERANCE_JND:g})")
    p.add_argument("--out", required=True, metavar="FILE",
                   help="the tuned texture: .npz, .npy, .h5 (mm), .png (16-bit), .tif")
    p.add_argument("--mesh-out", metavar="FILE", help="also the textured object with the tuned texture: .stl or .3mf")
    p.add_argument("--json", action="store_true", help="one JSON object (default: text)")
    add_printer_arg(p, "curvature and printer are corrected in one tune: the tuned texture is judged as printed on "
                       "the curved object; --out and --mesh-out are the digital design, whose own feel is reported "
                       "beside")
    add_quiet(p)
    add_overwrite(p)
    finish(p, run, regions="--region", spacing_mm="--spacing-mm", target_lambda="--target-lambda",
           min_factor="--min-factor", **MAPPING_FLAGS)


@dataclass(frozen=True)
class _Target:
    """The object's target: an equivalent wavelength (mm) and how it was given, in words."""

    lambda_mm: float
    text: str


@dataclass
class _LastMapping:
    """Lays textures on the object (``mapping_of``), keeping the last mapping laid (the tuned texture's)."""

    args: argparse.Namespace
    inputs: ObjectInputs
    last: object = None

    def __call__(self, texture):
        self.last = mapping_of(self.args, texture, self.inputs)
        return self.last


def run(args: argparse.Namespace) -> int:
    """Check the options, tune the texture on the object, write it (and the textured mesh), report."""
    from roughness.objects.feel_budget import DEFAULT_SPACING_MM
    from roughness.objects.tuning import tune_on_object
    from roughness.surface.io import save_heightmap

    _check_options(args)
    out = _checked_out(args)
    mesh_region = _union_region(args) if args.mesh_out else None
    _check_factor_range(args)
    printer = printer_of(args)
    inputs = read_object(args)
    target = _target(args)
    mappings = _LastMapping(args, inputs)
    show_notes(args, inputs.notes)
    result = tune_on_object(inputs.mesh, inputs.texture, mappings, target.lambda_mm, inputs.regions, args.by,
                            args.spacing_mm or DEFAULT_SPACING_MM, args.tolerance_jnd,
                            progress=lambda message: log(args, message), printer=printer, **_factor_options(args))
    show_notes(args, list(getattr(mappings.last, "notes", lambda: [])()))
    digital = mapping_of(args, result.heightmap, inputs)  # the design as written (mappings.last: its print's)
    beside = _digital_on_object(args, inputs, digital, target) if printer is not None else None
    textured = _textured(args, inputs, digital, mesh_region)  # before anything is written
    save_heightmap(result.heightmap, out, overwrite=args.overwrite)
    written = _write_mesh(args, textured)
    if args.json:
        summary = _summary(args, inputs, target, result)
        if printer is not None:
            summary["printing"] = {"printer": printer.as_dict(), "on_object_as": f"printed ({printer.name})",
                                   "digital_on_object": {**beside[0].__dict__, "uncertainty_median": beside[1]}}
        print(json_text(summary))
        return 0
    lines = _text_lines(args, target, result, written)
    if printer is not None:
        lines = _printed_lines(lines, printer, beside)
    print("\n".join(lines))
    return 0


def _digital_on_object(args: argparse.Namespace, inputs: ObjectInputs, mapping, target: _Target):
    """The tuned digital texture's ``ObjectResult`` on the object (the map of the design as written, not printed) and
    the median uncertainty (V) of its judged footprints."""
    import numpy as np

    from roughness.objects.feel import feel_map
    from roughness.objects.feel_budget import DEFAULT_SPACING_MM
    from roughness.objects.tuning import object_result

    log(args, "the tuned texture on the object as designed (digital), for comparison")
    feel = feel_map(inputs.mesh, mapping, inputs.regions, args.spacing_mm or DEFAULT_SPACING_MM, "spectral")
    judged = np.isfinite(feel.uncertainty)
    return object_result(feel, target.lambda_mm), float(np.median(feel.uncertainty[judged]))


def _printed_lines(lines: list[str], printer, beside) -> list[str]:
    """``_text_lines`` with the object's line said to be as printed, the digital design's beside it."""
    digital, uncertainty = beside
    out = []
    for line in lines:
        if line.startswith("on the object ("):
            line = line.replace("on the object (", f"on the object as printed ({printer.name}) (", 1)
            out.append(line)
            out.append(f"  digital (the design as written, unprinted): median V {digital.roughness:.4f} (± "
                       f"{uncertainty:.4f} per footprint, median) over {digital.points} footprints, lambda "
                       f"{digital.lambda_mm:.3f} mm, {digital.jnd_error:+.2f} JND from the target")
        elif line.startswith("flat texture:"):
            out.append(line.replace("flat texture:", f"flat texture (judged as printed by {printer.name}):", 1))
        else:
            out.append(line)
    return [*out, f"printer {printer.describe()}: every texture judged as printed; the files written are the "
                  "digital design"]


def _check_options(args: argparse.Namespace) -> None:
    """The engine (spectral) and the target's options go together (InputError naming the option at fault)."""
    from roughness.core.errors import InputError

    if args.engine != "spectral":
        raise InputError("object tune judges and verifies with the spectral engine (the surrogate searches inside "
                         "design.tune)", parameter="engine")
    if args.jnd is not None and not args.reference:
        raise InputError("--jnd counts from a texture: give --reference NAME", parameter="jnd")
    if args.reference and args.jnd is None:
        raise InputError("--reference is what --jnd counts from; with --target-lambda leave it out",
                         parameter="reference")


def _checked_out(args: argparse.Namespace) -> Path:
    """--out (a texture format, not .stl) and --mesh-out (a mesh format), checked before any work; --out's path."""
    from roughness.core.errors import InputError
    from roughness.core.files import check_distinct, check_output
    from roughness.surface.io import SAVE_SUFFIXES

    check_distinct({"--out": args.out, "--mesh-out": args.mesh_out}, {"MESH": args.mesh, "--texture": args.texture, "--printer": args.printer})
    out = check_output(args.out, args.overwrite, "out")
    if out.suffix.lower() not in SAVE_SUFFIXES or out.suffix.lower() == ".stl":
        raise InputError(f"cannot save {out}: unsupported format {out.suffix or '(no suffix)'!r}; supported: "
                         f"{', '.join(s for s in SAVE_SUFFIXES if s != '.stl')}", "out")
    if args.mesh_out:
        from roughness.objects.meshes import require_mesh_format

        require_mesh_format(check_output(args.mesh_out, args.overwrite, "mesh_out"), "mesh_out")
    return out


def _check_factor_range(args: argparse.Namespace) -> None:
    """--min-factor below --max-factor where both are given."""
    from roughness.core.errors import InputError

    if args.min_factor and args.max_factor and not args.min_factor < args.max_factor:
        raise InputError(f"the factor range must rise, got {args.min_factor:g}..{args.max_factor:g}", "min_factor")


def _target(args: argparse.Namespace) -> _Target:
    """--target-lambda, or --jnd JNDs from --reference on the spectral engine's standard scale."""
    from roughness.objects.feel import reference_of
    from roughness.perceptual_scale import WEBER_FRACTION, load_scale

    scale = load_scale("spectral")
    if args.jnd is None:
        return _Target(args.target_lambda, "given")
    ref = reference_of(args.reference, "spectral", scale)
    return _Target(ref.lambda_mm * (1 + WEBER_FRACTION) ** args.jnd,
                   f"{args.jnd:+g} JND from {ref.name} (lambda {ref.lambda_mm:.3f} mm)")


def _factor_options(args: argparse.Namespace) -> dict:
    """tune_on_object's factor range where --min-factor or --max-factor is given (the other end the knob's
    default)."""
    if not (args.min_factor or args.max_factor):
        return {}
    from roughness.design.tune import FACTOR_RANGE

    lo, hi = FACTOR_RANGE[args.by]
    return {"factor_range": (args.min_factor or lo, args.max_factor or hi)}


def _textured(args: argparse.Namespace, inputs: ObjectInputs, mapping, region):
    """With --mesh-out, the object textured with the tuned texture (None without): built before anything is
    written, so a texture too deep for the mesh writes nothing."""
    if not args.mesh_out:
        return None
    from roughness.objects.texturing import texture_mesh

    log(args, "texturing the mesh with the tuned texture")
    return texture_mesh(inputs.mesh, mapping, region)


def _write_mesh(args: argparse.Namespace, textured):
    """The textured mesh written to --mesh-out (its record), or None if none was built."""
    if textured is None:
        return None
    from roughness.objects.meshes import write_mesh

    return write_mesh(textured.mesh, args.mesh_out, args.overwrite, "mesh_out")


def _summary(args: argparse.Namespace, inputs: ObjectInputs, target: _Target, result: ObjectTuneResult) -> dict:
    """The JSON output."""
    return {"mesh": args.mesh, "texture": inputs.texture_name, "mapping": args.mapping, "target": target.text,
            "out": args.out, "mesh_out": args.mesh_out, **result.summary(),
            "regions": [row.as_dict() for row in result.feel.table()], "readings": readings(args)}


def _text_lines(args: argparse.Namespace, target: _Target, result: ObjectTuneResult, written) -> list[str]:
    """The text output: the target, the flat texture, the object's curved parts, its regions and notes."""
    flat, o = result.flat, result.on_object
    where = "curved parts" if o.curved else "judged parts (none curved)"
    lines = [f"target lambda {target.lambda_mm:.3f} mm ({target.text}), V {result.target_roughness:.4f} (spectral "
             "scale)",
             f"flat texture: {flat.by} x {flat.factor:.4g} (aimed at lambda {flat.target.lambda_mm:.3f} mm flat so that "
             f"the object meets the target): V {flat.achieved.roughness:.4f}, lambda "
             f"{flat.achieved.equivalent_lambda_mm:.3f} mm, {result.flat_jnd_error:+.2f} JND from the target as a flat "
             "plate",
             f"on the object ({o.points} footprints on its {where}): median V {o.roughness:.4f}, lambda "
             f"{o.lambda_mm:.3f} mm, {o.jnd_error:+.2f} JND from the target "
             f"({'reached' if result.reached else 'NOT reached'} within {result.tolerance_jnd:g} JND, "
             f"{result.rounds} round(s))",
             *feel_lines(result.feel, args.mesh)[1:],
             *(f"note: {n}" for n in result.notes), f"tuned texture written to {args.out}"]
    if written is not None:
        lines.append(f"textured mesh: {written.line()}")
    return lines


def _union_region(args: argparse.Namespace):
    """The one region texture_mesh takes: the --region given (one), else all faces."""
    from roughness.core.errors import InputError
    from roughness.objects.regions import Region, parse_region

    if not args.region:
        return Region()
    if len(args.region) > 1:
        raise InputError("--mesh-out textures one region: give one --region", parameter="regions")
    return parse_region(args.region[0])
