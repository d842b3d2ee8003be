"""The issue-40 handle, designed for the printer in one run, against texturing it with the default options.

    python benchmarks/handle_printer.py --out /tmp/handle   # writes results/handle_printer.{md,json}

The handle is a 20 x 60 mm cylinder (96 sides, trimesh), its sides textured (region ``box``, the caps left
flat) with ``standard-1.0`` wrapped around the axis. The steps are the documented commands, each run as its own
process and timed wall-clock in this one run (so their ratios compare like with like):

1. ``object tune --printer fdm-0.4-0.2``: curvature and printer corrected in one tune to lambda 1.0 mm;
2. ``object feel --printer fdm-0.4-0.2`` on the tuned texture: the feel map of the printed handle (picture);
3. ``object texture --printer fdm-0.4-0.2``: the textured mesh at the printer's edge length;
4. ``object texture --printer none``: today's default without a printer (the finest edge the texture holds).

Each step's peak resident memory is read from the child's rusage. The machine is named in the table, with
whether other jobs shared it.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

RESULTS = Path(__file__).parent / "results"
PRINTER = "fdm-0.4-0.2"
SIDES = ["--texture", "standard-1.0", "--mapping", "cylinder", "--region", "box:-11,-11,-29,11,11,29"]


def _run(name: str, args: list[str]) -> dict:
    """Run ``roughness ARGS`` as a child; its wall time (s), peak memory (MB) and output."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "roughness.cli", *args], capture_output=True, text=True)
    seconds = time.perf_counter() - t
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    if out.returncode != 0:
        raise SystemExit(f"{name} failed ({out.returncode}):\n{out.stderr[-3000:]}")
    print(f"{name}: {seconds:.0f} s", file=sys.stderr)
    return {"step": name, "seconds": seconds, "peak_mb": max(peak, before) / 1024, "stdout": out.stdout,
            "stderr": out.stderr}


def _mesh_facts(text: str) -> dict:
    """Triangles, STL MB and edge length from ``object texture``'s output."""
    def number(pattern: str) -> float | None:
        m = re.search(pattern, text)
        return float(m.group(1).replace(",", "")) if m else None
    return {"triangles": number(r"-> ([\d,]+) triangles"), "edge_mm": number(r"edges of at most ([\d.]+) mm"),
            "expected_triangles": number(r"expected: about ([\d,]+) triangles"),
            "expected_seconds": _seconds(re.search(r"expected: .*, about ([\d.]+) (s|min) \(", text))}


def _seconds(match) -> float | None:
    """``about N s`` or ``about N min`` as seconds."""
    return None if match is None else float(match[1]) * (60 if match[2] == "min" else 1)


def report(record: dict) -> str:
    """The Markdown table of a run, with the tune's and the feel map's output."""
    steps = record["steps"]
    lines = ["# The handle designed for the printer (issue 40)", "",
             f"`python benchmarks/handle_printer.py --out DIR` on {record['machine']}; 1-minute load average "
             f"{record['load_average_1min_at_end']:.1f} at the end (above the cores' count, other jobs shared the "
             "machine: times are then long, and only their ratios within this run compare).", "",
             "| step | wall s | peak MB | edge mm | triangles (expected) | STL MB | expected s |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for s in steps:
        if "triangles" in s:
            mesh = (f"{s['edge_mm']:.3f} | {s['triangles']:,.0f} ({s['expected_triangles']:,.0f}) | "
                    f"{50 * s['triangles'] / 1e6:,.0f} | {s['expected_seconds'] or 0:.0f}")
        else:
            mesh = " |  |  | "
        lines.append(f"| `{s['step']}` | {s['seconds']:.0f} | {s['peak_mb']:,.0f} | {mesh} |")
    lines += ["", "## What the tune said", "", "```", steps[0]["stdout"].strip(), "```", "",
              "## The feel map as printed", "", "```", steps[1]["stdout"].strip(), "```"]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", required=True, help="a new folder for the handle, texture, picture and meshes")
    parser.add_argument("--no-default", action="store_true", help="skip step 4 (the default texturing, minutes)")
    parser.add_argument("--no-record", action="store_true", help="do not write results/handle_printer.*")
    parser.add_argument("--report-only", action="store_true",
                        help="write results/handle_printer.md again from results/handle_printer.json (no runs)")
    args = parser.parse_args()
    if args.report_only:
        record = json.loads((RESULTS / "handle_printer.json").read_text())
        for step in record["steps"]:
            if step["step"].startswith("object texture"):
                step |= _mesh_facts(step["stdout"] + step["stderr"])
        (RESULTS / "handle_printer.md").write_text(report(record))
        return
    import trimesh

    out = Path(args.out)
    out.mkdir(parents=True)
    handle = out / "handle.stl"
    trimesh.creation.cylinder(radius=10.0, height=60.0, sections=96).export(handle)
    tuned = out / "tuned.npz"
    steps = [_run("object tune --printer", ["object", "tune", str(handle), *SIDES, "--target-lambda", "1.0",
                                            "--printer", PRINTER, "--out", str(tuned)])]
    steps.append(_run("object feel --printer", ["object", "feel", str(handle), *SIDES[2:], "--texture", str(tuned),
                                                "--printer", PRINTER, "--picture", str(out / "feel.png")]))
    steps.append(_run("object texture --printer", ["object", "texture", str(handle), *SIDES[2:], "--texture",
                                                   str(tuned), "--printer", PRINTER, "--out",
                                                   str(out / "printer.stl")]))
    if not args.no_default:
        steps.append(_run("object texture (default)", ["object", "texture", str(handle), *SIDES[2:], "--texture",
                                                       str(tuned), "--printer", "none", "--out",
                                                       str(out / "default.stl")]))
    for step in steps:
        if step["step"].startswith("object texture"):
            step |= _mesh_facts(step["stdout"] + step["stderr"])
    record = {"machine": f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}",
              "load_average_1min_at_end": os.getloadavg()[0], "steps": steps}
    text = report(record)
    print(text)
    if not args.no_record:
        (RESULTS / "handle_printer.md").write_text(text)
        (RESULTS / "handle_printer.json").write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
