"""The Python API checks its arguments as the command line checks its options and files (issue 46).

A sweep over every public function: each bad argument of every kind (wrong types, bools for numbers, floats for
integers, NaN and infinities, out-of-range and absurd numbers, arrays of the wrong shape or dtype, masked arrays,
nested lists, maps in metres or micrometres, too many pixels or positions, unknown choices) must raise an
``InputError`` whose ``parameter`` is the Python parameter at fault and whose message says what is wrong, before
any engine runs: the engines are replaced by tripwires (as ``conftest._tripwires`` does for the command line).
Beside the sweep, what arguments that look odd but are good give: a nested list, a masked array without masked
points, filled missing points, numbers confirmed as mm.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

import roughness
from roughness.core.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
PERCEPTION = ROOT / "examples" / "perception"
TEXTURE = roughness.standard_texture(1.0)  # 240 x 240 px of 0.05 mm, bumps 1 mm tall
HEIGHTS = np.asarray(TEXTURE.heights)
DIAGONAL = np.eye(240, dtype=bool)
PICTURE = np.zeros((30, 40, 3), np.uint8)
PICTURE[:, 20:] = 255  # two flat colours
NAN, INF = math.nan, math.inf


def _tripped(*args, **kwargs):
    raise AssertionError("a bad argument reached an engine")


@pytest.fixture()
def tripwires(monkeypatch):
    """Every engine (FEM mesh and solve, spectral solve and its Dask workers, the surrogate's network, the SDP of
    an embedding, stimulus values) replaced by a tripwire."""
    import roughness.perception.embed
    import roughness.perception.values
    import roughness.simulate.model
    import roughness.simulate.prepared
    import roughness.simulate.spectral.distributed
    import roughness.simulate.spectral.maps
    from roughness.surrogate.predictor import SurrogateModel

    for owner, name in ((roughness.simulate.model.Simulator, "solve"), (roughness.simulate.model.Simulator, "block"),
                        (roughness.simulate.model, "estimated"), (roughness.simulate.prepared, "simulate"),
                        (roughness.simulate.spectral.maps, "solve"),
                        (roughness.simulate.spectral.distributed, "dask_runner"), (SurrogateModel, "evaluate"),
                        (roughness.perception.embed.TripletSDP, "solve"),
                        (roughness.perception.values, "stimulus_values")):
        monkeypatch.setattr(owner, name, _tripped)


def _refused(call, parameter: str, message: str) -> InputError:
    with pytest.raises(InputError) as err:
        call()
    assert err.value.parameter == parameter, (err.value.parameter, str(err.value))
    assert re.search(message, str(err.value)), str(err.value)
    return err.value


# Bad heightmaps: (value, the parameter at fault if not the function's own, what the message says).
BAD_MAPS = {
    "None": (None, None, "2-D array"),
    "number": (3.0, None, "2-D array"),
    "object": (object(), None, "2-D array"),
    "bool": (True, None, "2-D array"),
    "dict": ({"a": 1}, None, "2-D array"),
    "1-D": (np.zeros(40), None, "must be 2-D"),
    "3-D": (np.zeros((2, 40, 40)), None, "must be 2-D"),
    "nested 1-D": ([1.0, 2.0, 3.0], None, "must be 2-D"),
    "empty": (np.zeros((0, 0)), None, "empty"),
    "one row": (np.zeros((1, 40)), None, "at least 2 pixels"),
    "object dtype": (HEIGHTS.astype(object), None, "real numbers"),
    "complex": (HEIGHTS.astype(complex), None, "real numbers"),
    "strings": (HEIGHTS.astype(str), None, "real numbers"),
    "bools": (HEIGHTS > 0.5, None, "real numbers"),
    "ragged rows": ([[0.0, 1.0], [0.0]], None, "2-D array of heights"),
    "NaN": (np.where(DIAGONAL, NAN, HEIGHTS), None, "240 NaN/Inf pixel.*missing data.*fill=True"),
    "masked": (np.ma.masked_array(HEIGHTS, mask=DIAGONAL), None, "240 NaN/Inf pixel.*missing data.*fill=True"),
    "inf": (np.where(DIAGONAL, INF, HEIGHTS), None, "240 NaN/Inf pixel.*infinite height"),
    "1e300": (HEIGHTS * 1e300, None, "MAX_HEIGHT_MM"),
    "too many pixels": (np.broadcast_to(np.float64(0), (20_000, 20_000)), None, "MAX_HEIGHTMAP_PIXELS"),
    "metres": (HEIGHTS / 1000, "units_ok", "heights in metres"),
    "micrometres": (HEIGHTS * 500, "units_ok", "heights in micrometres"),
    "48 mm relief": (HEIGHTS * 48, "units_ok", "relief 48 mm is above 20 mm"),
}
# Each public function that takes a heightmap, called with heights and a pixel size; the names of both parameters.
MAP_CALLS = {
    "predict": (lambda v, px: roughness.predict(v, engine="fem", pixel_mm=px), "inputs", "pixel_mm"),
    "predict spectral": (lambda v, px: roughness.predict(v, engine="spectral", pixel_mm=px), "inputs", "pixel_mm"),
    "predict_map": (lambda v, px: roughness.predict_map(v, "spectral", pixel_mm=px, workers=2), "heightmap",
                    "pixel_mm"),
    "fem_roughness": (lambda v, px: roughness.fem_roughness(v, pixel_mm=px), "heightmap", "pixel_mm"),
    "tune": (lambda v, px: roughness.tune(v, pixel_mm=px, target_v=0.1), "heightmap", "pixel_mm"),
    "tune like": (lambda v, px: roughness.tune(TEXTURE, like=v, pixel_mm=px), "like", "pixel_mm"),
    "homogeneity": (lambda v, px: roughness.homogeneity(v, pixel_mm=px), "heightmap", "pixel_mm"),
    "palette": (lambda v, px: roughness.palette(2, candidates={"a": v, "b": TEXTURE}, pixel_mm=px), "candidates",
                "pixel_mm"),
    "tactile_image": (lambda v, px: roughness.tactile_image(PICTURE, [v, HEIGHTS], texture_pixel_mm=px, size_mm=30),
                      "textures", "texture_pixel_mm"),
}
BAD_PIXELS = [("0.05", "positive finite"), (True, "positive finite"), (NAN, "positive finite"),
              (INF, "positive finite"), (-0.05, "positive finite"), (0, "positive finite"), ([0.05], "positive finite"),
              (1e-300, "MIN_PIXEL_MM"), (None, "without a pixel size")]


@pytest.mark.parametrize("call, value, parameter, message", [
    pytest.param(call, value, parameter or own, message, id=f"{name}-{case}")
    for name, (call, own, _) in MAP_CALLS.items() for case, (value, parameter, message) in BAD_MAPS.items()
    if (name, case) != ("tune like", "None")])  # like=None: no reference texture
def test_every_heightmap_argument_is_checked_before_any_engine(tripwires, call, value, parameter, message):
    _refused(lambda: call(value, 0.05), parameter, message)


@pytest.mark.parametrize("call, parameter, value, message", [
    pytest.param(call, parameter, value, message, id=f"{name}-{value!r}")
    for name, (call, _, parameter) in MAP_CALLS.items() for value, message in BAD_PIXELS])
def test_every_pixel_size_is_checked_before_any_engine(tripwires, call, parameter, value, message):
    _refused(lambda: call(HEIGHTS, value), parameter, message)


@pytest.mark.parametrize("case", [case for case, (_, parameter, _) in BAD_MAPS.items() if parameter is None])
def test_heightmaps_name_their_heights(case):
    """``as_heightmap`` and the ``Heightmap`` constructor refuse the same heights; a Heightmap is a container,
    so numbers in metres are the caller's to check (every function that computes with it does)."""
    value, _, message = BAD_MAPS[case]
    _refused(lambda: roughness.as_heightmap(value, 0.05), "heights", message)
    _refused(lambda: roughness.Heightmap(value, 0.05), "heights", "^heightmap ")


