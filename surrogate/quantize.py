"""int8 version of an exported surrogate: static QDQ quantisation, per-channel weights.

Static QDQ keeps standard Conv nodes between QuantizeLinear/DequantizeLinear pairs, which the CPU
runtime fuses into int8 kernels (dynamic quantisation would make ConvInteger, which it may refuse).
Four choices, each measured (models/MODEL_CARD.md, int8 variant):

- Only convolutions are quantised (``op_types_to_quantize``; the ReLU after one reads its dequantised
  output): the pooling, the embedding and the dense head work on fp32 tensors, so the only 8-bit steps
  are the convolutions' inputs, weights and outputs, whose rounding the global mean averages out.
  Quantising every op type also put the pooled embedding on an 8-bit grid: the v3 ensemble (3 members,
  session 6) then strayed 2.2% from fp32 on a standard texture and 1.7% (median) on the check textures,
  as far with a single convolution quantised as with all of them; with the convolutions only, 0.9% and
  0.8%, at 70% of the fp32 graph's time (every op type: 65%; both on a loaded machine). The 5-member v3
  ensemble: 0.8% (standard, max) and 0.3% (check, median) with the convolutions only.
- 7-bit weights (``reduce_range``). On x86-64 CPUs with AVX2 but without VNNI the runtime's u8 x s8
  kernels add pairs of products in int16 (VPMADDUBSW), which saturates for full-range weights: the
  first int8 model was 10% below fp32 on the standard textures there although the same graph without
  the fused kernels was within 0.7%.
- The first convolution (it sees the raw heights, whose 8-bit step would be several um for a 1 mm
  relief and erase low-relief textures) and the dense head (its output is log V: an 8-bit step there
  is ~2% of V) stay in fp32; they hold a small share of the arithmetic.
- Activation ranges from the 0.001st..99.999th percentiles of 512 calibration textures of every family
  (bumps, natural, engineered), rather than their min/max, so a few extreme inputs do not coarsen every
  step. With 64 textures of the natural families only, a 5-member test ensemble's int8 V strayed 2.4% from
  fp32 on a standard texture; with 256, 1.2% (by hand, session 23). The shipped v2 ensemble strayed 2.4%
  with 256 and 1.9% with 512 (session 25).

The int8 graph keeps the fp32 model's metadata (domain, scale, metrics of the fp32 model); how far
its V moves from the fp32 V on the standard textures and on other recipe textures is stored under
``int8`` in the metadata, and nothing is written if it moves more than the limits below.
"""
from __future__ import annotations

import contextlib
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import onnx
import onnxruntime as ort

from roughness.core.files import atomic_write, check_output

from .export import OUTPUTS, check_patches
from .metadata import METADATA_KEY, onnx_metadata
from .patch import footprint_patch
from .predictor import INPUT
from .target import roughness_from_log

MAX_STANDARD_REL_DIFF = 0.02  # int8 V within 2% of fp32 V on every standard texture
MAX_MEDIAN_REL_DIFF = 0.01  # and within 1% (median) on the check textures
V_FLOOR = 2e-3  # relative differences are taken of max(V, V_FLOOR): below it V is flat-texture noise
CALIBRATION_PERCENTILE = 99.999


class QuantizationError(RuntimeError):
    """The int8 graph strays too far from the fp32 one."""


