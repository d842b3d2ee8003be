"""A spectral roughness map larger than one solve, its windows on a local Dask cluster: time and peak memory.

A printed texture (standard 1.5 mm bumps) of ``--size-mm`` square at ``--pixel-mm`` is more pixels than one
solve's MAX_MAP_PIXELS, so ``roughness.predict_map`` cuts it into overlapping windows
(simulate/spectral/windows.py) and solves them on ``--workers`` local worker processes of one thread each
(src/roughness/cluster.py ``local_cluster``, as ``roughness predict --map --engine spectral`` does by default).
Peak memory is each process's resident high-water mark (VmHWM; getrusage's maximum would be the calling
process's, inherited across the workers' exec): the calling process's from after the texture is made (the map,
the scheduler, the stitched result) and every worker's (one window's fields at a time). Run it once: it takes
minutes and gigabytes.

    python benchmarks/spectral_map_distributed.py [--size-mm 150] [--pixel-mm 0.025] [--workers 2]
    # writes benchmarks/results/spectral_map_distributed.{md,json}
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

OUT = Path(__file__).parent / "results"


def peak_rss_gb() -> float:
    """This process's resident high-water mark (GB): VmHWM, which is its own memory's (reset by exec)."""
    return int(re.search(r"VmHWM:\s+(\d+) kB", Path("/proc/self/status").read_text()).group(1)) / 1e6


def reset_peak() -> None:
    """Start this process's high-water mark again from its present resident set (Linux 4.0 and later)."""
    Path("/proc/self/clear_refs").write_text("5")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size-mm", type=float, default=150.0, help="side of the square map in mm (default 150)")
    parser.add_argument("--pixel-mm", type=float, default=0.025, help="pixel in mm (default 0.025)")
    parser.add_argument("--step-mm", type=float, default=1.0, help="footprint step in mm (default 1)")
    parser.add_argument("--workers", type=int, default=2, help="local Dask workers, one thread each (default 2)")
    parser.add_argument("--note", default="", help="a remark on the machine's state, written with the results")
    args = parser.parse_args()

    from dask.distributed import Client

    import roughness
    from roughness.cluster import local_cluster
    from roughness.dataset.textures import standard_texture

    load_before = os.getloadavg()
    start = time.perf_counter()
    hm = standard_texture(1.5, seed=1, size_mm=args.size_mm, pixel_mm=args.pixel_mm)
    made = time.perf_counter() - start
    reset_peak()  # making the texture is not the map's memory
    with local_cluster(args.workers) as cluster, Client(cluster) as client:
        start = time.perf_counter()
        cpu = time.process_time()
        result = roughness.predict_map(hm, "spectral", args.step_mm, client=client, quiet=False)
        seconds, client_cpu = time.perf_counter() - start, time.process_time() - cpu
        workers = sorted(client.run(peak_rss_gb).values())
    v = result.map.roughness
    record = {
        "map": f"standard 1.5 mm bumps, {args.size_mm:g} x {args.size_mm:g} mm at {args.pixel_mm:g} mm",
        "pixels": list(hm.shape), "positions": int(v.size), "step_mm": args.step_mm, "workers": args.workers,
        "texture_seconds": made, "map_seconds": seconds, "calling_process_cpu_seconds": client_cpu,
        "peak_rss_gb": {"calling process": peak_rss_gb(), "workers": workers},
        "notes": result.notes, "v_min": float(v.min()), "v_median": float(np.median(v)), "v_max": float(v.max()),
        "finite": bool(np.isfinite(v).all()), "load_average_before": load_before,
        "load_average_after": os.getloadavg(), "machine": f"{platform.machine()}, {os.cpu_count()} cores",
        "note": args.note}
    OUT.mkdir(exist_ok=True)
    (OUT / "spectral_map_distributed.json").write_text(json.dumps(record, indent=1))
    lines = [f"# A spectral map larger than one solve on {args.workers} local Dask workers",
             "",
             f"`python benchmarks/spectral_map_distributed.py` ({record['machine']}; run once). {args.note}",
             "",
             "| | |", "|---|---|",
             f"| map | {record['map']} ({hm.shape[1]:,} x {hm.shape[0]:,} pixels) |",
             f"| footprint positions | {v.size:,} ({args.step_mm:g} mm apart) |",
             f"| how | {result.notes[0] if result.notes else 'one solve'} |",
             f"| map wall time | {seconds:.0f} s (texture made in {made:.0f} s before) |",
             f"| calling process CPU time | {client_cpu:.1f} s |",
             f"| peak memory, calling process | {record['peak_rss_gb']['calling process']:.2f} GB |",
             f"| peak memory, each worker | {', '.join(f'{w:.2f}' for w in workers)} GB |",
             f"| V | {record['v_min']:.4f} to {record['v_max']:.4f} (median {record['v_median']:.4f}), all finite: "
             f"{record['finite']} |",
             f"| load average (1, 5, 15 min) before / after | {', '.join(f'{x:.1f}' for x in load_before)} / "
             f"{', '.join(f'{x:.1f}' for x in record['load_average_after'])} |",
             "", *(f"- note: {n}" for n in result.notes[1:])]
    (OUT / "spectral_map_distributed.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