def _small(n: int = 100) -> roughness.Heightmap:
    """A patch cut from the texture: 5 mm, 4 feature lengths, its heights jumping across the wrap (not a tile)."""
    return roughness.Heightmap(HEIGHTS[:n, :n], 0.05)


P, M, F = roughness.PredictOptions, roughness.predict_map, roughness.fem_roughness
CB = roughness.CurvedBase
# (call, parameter, what the message says): one bad argument each, the others good.
CASES = {
    "predict": [
        *[(lambda v=v: roughness.predict(TEXTURE, engine=v), "engine", "unknown engine")
          for v in (3, None, "FEM", ["auto"])],
        *[(lambda v=v: roughness.predict(TEXTURE, engine="surrogate", model=v), "model", "file path")
          for v in (3, object())],
        (lambda: roughness.predict(TEXTURE, engine="surrogate", model="missing.onnx"), "model", "not found"),
        *[(lambda v=v: roughness.predict(TEXTURE, options=v), "options", "PredictOptions")
          for v in ({"tile": True}, "tile", 3)],
        (lambda: roughness.predict(TEXTURE, on_result=3), "on_result", "function"),
        *[(lambda v=v: roughness.predict(TEXTURE, units_ok=v), "units_ok", "True or False") for v in ("yes", 1, None)],
        *[(lambda v=v: roughness.predict(TEXTURE, options=P(centre_mm=v)), "centre_mm", "two numbers")
          for v in ("ab", (1.0,), 5.0, (True, 1.0), ("1", "2"))],
        *[(lambda v=v: roughness.predict(TEXTURE, options=P(centre_mm=v)), "centre_mm", "finite")
          for v in ((NAN, 5.0), (INF, 5.0))],
        (lambda: roughness.predict(TEXTURE, options=P(centre_mm=(1e300, 0.0))), "centre_mm", "MAX_COORDINATE_MM"),
        (lambda: roughness.predict(TEXTURE, options=P(centre_mm=(1.0, 1.0))), "centre_mm", "extends beyond"),
        *[(lambda v=v: roughness.predict(TEXTURE, options=P(tile=v)), "tile", "True or False")
          for v in ("yes", 2, None)],
        *[(lambda v=v: roughness.predict(TEXTURE, options=P(fidelity=v)), "fidelity", "unknown fidelity")
          for v in ("ultra", 3)],
        *[(lambda v=v: roughness.predict(TEXTURE, options=P(tolerance=v)), "tolerance", "tolerance must be")
          for v in (-1, NAN, "x", 2, True)],
        *[(lambda v=v: roughness.predict(TEXTURE, options=P(max_std=v)), "max_std", "positive finite")
          for v in (NAN, -1, "x", True)],
        *[(lambda v=v: roughness.predict(TEXTURE, options=P(batch_size=v)), "batch_size", "integer")
          for v in (2.5, True, 0, "8")],
        (lambda: roughness.predict(TEXTURE, options=P(batch_size=10**9)), "batch_size", "MAX_BATCH"),
        *[(lambda v=v: roughness.predict(TEXTURE, options=P(curved=v)), "curved", "CurvedBase") for v in ("x", 3)],
        *[(lambda v=v: roughness.predict(TEXTURE, options=P(curved=CB(v))), "radius_mm", "radius")
          for v in ("x", 0, NAN, True)],
        (lambda: roughness.predict(TEXTURE, options=P(curved=CB(50.0, "cone"))), "shape", "unknown shape"),
        (lambda: roughness.predict(TEXTURE, options=P(curved=CB(50.0, axis="z"))), "axis", "unknown axis"),
        (lambda: roughness.predict(TEXTURE, options=P(curved=CB(50.0, texture_along="x"))), "texture_along",
         "unknown texture_along"),
        (lambda: roughness.predict(TEXTURE, engine="fem", options=P(curved=CB(0.1))), "curved", "edge, not a curved"),
        (lambda: roughness.predict(TEXTURE, engine="spectral", options=P(curved=CB(50.0))), "curved", "flat skin"),
        *[(lambda e=e: roughness.predict(_small(), engine=e), "tile", "smaller than the 10.0 mm x 10.0 mm")
          for e in ("surrogate", "spectral", "fem", "auto")],
        (lambda: roughness.predict(_small(), options=P(tile=True)), "tile", "too small to tile"),
    ],
    "predict_map": [
        *[(lambda v=v: M(TEXTURE, v), "engine", "engine is one of") for v in (3, "fem", None)],
        *[(lambda v=v: M(TEXTURE, "spectral", v, workers=2), "step_mm", "positive finite")
          for v in ("1", True, NAN, -1, 0)],
        (lambda: M(TEXTURE, "spectral", 1e-6, workers=2), "step_mm", "MAX_MAP_POSITIONS"),
        (lambda: M(TEXTURE, "surrogate", 1e-6), "step_mm", "MAX_MAP_POSITIONS"),
        (lambda: M(TEXTURE, "spectral", tile="yes"), "tile", "True or False"),
        *[(lambda v=v: M(TEXTURE, batch_size=v), "batch_size", "integer") for v in (2.5, True, 0)],
        (lambda: M(TEXTURE, batch_size=10**9), "batch_size", "MAX_BATCH"),
        *[(lambda v=v: M(TEXTURE, "spectral", workers=v), "workers", "integer") for v in (2.5, True, 0)],
        (lambda: M(TEXTURE, "spectral", workers=10**6), "workers", "MAX_PARALLEL"),
        (lambda: M(TEXTURE, progress=3), "progress", "function"),
        (lambda: M(TEXTURE, "spectral", quiet="x"), "quiet", "True or False"),
        (lambda: M(TEXTURE, units_ok="x"), "units_ok", "True or False"),
        (lambda: M(TEXTURE, model=3), "model", "file path"),
        (lambda: M(TEXTURE, "spectral", model="roughness-cnn.onnx"), "model", "no surrogate model"),
        (lambda: M(TEXTURE, "spectral", scheduler=3), "scheduler", "address"),
        (lambda: M(TEXTURE, "spectral", scheduler_file=3), "scheduler_file", "file path"),
        (lambda: M(TEXTURE, "spectral", scheduler_file="missing.json"), "scheduler_file", "does not exist"),
        (lambda: M(_small(), "spectral", workers=2), "tile", "smaller than"),
        (lambda: M(_small(), "spectral", tile=True, workers=2), "tile", "too small to tile"),
    ],
    "fem_roughness": [
        *[(lambda v=v: F(TEXTURE, centre_mm=v), "centre_mm", "two") for v in ("ab", (NAN, 0.0), 5.0)],
        (lambda: F(TEXTURE, tile="yes"), "tile", "True or False"),
        *[(lambda v=v: F(TEXTURE, simulator=v), "simulator", "Simulator") for v in (3, "x")],
        *[(lambda v=v: F(TEXTURE, force_n=v), "force_n", "positive finite") for v in ("x", -1, NAN, True)],
        *[(lambda v=v: F(TEXTURE, fidelity=v), "fidelity", "fidelity must be one of") for v in (3, "ultra")],
        *[(lambda v=v: F(TEXTURE, pairs=v), "pairs", "integer") for v in (2.5, True)],
        *[(lambda v=v: F(TEXTURE, seed=v), "seed", "integer") for v in (-1, 2.5)],
        (lambda: F(TEXTURE, poisson="x"), "poisson", "finite number"),
        (lambda: F(TEXTURE, colour=1), "colour", "not a simulation parameter"),
        (lambda: F(TEXTURE, estimate_error="x"), "estimate_error", "True or False"),
        (lambda: F(TEXTURE, callback=3), "callback", "function"),
        (lambda: F(TEXTURE, units_ok="x"), "units_ok", "True or False"),
        (lambda: F(_small()), "tile", "smaller than"),
        *[(lambda v=v: roughness.Simulator(config=v), "config", "SimConfig") for v in ("x", {})],
        *[(lambda v=v: roughness.Simulator(max_blocks=v), "max_blocks", "integer") for v in (0, 2.5)],
        (lambda: roughness.Simulator(cache="x"), "cache", "True or False"),
        (lambda: roughness.Simulator().run(TEXTURE, colour=1), "colour", "not a simulation parameter"),
        (lambda: roughness.SimConfig(poisson="x"), "poisson", "finite number"),
    ],
    "textures": [
        *[(lambda v=v: roughness.standard_texture(v), "lambda_mm", "lambda_mm") for v in ("1", None, NAN, True, 0.9)],
        *[(lambda v=v: roughness.standard_texture(1.0, seed=v), "seed", "integer") for v in (-1, 2.5, True, "0")],
        (lambda: roughness.standard_texture(1.0, top="flat"), "top", "sets top='cap'"),
        (lambda: roughness.standard_texture(1.0, colour=1), "colour", "not a bump texture parameter"),
        (lambda: roughness.standard_texture(1.0, size_mm=1e300), "size_mm", "MAX_HEIGHTMAP_PIXELS"),
        (lambda: roughness.standard_texture(1.0, size_mm="x"), "size_mm", "positive finite"),
        (lambda: roughness.standard_texture(1.0, pixel_mm=1e-300), "pixel_mm", "MIN_PIXEL_MM"),
        (lambda: roughness.standard_texture(1.0, height_mm=-1), "height_mm", "positive finite"),
        (lambda: roughness.standard_texture(1.0, height_mm=1e300), "height_mm", "MAX_HEIGHT_MM"),
        *[(lambda v=v: roughness.named_texture(v), "name", "unknown texture") for v in (3, None, "nope")],
        *[(lambda v=v, n=n: roughness.named_texture(n, seed=v), "seed", "integer")
          for v in (-1, "x") for n in ("standard-1.0", "flat")],
        *[(lambda v=v: roughness.open_dataset(v), "path", "file path") for v in (3, None)],
        (lambda: roughness.open_dataset("missing.h5"), "path", "no dataset file"),
        *[(lambda v=v: roughness.load_scale(v), "fidelity", "fidelity") for v in ("ultra", 3, None)],
        (lambda: roughness.load_scale("fine", path="missing.json"), "path", "no standard-scale file"),
        (lambda: roughness.load_scale("fine", path=3), "path", "file path"),
    ],
    "tune": [
        *[(lambda v=v: roughness.tune(TEXTURE, target_lambda_mm=v), "target_lambda_mm", "positive finite")
          for v in ("x", NAN, -1, True)],
        (lambda: roughness.tune(TEXTURE, target_lambda_mm=1e300), "target_lambda_mm", "power law"),
        *[(lambda v=v: roughness.tune(TEXTURE, target_v=v), "target_v", "positive finite") for v in ("x", NAN, -1)],
        *[(lambda v=v: roughness.tune(TEXTURE, jnd=v), "jnd", "jnd must be") for v in ("x", NAN, 1e300)],
        (lambda: roughness.tune(TEXTURE, target_lambda_mm=1.0, target_v=0.1), "target_v", "exactly one target"),
        *[(lambda v=v: roughness.tune(TEXTURE, target_v=0.1, by=v), "by", "unknown by") for v in (3, "x")],
        *[(lambda v=v: roughness.tune(TEXTURE, target_v=0.1, factor_range=v), "factor_range", "factor")
          for v in ("x", (1,), (2, 1), (NAN, 2), (-1, 2), 3, ("a", "b"))],
        *[(lambda v=v: roughness.tune(TEXTURE, target_v=0.1, tolerance_jnd=v), "tolerance_jnd", "positive finite")
          for v in (NAN, -1, "x")],
        *[(lambda v=v: roughness.tune(TEXTURE, target_v=0.1, max_fem=v), "max_fem", "integer")
          for v in (2.5, 0, True, "3")],
        (lambda: roughness.tune(TEXTURE, target_v=0.1, tile="yes"), "tile", "True or False"),
        *[(lambda v=v: roughness.tune(TEXTURE, target_v=0.1, verify=v), "verify", "unknown verify")
          for v in (3, "ultra")],
        (lambda: roughness.tune(TEXTURE, target_v=0.1, model=3), "model", "file path"),
        (lambda: roughness.tune(TEXTURE, target_v=0.1, model="missing.onnx"), "model", "not found"),
        (lambda: roughness.tune(HEIGHTS, pixel_mm=0.05, height_mm=1.0, target_v=0.1), "height_mm", "image files"),
        (lambda: roughness.tune(TEXTURE, target_v=0.1, units_ok="x"), "units_ok", "True or False"),
    ],
    "homogeneity": [
        *[(lambda v=v: roughness.homogeneity(TEXTURE, engine=v), "engine", "unknown engine") for v in (3, "x")],
        *[(lambda v=v: roughness.homogeneity(TEXTURE, window_mm=v), "window_mm", "window_mm")
          for v in ("x", NAN, -1, 0.01)],
        *[(lambda v=v: roughness.homogeneity(TEXTURE, n=v), "n", "n must be") for v in (2.5, True, 0, "8")],
        (lambda: roughness.homogeneity(TEXTURE, n=10**9), "n", "MAX_WINDOWS"),
        *[(lambda v=v: roughness.homogeneity(TEXTURE, seed=v), "seed", "integer") for v in (-1, 2.5, "x")],
        (lambda: roughness.homogeneity(TEXTURE, tile="yes"), "tile", "True or False"),
        (lambda: roughness.homogeneity(TEXTURE, model=3), "model", "file path"),
        (lambda: roughness.homogeneity(HEIGHTS, pixel_mm=0.05, height_mm=1.0), "height_mm", "image files"),
    ],
    "palette": [
        *[(lambda v=v: roughness.palette(v), "k", "integer") for v in (2.5, True, 1, "3")],
        *[(lambda v=v: roughness.palette(2, min_jnd=v), "min_jnd", "positive finite") for v in ("x", NAN, -1)],
        *[(lambda v=v: roughness.palette(2, family=v), "family", "unknown family") for v in (3, "nope", "bumps")],
        *[(lambda v=v: roughness.palette(2, by=v), "by", "unknown by") for v in (3, "x")],
        *[(lambda v=v: roughness.palette(2, candidates=v), "candidates", "folder of heightmaps or a mapping")
          for v in (3, [TEXTURE])],
        (lambda: roughness.palette(2, candidates="missing_folder"), "candidates", "does not exist"),
        *[(lambda v=v: roughness.palette(2, tolerance_jnd=v), "tolerance_jnd", "positive finite") for v in (NAN, -1)],
        *[(lambda v=v: roughness.palette(2, seed=v), "seed", "integer") for v in (-1, 2.5)],
        (lambda: roughness.palette(2, tile="yes"), "tile", "True or False"),
        *[(lambda v=v: roughness.palette(2, verify=v), "verify", "unknown verify") for v in (3, "ultra")],
        (lambda: roughness.palette(2, model=3), "model", "file path"),
        (lambda: roughness.palette(2, pixel_mm="x"), "pixel_mm", "positive finite"),
    ],
    "tactile_image": [
        *[(lambda v=v: roughness.tactile_image(v, [HEIGHTS, HEIGHTS], texture_pixel_mm=0.05), "picture", "picture")
          for v in (None, 3, np.zeros((5, 5, 4)), np.full((5, 5), NAN), [[0, 1], [1]],
                    np.ma.masked_array(PICTURE, mask=np.ones(PICTURE.shape, bool)))],
        (lambda: roughness.tactile_image("missing.png", [HEIGHTS, HEIGHTS], texture_pixel_mm=0.05), "picture",
         "not found"),
        (lambda: roughness.tactile_image(np.zeros((30, 40)), [HEIGHTS, HEIGHTS], texture_pixel_mm=0.05), "picture",
         "fewer than 2 flat colours"),
        *[(lambda v=v: roughness.tactile_image(PICTURE, v), "textures", "palette folder or a list") for v in (3, {})],
        (lambda: roughness.tactile_image(PICTURE, "missing_folder"), "textures", "not a palette folder"),
        (lambda: roughness.tactile_image(PICTURE, [3, 3], texture_pixel_mm=0.05), "textures", "2-D array"),
        *[(lambda v=v: roughness.tactile_image(PICTURE, k=v), "k", "integer") for v in (2.5, True, 1)],
        (lambda: roughness.tactile_image(PICTURE, [HEIGHTS, HEIGHTS], k=2, texture_pixel_mm=0.05), "k", "not both"),
        *[(lambda v=v: roughness.tactile_image(PICTURE, min_jnd=v), "min_jnd", "positive finite") for v in ("x", NAN)],
        *[(lambda v=v: roughness.tactile_image(PICTURE, family=v), "family", "unknown family") for v in (3, "nope")],
        *[(lambda v=v: roughness.tactile_image(PICTURE, size_mm=v), "size_mm", "positive finite")
          for v in ("x", NAN, -1)],
        (lambda: roughness.tactile_image(PICTURE, size_mm=1e300), "size_mm", "MAX_PLATE_PIXELS"),
        *[(lambda v=v: roughness.tactile_image(PICTURE, pixel_mm=v), "pixel_mm", "positive finite") for v in ("x", -1)],
        (lambda: roughness.tactile_image(PICTURE, pixel_mm=1e-300), "pixel_mm", "MIN_PIXEL_MM"),
        *[(lambda v=v: roughness.tactile_image(PICTURE, [HEIGHTS, HEIGHTS], texture_pixel_mm=v), "texture_pixel_mm",
           "positive finite") for v in ("x", -1)],
        *[(lambda v=v: roughness.tactile_image(PICTURE, outline_mm=v), "outline_mm", "positive finite")
          for v in ("x", -1, NAN)],
        *[(lambda v=v: roughness.tactile_image(PICTURE, outline_height_mm=v), "outline_height_mm", "finite number")
          for v in ("x", NAN)],
        *[(lambda v=v: roughness.tactile_image(PICTURE, step_mm=v), "step_mm", "positive finite") for v in ("x", -1)],
        (lambda: roughness.tactile_image(PICTURE, step_mm=1e-6), "step_mm", "MAX_MAP_POSITIONS"),
        (lambda: roughness.tactile_image(PICTURE, strain="x"), "strain", "True or False"),
        *[(lambda v=v: roughness.tactile_image(PICTURE, colour_tolerance=v), "colour_tolerance", "positive finite")
          for v in ("x", -1, NAN)],
        (lambda: roughness.tactile_image(PICTURE, verify=3), "verify", "unknown verify"),
        (lambda: roughness.tactile_image(PICTURE, model=3), "model", "file path"),
    ],
    "embed_trials": [
        *[(lambda v=v: roughness.embed_trials(v), "trials", "file path") for v in (None, 3)],
        (lambda: roughness.embed_trials("missing.csv"), "trials", "not found"),
        (lambda: roughness.embed_trials(PERCEPTION / "simulated" / "trials.csv", 3), "stimuli", "file path"),
        (lambda: roughness.embed_trials(PERCEPTION / "simulated" / "trials.csv", "missing.csv"), "stimuli",
         "not found"),
        *[(lambda name=name, v=v: roughness.embed_trials(PERCEPTION / "simulated" / "trials.csv", **{name: v}), name,
           message) for name, values, message in (
            ("lam", ("x", NAN, -1, True), "lam must be"), ("folds", (2.5, True, 1), "integer"),
            ("resamples", (-1, 2.5, True), "integer"), ("seed", (-1, 2.5, "x"), "integer"),
            ("workers", (0, 2.5), "integer"), ("workers", (10**6,), "MAX_PARALLEL"),
            ("roughest", (3,), "stimulus id"), ("roughest", ("nope",), "not among"),
            ("scale", (3, "x"), "scale"), ("lapse", (NAN, -1, 2, "x"), "lapse must be"),
            ("repeats", (3, "x"), "repeats must be")) for v in values],
    ],
    "fit_embedding": [
        *[(lambda v=v: roughness.fit_embedding(v, PERCEPTION / "stimuli.csv"), "embedding", "embedding")
          for v in (None, 3, "missing.csv")],
        *[(lambda v=v: roughness.fit_embedding(PERCEPTION / "embedding" / "embedding.csv", v), "stimuli", message)
          for v, message in ((None, "file path"), (3, "file path"), ("missing.csv", "not found"))],
        *[(lambda name=name, v=v: roughness.fit_embedding(PERCEPTION / "embedding" / "embedding.csv",
                                                          PERCEPTION / "stimuli.csv", **{name: v}), name, message)
          for name, values, message in (
            ("engine", (3, "x"), "unknown engine"), ("exclude", ("standard-1.0", 3, [3]), "list of stimulus ids"),
            ("exclude", (["nope"],), "not in the embedding"), ("cache", (3,), "file path")) for v in values],
    ],
}