def relative_difference(v: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """|v - reference| / max(reference, V_FLOOR), per input."""
    return np.abs(v - reference) / np.maximum(reference, V_FLOOR)


def fp32_nodes(graph: onnx.GraphProto) -> list[str]:
    """Nodes kept in fp32: every convolution reading the graph input, and every dense (Gemm/MatMul) node."""
    return [node.name for node in graph.node
            if (node.op_type == "Conv" and INPUT in node.input) or node.op_type in ("Gemm", "MatMul")]


def standard_patches() -> np.ndarray:
    """Footprint patches (n, 1, P, P) of the 13 standard textures (seed 0)."""
    from roughness.dataset.textures import STANDARD_LAMBDAS_MM, standard_texture

    return np.stack([footprint_patch(standard_texture(lam)) for lam in STANDARD_LAMBDAS_MM])[:, None]


def quantize(fp32_path: str | Path, out: str | Path, calibration: int = 512, check: int = 32,
             overwrite: bool = False) -> dict:
    """Write the int8 model and return the checks' numbers; nothing is written if a check fails.

    ``out`` must not exist unless ``overwrite``.
    """
    from onnxruntime.quantization import (
        CalibrationDataReader,
        CalibrationMethod,
        QuantFormat,
        QuantType,
        quantize_static,
    )
    from onnxruntime.quantization.shape_inference import quant_pre_process

    out = check_output(out, overwrite, "int8")
    fp32_meta = onnx_metadata(fp32_path)
    patches = check_patches(calibration + check)
    calib, held = patches[:calibration], patches[calibration:]

    class Reader(CalibrationDataReader):
        def __init__(self) -> None:
            self.batches = iter([{INPUT: calib[i:i + 8]} for i in range(0, len(calib), 8)])

        def get_next(self) -> dict | None:
            return next(self.batches, None)

    with tempfile.TemporaryDirectory() as tmp:
        pre, q = Path(tmp) / "pre.onnx", Path(tmp) / "int8.onnx"
        quant_pre_process(str(fp32_path), str(pre))
        with contextlib.redirect_stdout(sys.stderr):  # the calibrator prints its progress
            quantize_static(str(pre), str(q), Reader(), quant_format=QuantFormat.QDQ, per_channel=True,
                            reduce_range=True, activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8,
                            nodes_to_exclude=fp32_nodes(onnx.load(str(pre)).graph), op_types_to_quantize=["Conv"],
                            calibrate_method=CalibrationMethod.Percentile,
                            extra_options={"CalibPercentile": CALIBRATION_PERCENTILE})
        report = {"calibration_inputs": len(calib), "checked_inputs": len(held)}
        for name, x in (("standard", standard_patches()), ("check", held)):
            v32 = roughness_from_log(_run(fp32_path, x), fp32_meta.log_offset)
            rel = relative_difference(roughness_from_log(_run(q, x), fp32_meta.log_offset), v32)
            report |= {f"{name}_median_rel_diff_vs_fp32": float(np.median(rel)),
                       f"{name}_p95_rel_diff_vs_fp32": float(np.percentile(rel, 95)),
                       f"{name}_max_rel_diff_vs_fp32": float(rel.max())}
        if not (report["standard_max_rel_diff_vs_fp32"] < MAX_STANDARD_REL_DIFF
                and report["check_median_rel_diff_vs_fp32"] < MAX_MEDIAN_REL_DIFF):
            raise QuantizationError(
                f"int8 V differs from fp32 by up to {100 * report['standard_max_rel_diff_vs_fp32']:.1f}% on the "
                f"standard textures (limit {100 * MAX_STANDARD_REL_DIFF:.0f}%) and by "
                f"{100 * report['check_median_rel_diff_vs_fp32']:.1f}% (median) on other textures "
                f"(limit {100 * MAX_MEDIAN_REL_DIFF:.0f}%)")
        graph = onnx.load(str(q))
        if any(node.op_type in ("ConvInteger", "MatMulInteger") for node in graph.graph.node):
            raise QuantizationError("the int8 graph has ConvInteger/MatMulInteger nodes (dynamic quantisation)")
        del graph.metadata_props[:]
        graph.metadata_props.add(key=METADATA_KEY, value=replace(fp32_meta, int8=report).to_json())
        graph.model_version = onnx.load(str(fp32_path), load_external_data=False).model_version  # the fp32's
        atomic_write(out, lambda path: onnx.save(graph, path), overwrite)
    return report | {"path": str(out), "bytes": out.stat().st_size}


def _run(path: str | Path, patches: np.ndarray) -> np.ndarray:
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    return session.run([OUTPUTS[0]], {INPUT: patches})[0].astype(float)
