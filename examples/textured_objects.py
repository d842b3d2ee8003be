"""Worked example (docs/tutorials/textured-objects.md): a knob and a handle, each textured to a target
roughness on its curved part, with pictures of how each part feels and the per-region tables.

    python examples/textured_objects.py [--out FOLDER] [--overwrite] [--case knob] [--mesh]

Writes, into FOLDER (default: a new folder textured-objects/ under the current directory; a folder holding files is
refused without --overwrite), knob.stl and handle.stl (the untextured objects), the tuned textures (*_tuned.npz),
pictures of the tuned objects coloured by JND from the target (*_feel.png), results.md (tables and timings) and
results.json (the numbers the tutorial quotes). ``--case`` runs one object only (the knob takes seconds, the handle
minutes). ``--mesh`` also builds the textured meshes with ``texture_mesh`` (minutes: millions of triangles each) and
times it. The committed results were made with ``--out examples/objects --overwrite --mesh``.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import resource
import time
from pathlib import Path

import numpy as np


def knob():
    """A knob: a cylinder of radius 15 mm, 20 mm tall, its top edge rounded to 4 mm."""
    import trimesh

    profile = [(0, 0), (15, 0), (15, 16)] + [(11 + 4 * math.cos(a), 16 + 4 * math.sin(a))
                                             for a in np.linspace(0, math.pi / 2, 12)[1:]] + [(0, 20)]
    return trimesh.creation.revolve(np.array(profile), sections=128)


def handle():
    """A handle: a capsule of radius 12 mm, 80 mm long between its hemispherical ends, along z."""
    import trimesh

    return trimesh.creation.capsule(height=80.0, radius=12.0, count=[64, 64])


CASES = {  # name: (mesh, mapping, regions, target (lambda mm or JND from standard-1.0), texture)
    "knob": (knob, "cylinder", ["cone:0,0,1,3", "all"], ("lambda", 1.0), "standard-1.0"),
    "handle": (handle, "cylinder", ["cone:0,0,1,80", "all"], ("jnd", 1.0), "standard-1.0"),
}


def table(feel) -> list[str]:
    """The per-region table in Markdown."""
    ref = feel.reference
    lines = ["| region | area mm² | points | refused | V median | V range | ± V | lambda mm | JND from "
             f"{ref.name if ref else '-'} |", "|---|---|---|---|---|---|---|---|---|"]
    for r in feel.table():
        if r.roughness_median is None:
            lines.append(f"| {r.name} | {r.area_mm2:.0f} | {r.points} | {100 * r.refused_fraction:.0f}% | - | - | - | - "
                         "| - |")
            continue
        lines.append(f"| `{r.name}` | {r.area_mm2:.0f} | {r.points} | {100 * r.refused_fraction:.0f}% | "
                     f"{r.roughness_median:.4f} | {r.roughness_min:.4f}..{r.roughness_max:.4f} | "
                     f"{r.uncertainty_median:.4f} | {'below' if r.lambda_median_mm is None else f'{r.lambda_median_mm:.3f}'} | "
                     + (f"{r.jnd_median:+.2f} |" if r.jnd_median is not None else "- |"))
    return lines


def main(argv: list[str] | None = None) -> None:
    from roughness.core.figures import save_figure
    from roughness.dataset.textures import named_texture
    from roughness.objects.feel import Reference, feel_map, reference_of
    from roughness.objects.feel_figure import feel_figure
    from roughness.objects.layout import make_mapping
    from roughness.objects.regions import parse_region
    from roughness.objects.tuning import tune_on_object
    from roughness.perceptual_scale import WEBER_FRACTION, load_scale
    from roughness.surface.io import save_heightmap

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="textured-objects",
                        help="output folder (default: textured-objects under the current directory)")
    parser.add_argument("--overwrite", action="store_true", help="write into a folder that already holds files")
    parser.add_argument("--case", action="append", choices=sorted(CASES), help="one object only (repeatable)")
    parser.add_argument("--mesh", action="store_true", help="also build and time the textured meshes")
    args = parser.parse_args(argv)
    out = Path(args.out)
    if out.is_dir() and any(out.iterdir()) and not args.overwrite:
        parser.error(f"{out} already holds files: name a new folder, or add --overwrite to replace them")
    out.mkdir(parents=True, exist_ok=True)
    cases = {name: CASES[name] for name in args.case} if args.case else CASES
    scale = load_scale("spectral")
    reference = reference_of("standard-1.0", "spectral", scale)
    report = ["# Textured objects: a knob and a handle tuned to a target on their curved parts", "",
              f"`python examples/textured_objects.py{' --mesh' if args.mesh else ''}` on {os.cpu_count()} cores "
              f"({platform.processor() or platform.machine()}), OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', '-')};"
              " spectral engine, footprints 5 mm apart, textures tuned by height.", ""]
    numbers = {}
    for name, (make, kind, region_specs, (how, value), texture_name) in cases.items():
        mesh = make()
        mesh.export(out / f"{name}.stl")
        regions = {spec: parse_region(spec).faces(mesh) for spec in region_specs}
        textured = np.logical_or.reduce(list(regions.values()))
        texture = named_texture(texture_name, 0)
        target = value if how == "lambda" else reference.lambda_mm * (1 + WEBER_FRACTION) ** value
        wanted = f"lambda {target:.3f} mm" + ("" if how == "lambda" else f" ({value:+g} JND from {reference.name})")

        def mapping_for(hm, mesh=mesh, textured=textured):
            return make_mapping(kind, hm, mesh, textured)

        start = time.perf_counter()
        before = feel_map(mesh, mapping_for(texture), regions, reference="standard-1.0")
        map_seconds = time.perf_counter() - start
        start = time.perf_counter()
        result = tune_on_object(mesh, texture, mapping_for, target, regions)
        tune_seconds = time.perf_counter() - start
        save_heightmap(result.heightmap, out / f"{name}_tuned.npz")
        after = feel_map(mesh, mapping_for(result.heightmap), regions,
                         reference=Reference("the target", result.target_roughness, target))
        save_figure(feel_figure(mesh, after, textured, "jnd", f"{name}, tuned to {wanted}"), out / f"{name}_feel.png",
                    80)
        o, flat = result.on_object, result.flat
        numbers[name] = {"factor": flat.factor, "flat_jnd": result.flat_jnd_error, "object_jnd": o.jnd_error,
                         "object_lambda_mm": o.lambda_mm, "reached": result.reached,
                         "regions_jnd": {r.name: r.jnd_median for r in after.table()}}
        report += [f"## The {name} ({len(mesh.faces):,} triangles, {mesh.area:.0f} mm²; {kind} mapping)", "",
                   f"Target {wanted}. Tuned: height x {flat.factor:.3f}; as a flat plate the tuned texture feels like "
                   f"lambda {flat.achieved.equivalent_lambda_mm:.3f} mm ({result.flat_jnd_error:+.2f} JND from the "
                   f"target); on the {name}'s curved parts ({o.points} footprints) like lambda {o.lambda_mm:.3f} mm "
                   f"({o.jnd_error:+.2f} JND: {'reached' if result.reached else 'NOT reached'} within "
                   f"{result.tolerance_jnd:g} JND, {result.rounds} round(s)).", "",
                   f"Before tuning ({texture_name} as it is):", "", *table(before), "",
                   "After tuning (JNDs from the target):", "", *table(after), "",
                   *(f"- refused at {n} point(s): {why}" for why, n in after.refusals().items()), "",
                   f"![{name}]({name}_feel.png)", "",
                   f"Timings: map {map_seconds:.1f} s ({len(before.points)} footprints), tune {tune_seconds:.1f} s "
                   f"(including {result.rounds + 1} maps).", ""]
        if args.mesh:
            from roughness.objects.meshes import write_mesh
            from roughness.objects.regions import Region
            from roughness.objects.texturing import texture_mesh

            start = time.perf_counter()
            built = texture_mesh(mesh, mapping_for(result.heightmap), Region())
            written = write_mesh(built.mesh, out / f"{name}_textured.stl", overwrite=True)
            peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
            report += [f"Textured mesh: {written.triangles:,} triangles, {written.bytes / 1e6:.0f} MB, built in "
                       f"{time.perf_counter() - start:.0f} s; peak memory of the process so far {peak:.1f} GB.", ""]
        print(f"{name}: done")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    report.append(f"Peak memory of the whole run: {peak:.2f} GB.")
    (out / "results.md").write_text("\n".join(report) + "\n")
    (out / "results.json").write_text(json.dumps(numbers, indent=1) + "\n")
    print(f"wrote {out / 'results.md'} and results.json")


if __name__ == "__main__":
    main()