@pytest.mark.parametrize("call, parameter, message", [
    pytest.param(call, parameter, message, id=f"{group}-{parameter}-{i}")
    for group, cases in CASES.items() for i, (call, parameter, message) in enumerate(cases)])
def test_every_bad_argument_is_an_input_error_naming_its_parameter(tripwires, call, parameter, message):
    _refused(call, parameter, message)


def test_a_nested_list_is_one_map_and_a_list_of_arrays_several():
    [from_array] = roughness.predict(HEIGHTS, pixel_mm=0.05, engine="surrogate")
    [from_list] = roughness.predict(HEIGHTS.tolist(), pixel_mm=0.05, engine="surrogate")
    assert from_list.roughness == from_array.roughness and from_list.source == "heightmap 0"
    nested = tuple(tuple(row) for row in HEIGHTS.tolist())
    assert np.array_equal(roughness.as_heightmap(nested, 0.05).heights, HEIGHTS)
    several = roughness.predict([HEIGHTS, HEIGHTS.tolist()], pixel_mm=0.05, engine="surrogate")
    assert [p.roughness for p in several] == [from_array.roughness] * 2


def test_masked_points_are_missing_data_filled_only_when_asked():
    masked = np.ma.masked_array(HEIGHTS, mask=DIAGONAL)
    nothing_masked = np.ma.masked_array(HEIGHTS, mask=np.zeros_like(DIAGONAL))
    assert np.array_equal(roughness.as_heightmap(nothing_masked, 0.05).heights, HEIGHTS)  # a mask of False hides none
    filled = roughness.as_heightmap(masked, 0.05, fill=True)
    from_nan = roughness.as_heightmap(np.where(DIAGONAL, NAN, HEIGHTS), 0.05, fill=True)
    assert np.array_equal(filled.heights, from_nan.heights)  # a masked point is a NaN: missing
    assert np.array_equal(filled.heights[~DIAGONAL], HEIGHTS[~DIAGONAL])  # measured points untouched
    # harmonic interpolation obeys the maximum principle: within the range of the measured heights around the holes
    assert HEIGHTS.min() <= filled.heights[DIAGONAL].min() and filled.heights[DIAGONAL].max() <= HEIGHTS.max()
    mostly = np.ma.masked_array(HEIGHTS, mask=np.arange(HEIGHTS.size).reshape(HEIGHTS.shape) % 2 == 0)
    _refused(lambda: roughness.as_heightmap(mostly, 0.05, fill=True), "max_fill", "50.00% of the map is missing")
    [p] = roughness.predict(filled, engine="surrogate")
    assert np.isfinite(p.roughness)


