"""Roughness-map throughput (footprints/s) and where its time goes, all measured in one run.

Times, for the same footprints of a 30 mm map: cutting the patches out one at a time
(patch.footprint_patch) and together (patch.footprint_patches: strided windows of one averaged
grid), the descriptors one patch at a time and batched, the network alone (batch 256), and the whole
map end to end (surrogate.roughness_map: patches, network, descriptors, domain check, the next
batch prepared while the network runs) and the same work done serially. Each is the
best of ``--repeats`` runs, interleaved, so a busy machine slows them alike: compare them as ratios.
The map's CPU time (all threads of this process) is recorded too: it is much less sensitive to other
processes than the wall time, and bounds the rate on an idle machine with T threads between
1/cpu (nothing runs in parallel) and T/cpu (everything does).

    python benchmarks/surrogate_map.py [--model models/roughness-cnn.onnx] [--threads 2]
    # writes benchmarks/results/surrogate_map.{md,json}
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

OUT = Path(__file__).parent / "results"


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = Path(__file__).resolve().parents[1]
    parser.add_argument("--model", default=str(root / "models" / "roughness-cnn.onnx"), help="ONNX model to time "
                        "(default: models/roughness-cnn.onnx)")
    parser.add_argument("--threads", type=int, default=2, help="onnxruntime threads (default: 2)")
    parser.add_argument("--size-mm", type=float, default=30.0, help="side of the square test map in mm (default: 30)")
    parser.add_argument("--step-mm", type=float, default=0.5, help="map step in mm (default: 0.5)")
    parser.add_argument("--repeats", type=int, default=3, help="runs of each measurement; the best counts (default 3)")
    return parser.parse_args()


def best(fn, repeats: int, clock=time.perf_counter) -> float:
    times = []
    for _ in range(repeats):
        start = clock()
        fn()
        times.append(clock() - start)
    return min(times)


def serial_map(model, hm, grid: np.ndarray, batch: int = 256) -> None:
    """The map's work without overlap: cut out, then evaluate, batch after batch."""
    from roughness.surrogate.patch import footprint_patches

    for i in range(0, len(grid), batch):
        model.evaluate(footprint_patches(hm, grid[i:i + batch]))


def main() -> None:
    from roughness.dataset.families import make
    from roughness.surrogate.patch import batch_descriptors, descriptors, footprint_patch, footprint_patches
    from roughness.surrogate.predictor import INPUT, SurrogateModel
    from roughness.surrogate.roughness_map import centres, roughness_map

    args = parse_args()
    hm = make("mixture", seed=3, size_mm=args.size_mm, pixel_mm=0.05)
    model = SurrogateModel(args.model, threads=args.threads)
    xs = centres(args.size_mm, model.footprint_mm, args.step_mm, False)
    grid = np.array([(x, y) for y in xs for x in xs])
    sample = grid[:256]
    patches = footprint_patches(hm, sample)
    seconds: dict[str, list[float]] = {k: [] for k in ("patch_one_by_one", "patches_strided", "descriptors_one_by_one",
                                                       "descriptors_batched", "network", "map_end_to_end", "map_serial")}
    cpu: list[float] = []
    for _ in range(args.repeats):  # interleaved: each round times every stage once
        seconds["patch_one_by_one"].append(best(lambda: [footprint_patch(hm, tuple(c)) for c in sample], 1))
        seconds["patches_strided"].append(best(lambda: footprint_patches(hm, sample), 1))
        seconds["descriptors_one_by_one"].append(best(lambda: [descriptors(p) for p in patches], 1))
        seconds["descriptors_batched"].append(best(lambda: batch_descriptors(patches), 1))
        seconds["network"].append(best(lambda: model.session.run(None, {INPUT: patches[:, None]}), 1))
        seconds["map_end_to_end"].append(best(lambda: roughness_map(model, hm, args.step_mm), 1))
        seconds["map_serial"].append(best(lambda: serial_map(model, hm, grid), 1))
        cpu.append(best(lambda: roughness_map(model, hm, args.step_mm), 1, time.process_time))
    per_footprint_ms = {k: 1e3 * min(v) / (len(grid) if k.startswith("map") else len(sample))
                        for k, v in seconds.items()}
    result = {"model": Path(args.model).name, "machine": f"{platform.machine()}, {os.cpu_count()} cores",
              "threads": args.threads, "map_mm": args.size_mm, "step_mm": args.step_mm, "footprints": len(grid),
              "per_footprint_ms": per_footprint_ms,
              "map_footprints_per_s": 1e3 / per_footprint_ms["map_end_to_end"],
              "network_footprints_per_s": 1e3 / per_footprint_ms["network"],
              "network_share_of_map_time": per_footprint_ms["network"] / per_footprint_ms["map_end_to_end"],
              "map_cpu_ms_per_footprint": 1e3 * min(cpu) / len(grid)}
    result["idle_machine_footprints_per_s_bounds"] = [1e3 / result["map_cpu_ms_per_footprint"],
                                                      args.threads * 1e3 / result["map_cpu_ms_per_footprint"]]
    OUT.mkdir(exist_ok=True)
    (OUT / "surrogate_map.json").write_text(json.dumps(result, indent=1))
    rows = [(k.replace("_", " "), f"{v:.3f} ms") for k, v in per_footprint_ms.items()]
    rows += [("map end to end, rate", f"{result['map_footprints_per_s']:,.0f} footprints/s"),
             ("network alone (batch 256)", f"{result['network_footprints_per_s']:,.0f} footprints/s"),
             ("network share of the map's time", f"{100 * result['network_share_of_map_time']:.0f}%"),
             ("map CPU time (all threads)", f"{result['map_cpu_ms_per_footprint']:.3f} ms"),
             (f"map on an idle machine, {args.threads} threads (from the CPU time)",
              "{:,.0f} to {:,.0f} footprints/s".format(*result["idle_machine_footprints_per_s_bounds"]))]
    table = "| per footprint | value |\n|---|---|\n" + "".join(f"| {a} | {b} |\n" for a, b in rows)
    (OUT / "surrogate_map.md").write_text(
        f"# Roughness-map throughput ({result['model']}, {result['machine']}, {args.threads} onnxruntime threads)\n\n"
        f"A {args.size_mm:g} mm map at {args.step_mm:g} mm steps ({len(grid):,} footprints). Regenerate: "
        "`python benchmarks/surrogate_map.py`. Best of interleaved runs; the machine may be shared, so compare "
        "rows as ratios.\n\n" + table)
    print(table)


if __name__ == "__main__":
    main()
