"""Surrogate latency and throughput with onnxruntime, and the ratio to FEM, in one run.

Model-only latency at batch 1 on one thread (the graph alone), end-to-end time per heightmap
(footprint patch, descriptors, domain check and the graph, via roughness.predict), batched
throughput on 1 and 2 threads, FEM `default` and `coarse` per texture (warm block: the
mesh, assembly and base field are excluded, as they are paid once per process), and a fresh
Python process that imports roughness, loads the README's example and predicts it (wall time
of the whole process, and of the first predict call in it), and the README's main job in a
fresh process: ``roughness predict`` on that example, wall time of the whole command. Fresh processes
find compiled bytecode, as an installed package does (the first, compiling run is not timed).

    python benchmarks/surrogate_latency.py [--model models/roughness-cnn.onnx]
    # writes benchmarks/results/surrogate_latency.{md,json}
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

OUT = Path(__file__).parent / "results"
ROOT = Path(__file__).resolve().parents[1]
FRESH = """
import time
import roughness
hm = roughness.load_heightmap({example!r}, pixel_mm=0.05, height_mm=1.0)
t = time.perf_counter()
roughness.predict(hm, model={model!r})
print(time.perf_counter() - t)
"""


def compiled_env(cache: str) -> dict[str, str]:
    """The environment of a fresh process that finds compiled bytecode, as an installed package has (pip compiles
    it at install time): a bytecode cache outside the tree, filled by an untimed first run."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    return env | {"PYTHONPYCACHEPREFIX": cache}


def fresh_process(model: str, cache: str, repeats: int = 5) -> tuple[float, float]:
    """Median wall time (s) of a whole fresh process predicting the README example, and of its predict call."""
    code = FRESH.format(example=str(ROOT / "examples" / "standard-1.0mm.png"), model=model)
    walls, calls = [], []
    for i in range(repeats + 1):
        t = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                             env=compiled_env(cache))
        if i:  # the first run compiles the bytecode
            walls.append(time.perf_counter() - t)
            calls.append(float(out.stdout.split()[-1]))
    return statistics.median(walls), statistics.median(calls)


def fresh_cli(model: str, cache: str, repeats: int = 5) -> float:
    """Median wall time (s) of ``roughness predict`` on the README example in a fresh process (the console
    command's own start-up: argument parsing, imports, model loading, reading the file, printing)."""
    command = [sys.executable, "-m", "roughness.cli", "predict", str(ROOT / "examples" / "standard-1.0mm.png"),
               "--pixel-mm", "0.05", "--height-mm", "1", "--engine", "surrogate", "--model", model]
    walls = []
    for i in range(repeats + 1):
        t = time.perf_counter()
        subprocess.run(command, capture_output=True, text=True, check=True, cwd=ROOT, env=compiled_env(cache))
        if i:  # the first run compiles the bytecode
            walls.append(time.perf_counter() - t)
    return statistics.median(walls)


def timed(fn, repeats: int) -> list[float]:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return times


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default=str(Path(__file__).resolve().parents[1] / "models" / "roughness-cnn.onnx"),
                        help="ONNX model to time (default: models/roughness-cnn.onnx; models/*-int8.onnx beside it "
                             "is timed too)")
    return parser.parse_args()