def test_numbers_confirmed_as_mm_are_answered():
    """``units_ok=True`` takes implausible numbers as mm (a polished sample with microns of relief) and answers."""
    smooth = HEIGHTS / 1000
    error = _refused(lambda: roughness.predict(smooth, pixel_mm=0.05, engine="surrogate"), "units_ok",
                     "heightmap 0: relief 0.001 mm is below 0.005 mm")
    assert "pass units_ok" in str(error)
    [p] = roughness.predict(smooth, pixel_mm=0.05, engine="surrogate", units_ok=True)
    [q] = roughness.predict({"polished": roughness.Heightmap(smooth, 0.05)}, engine="surrogate", units_ok=True)
    assert p.roughness == q.roughness and np.isfinite(p.roughness) and q.source == "polished"
    hm = roughness.homogeneity(smooth, pixel_mm=0.05, n=4, units_ok=True)
    assert len(hm.roughness) == 4


def test_predict_options_check_themselves_where_they_are_made():
    """The error comes from the constructor, before any ``predict``: a bad option never waits for an engine."""
    with pytest.raises(InputError) as err:
        roughness.PredictOptions(tile="yes")
    assert err.value.parameter == "tile"
    with pytest.raises(InputError) as err:
        roughness.CurvedBase(0.0)
    assert err.value.parameter == "radius_mm"
    assert roughness.PredictOptions(tile=np.bool_(True), centre_mm=np.array([6.0, 6.0])).tile  # NumPy values are fine
