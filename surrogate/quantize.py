"""int8 version of an exported surrogate: static QDQ quantisation, per-channel weights.

Static QDQ keeps standard Conv nodes between QuantizeLinear/DequantizeLinear pairs, which the CPU
runtime fuses into int8 kernels (dynamic quantisation would make ConvInteger, which it may refuse).
Activation ranges are calibrated on real textures drawn like the training recipe's. The int8 graph
keeps the fp32 model's metadata (domain, scale, metrics of the fp32 model); how far its V moves from
the fp32 V is measured on other textures and stored under ``int8`` in the metadata.
"""
from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import onnx
import onnxruntime as ort

from roughness.core.files import atomic_write, check_output

from .export import OUTPUTS, check_patches
from .metadata import METADATA_KEY, onnx_metadata
from .predictor import INPUT
from .target import roughness_from_log

MAX_REL_DIFF = 0.1  # int8 V may differ from fp32 V by at most 10% on the check textures


class QuantizationError(RuntimeError):
    """The int8 graph strays too far from the fp32 one."""


def quantize(fp32_path: str | Path, out: str | Path, calibration: int = 64, check: int = 32,
             overwrite: bool = False) -> dict:
    """Write the int8 model and return the checks' numbers; nothing is written if the check fails.

    ``out`` must not exist unless ``overwrite``.
    """
    from onnxruntime.quantization import (
        CalibrationDataReader,
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
        quantize_static(str(pre), str(q), Reader(), quant_format=QuantFormat.QDQ, per_channel=True,
                        activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8)
        v32 = roughness_from_log(_run(fp32_path, held), fp32_meta.log_offset)
        v8 = roughness_from_log(_run(q, held), fp32_meta.log_offset)
        rel = np.abs(v8 - v32) / np.maximum(v32, 1e-6)
        report = {"median_rel_diff_vs_fp32": float(np.median(rel)), "max_rel_diff_vs_fp32": float(rel.max()),
                  "checked_inputs": len(held), "calibration_inputs": len(calib)}
        if not report["max_rel_diff_vs_fp32"] < MAX_REL_DIFF:
            raise QuantizationError(f"int8 V differs from fp32 by up to {100 * rel.max():.1f}% "
                                    f"(limit {100 * MAX_REL_DIFF:.0f}%)")
        graph = onnx.load(str(q))
        if any(node.op_type in ("ConvInteger", "MatMulInteger") for node in graph.graph.node):
            raise QuantizationError("the int8 graph has ConvInteger/MatMulInteger nodes (dynamic quantisation)")
        del graph.metadata_props[:]
        graph.metadata_props.add(key=METADATA_KEY, value=replace(fp32_meta, int8=report).to_json())
        atomic_write(out, lambda path: onnx.save(graph, path))
    return report | {"path": str(out), "bytes": out.stat().st_size}


def _run(path: str | Path, patches: np.ndarray) -> np.ndarray:
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    return session.run([OUTPUTS[0]], {INPUT: patches})[0].astype(float)