def main() -> None:
    from roughness.dataset.recipe import Recipe, realise, sample_record
    from roughness.dataset.textures import standard_texture
    from roughness.prediction import PredictOptions, predict
    from roughness.simulate.config import SimConfig
    from roughness.simulate.model import Simulator
    from roughness.surrogate.predictor import INPUT, SurrogateModel

    args = parse_args()
    families = {f: 1.0 for f in ("bumps", "cellular", "dots", "fbm", "grains", "grating", "knit", "woven")}
    maps = [realise(sample_record(Recipe(seed=99, families=families), i)) for i in range(64)]
    one = SurrogateModel(args.model, threads=1)
    patches = np.stack([one.patch(hm) for hm in maps])
    for p in patches[:20]:
        one.run(p[None])  # warm-up

    model_only = [t for p in np.tile(patches, (8, 1, 1)) for t in timed(lambda: one.session.run(
        None, {INPUT: p[None, None]}), 1)]
    end_to_end = timed(lambda: predict(maps[0], engine="surrogate", model=one), 200)
    batched = {}
    for threads in (1, 2):
        model = SurrogateModel(args.model, threads=threads)
        batch = np.tile(patches, (4, 1, 1))[:, None]  # 256 patches
        model.session.run(None, {INPUT: batch})
        seconds = min(timed(lambda: model.session.run(None, {INPUT: batch}), 5))
        batched[threads] = len(batch) / seconds
    e2e_batched = len(maps) / min(timed(lambda: predict(maps, engine="surrogate", model=SurrogateModel(
        args.model, threads=2), options=PredictOptions(batch_size=64)), 3))
    int8 = {}
    int8_path = Path(args.model).with_name(Path(args.model).stem + "-int8.onnx")
    if int8_path.exists():
        q1, q2 = SurrogateModel(int8_path, threads=1), SurrogateModel(int8_path, threads=2)
        batch = np.tile(patches, (4, 1, 1))[:, None]
        q2.session.run(None, {INPUT: batch})
        int8 = {"path": int8_path.name,
                "batch1_1thread_ms_median": 1e3 * statistics.median(
                    [t for p in np.tile(patches, (8, 1, 1)) for t in timed(lambda: q1.session.run(
                        None, {INPUT: p[None, None]}), 1)]),
                "batched_2threads_per_s": len(batch) / min(timed(lambda: q2.session.run(None, {INPUT: batch}), 5))}

    with tempfile.TemporaryDirectory() as cache:
        fresh_wall, fresh_call = fresh_process(args.model, cache)
        cli_wall = fresh_cli(args.model, cache)
    fem = {}
    for fidelity in ("coarse", "default"):
        sim = Simulator(SimConfig(fidelity=fidelity))
        sim.run(standard_texture(1.0, seed=0))  # cold: mesh and base field
        fem[fidelity] = statistics.mean(sim.run(standard_texture(lam, seed=s)).seconds
                                        for lam, s in ((0.75, 1), (1.0, 2), (1.25, 3)))

    lat = statistics.median(model_only)
    e2e = statistics.median(end_to_end)
    result = {
        "model": Path(args.model).name, "machine": f"{platform.machine()}, {os.cpu_count()} cores",
        "batch1_1thread_ms_median": 1e3 * lat, "batch1_1thread_ms_p95": 1e3 * float(np.percentile(model_only, 95)),
        "end_to_end_1thread_ms_median": 1e3 * e2e,
        "batched_patches_per_s": {str(k): v for k, v in batched.items()},
        "end_to_end_batched_2threads_per_s": e2e_batched,
        "fem_warm_seconds": fem,
        "speedup_vs_fem_default_end_to_end": fem["default"] / e2e,
        "speedup_vs_fem_coarse_end_to_end": fem["coarse"] / e2e,
        "int8": int8,
        "fresh_process_wall_s": fresh_wall, "fresh_process_first_predict_s": fresh_call,
        "fresh_cli_predict_wall_s": cli_wall,
    }
    OUT.mkdir(exist_ok=True)
    (OUT / "surrogate_latency.json").write_text(json.dumps(result, indent=1))
    rows = [
        ("graph only, batch 1, 1 thread (median / p95)", f"{1e3 * lat:.2f} ms / "
                                                          f"{result['batch1_1thread_ms_p95']:.2f} ms"),
        ("end to end per heightmap, 1 thread (median)", f"{1e3 * e2e:.2f} ms"),
        ("graph only, batch 256, 1 thread", f"{batched[1]:,.0f} patches/s"),
        ("graph only, batch 256, 2 threads", f"{batched[2]:,.0f} patches/s"),
        ("end to end, batch 64, 2 threads", f"{e2e_batched:,.0f} heightmaps/s"),
        ("fresh process: import, load the README example, predict (wall, median of 5)", f"{fresh_wall:.2f} s"),
        ("fresh process: its first predict call (model loading included)", f"{1e3 * fresh_call:.0f} ms"),
        ("fresh process: `roughness predict` on the README example (wall, median of 5)", f"{cli_wall:.2f} s"),
        ("FEM coarse, warm, per texture", f"{fem['coarse']:.2f} s"),
        ("FEM default, warm, per texture", f"{fem['default']:.2f} s"),
        ("speed-up over FEM default (end to end, batch 1)", f"{result['speedup_vs_fem_default_end_to_end']:,.0f}x"),
        ("speed-up over FEM coarse (end to end, batch 1)", f"{result['speedup_vs_fem_coarse_end_to_end']:,.0f}x"),
    ]
    if int8:
        rows += [("int8 graph, batch 1, 1 thread (median)", f"{int8['batch1_1thread_ms_median']:.2f} ms"),
                 ("int8 graph, batch 256, 2 threads", f"{int8['batched_2threads_per_s']:,.0f} patches/s")]
    table = "| measure | value |\n|---|---|\n" + "".join(f"| {a} | {b} |\n" for a, b in rows)
    (OUT / "surrogate_latency.md").write_text(
        f"# Surrogate latency ({result['model']}, {result['machine']})\n\n"
        "Regenerate: `python benchmarks/surrogate_latency.py`. All numbers from one run.\n\n" + table)
    print(table)


if __name__ == "__main__":
    main()
