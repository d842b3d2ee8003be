"""Near-zero roughness: the standard scale's floor, JND distances at zero, and strict JSON from every command.

A V below the floor (the power law's V at the shortest standard-like bump wavelength, 0.2 mm) is
"below the scale": no equivalent wavelength, no JND, instead of microns and -68 JND. Every ``--json``
output of the CLI (subcommands found from the parser) is parsed by a strict JSON parser on a flat map
and on a 1 um relief, and the answers are checked for sense.
"""
from __future__ import annotations

import json
import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

from roughness.cli import main
from roughness.dataset.grid import PIXEL_MM
from roughness.dataset.textures import MIN_PIXELS_PER_LAMBDA, standard_texture
from roughness.design.homogeneity import homogeneity
from roughness.perceptual_scale import FLOOR_LAMBDA_MM, StandardScale, jnd_distance, load_scale
from roughness.surface.heightmap import Heightmap
from test_bad_inputs import PARSERS

SCALE = StandardScale((0.5, 1.0, 2.0), (0.025, 0.1, 0.4), "test")  # V = 0.1 lambda^2: floor 0.1 * 0.2^2 = 0.004
STEP = math.log(1.19)
FLAT_SPREAD = 1e-4  # about the shipped ensemble's spread of V on a flat map


def strict_json(text: str):
    """json.loads that refuses NaN, Infinity and -Infinity (Python's parser accepts them by default)."""
    def refuse(name: str):
        raise ValueError(f"{name} is not JSON")

    return json.loads(text, parse_constant=refuse)


def test_json_text_writes_null_where_a_number_is_not_finite():
    from roughness.cli.common import json_text

    text = json_text({"a": math.nan, "b": [1.0, np.float64(math.inf)], "c": {"d": -math.inf}, "e": 2.5})
    assert strict_json(text) == {"a": None, "b": [1.0, None], "c": {"d": None}, "e": 2.5,
                                 "non_finite": ["a", "b[1]", "c.d"]}
    assert strict_json(json_text({"e": 2.5})) == {"e": 2.5}  # no note when all is finite


# ---- the floor -------------------------------------------------------------------------------------------------

def test_the_scale_is_continuous_and_rising_across_its_ends():
    """Beyond its ends the scale extrapolates from the end standards with the fitted exponent: no jump
    (the fitted law itself gave V 0.20-0.22 at the coarsest standard, whose table V is 0.185)."""
    for fidelity in ("coarse", "default", "fine", "spectral"):
        scale = load_scale(fidelity)
        for end in (0, -1):
            v = scale.roughness[end]
            for side in (1 - 1e-9, 1 + 1e-9):
                assert scale.equivalent_lambda(v * side)[0] == pytest.approx(scale.lambdas_mm[end], rel=1e-8)
        lams = np.geomspace(0.1, 5.0, 400)
        vs = np.array([scale.roughness_at(lam) for lam in lams])
        assert np.all(np.diff(vs) > 0)
        assert np.allclose([scale.equivalent_lambda(v)[0] for v in vs], lams, rtol=1e-9)


def test_floor_is_the_shortest_standard_bump_on_the_power_law():
    assert FLOOR_LAMBDA_MM == pytest.approx(MIN_PIXELS_PER_LAMBDA * PIXEL_MM)  # the texture generator's limit
    assert SCALE.floor == pytest.approx(0.004)
    for fidelity in ("coarse", "default", "fine"):
        scale = load_scale(fidelity)
        b = scale.power_law[1]  # the fitted exponent, from the finest standard down
        assert scale.floor == pytest.approx(scale.roughness[0] * (0.2 / scale.lambdas_mm[0]) ** b)
        # well below the finest standard (6.5 JND of lambda) and well above the engines' noise around zero
        assert 20 * FLAT_SPREAD < scale.floor < scale.roughness[0] / 5


def test_below_the_floor_is_not_placed():
    for v in (0.0, 1e-12, 0.0039):
        p = SCALE.place(v)
        assert p.below_scale and not p.on_scale and p.equivalent_lambda_mm is None and p.jnd_from_nearest is None
        assert p.nearest_standard == "standard-0.5"
        d = strict_json(json.dumps(p.as_dict(), allow_nan=False))
        assert d["below_scale"] and not d["extrapolated"] and d["scale_floor_roughness"] == pytest.approx(0.004)
        assert "below the standard scale" in p.describe()
    just_above = SCALE.place(0.004 * 1.0001)  # extrapolated down to the floor, placed
    assert not just_above.below_scale and not just_above.on_scale and just_above.as_dict()["extrapolated"]
    assert just_above.equivalent_lambda_mm == pytest.approx(0.2, rel=1e-4)
    assert SCALE.place(0.1).equivalent_lambda_mm == pytest.approx(1.0) and SCALE.place(0.1).on_scale
    for bad in (-0.1, math.nan, math.inf):
        with pytest.raises(ValueError):
            SCALE.place(bad)


# ---- JND distances at zero ---------------------------------------------------------------------------------------

def test_two_textures_below_the_scale_are_too_close_without_a_distance():
    d = jnd_distance(SCALE, 0.0, 0.001, FLAT_SPREAD, FLAT_SPREAD)
    assert d.jnd is None and d.jnd_stderr is None and d.verdict == "too close" and not d.lower_bound
    assert "both below" in d.note and d.as_dict()["below_scale"] == ["a", "b"]
    strict_json(json.dumps(d.as_dict(), allow_nan=False))


def test_smooth_against_rough_is_a_bounded_lower_bound():
    """Flat against lambda 1 mm: at least ln(1 / 0.2) / ln 1.19 = 9.3 JND, with an error carried in V."""
    d = jnd_distance(SCALE, 0.0, 0.1, FLAT_SPREAD, 0.004)
    assert d.jnd == pytest.approx(math.log(0.2 / 1.0) / STEP) and d.lower_bound and d.verdict == "tell apart"
    # se of ln(lambda) = se / (b max(V, floor)): the flat side's error is taken at the floor's slope, not se / 0
    assert d.jnd_stderr == pytest.approx(math.hypot(FLAT_SPREAD / 0.004, 0.004 / 0.1) / 2 / STEP)
    assert d.jnd_stderr < 0.2 and "A is below" in d.note
    # just above the floor: a quarter of a JND from a flat map, too close; the error stays finite at V = 0
    near = jnd_distance(SCALE, 0.004 * 1.19**0.5, 0.0, FLAT_SPREAD, FLAT_SPREAD)
    assert near.jnd == pytest.approx(0.25) and near.verdict == "too close" and math.isfinite(near.jnd_stderr)


def test_errors_in_v_still_make_a_verdict_borderline():
    """One JND above the floor against a flat map, with V known to +-30%: borderline, not 'tell apart'."""
    v = 0.004 * 1.19**2  # lambda 0.2 * 1.19: one JND above the floor
    d = jnd_distance(SCALE, v, 0.0, 0.3 * v, FLAT_SPREAD)
    assert d.jnd == pytest.approx(1.0) and d.verdict == "borderline"


def test_fem_prediction_at_zero_has_no_infinite_error(monkeypatch):
    """richardson() says inf when V is 0 at one mesh only; a prediction says null, with a note."""
    from roughness.engines import FemEngine
    from roughness.prediction import predict

    fake = SimpleNamespace(roughness=0.0, seconds=0.0, roughness_stderr=0.0, discretization_error=math.inf)
    monkeypatch.setattr(FemEngine, "simulate", lambda self, hm: fake)
    [p] = predict(Heightmap(np.zeros((240, 240)), 0.05), engine="fem")
    d = strict_json(json.dumps(p.as_dict(), allow_nan=False))
    assert d["discretization_error"] is None and d["below_scale"] and d["equivalent_lambda_mm"] is None
    assert any("discretization error undefined" in n for n in d["domain_notes"])


# ---- homogeneity at zero -----------------------------------------------------------------------------------------

class _Windows:
    """An evaluator stub: the test scale, a 10 mm footprint, and given window values for the surrogate."""

    footprint_mm = 10.0
    scale = SCALE

    def __init__(self, values):
        self.values = np.asarray(values, dtype=float)

    def surrogate(self, maps, tile=False, centres_mm=None):
        return self.values, np.ones(len(self.values), dtype=bool)


def test_homogeneity_of_nothing_is_one_verdict_with_no_ratio():
    plate = Heightmap(np.zeros((240, 240)), 0.05)
    flat = homogeneity(plate, n=5, evaluator=_Windows([0.0, 1e-6, 0.0, 2e-6, 0.0]))
    s = strict_json(json.dumps(flat.summary(), allow_nan=False))
    assert s["relative_variance"] is None and s["paper_verdict"] is None and s["spread_jnd"] is None
    assert s["verdict"] == "homogeneous" and s["below_scale_windows"] == 5 and "no roughness anywhere" in s["note"]
    # a plate half smooth, half rough: parts feel different (at least 9.3 JND), the ratio is defined
    half = homogeneity(plate, n=6, evaluator=_Windows([0.0, 0.1, 0.0, 0.1, 0.0, 0.1]))
    assert half.verdict == "inhomogeneous" and half.paper_verdict == "inhomogeneous" and half.below_scale == 3
    assert half.relative_variance == pytest.approx(np.var([0, 0.1] * 3, ddof=1) / 0.05**2)
    assert half.range_jnd == pytest.approx(math.log(1.0 / 0.2) / STEP) and "lower bound" in half.note


# ---- every --json command on near-zero inputs --------------------------------------------------------------------

JSON_COMMANDS = {path for path, parser in PARSERS.items()
                 if any("--json" in action.option_strings for action in parser._actions)}
MAP = ["--pixel-mm", "0.05"]


def _below(objects):
    for o in objects:
        assert o["below_scale"] is True and o["equivalent_lambda_mm"] is None and o["jnd_from_nearest"] is None


def _check_jnd_flat(objects):
    [o] = objects
    assert o["verdict"] == "too close" and o["jnd"] is None and o["jnd_stderr"] is None
    assert o["below_scale"] == ["a", "b"]


def _check_jnd_relief(objects):
    [o] = objects
    _below([o["a"]])
    assert o["verdict"] == "tell apart" and o["jnd_is_lower_bound"] and -20 < o["jnd"] <= -5 and o["jnd_stderr"] < 1


def _check_homogeneity(objects):
    [o] = objects
    assert o["relative_variance"] is None and o["paper_verdict"] is None and o["verdict"] == "homogeneous"
    assert o["below_scale_windows"] == o["windows"]


def _check_simulate(objects):
    """A flat map's V, with its relative discretization error made undefined (V 0 here, not at the coarser mesh)."""
    [o] = objects
    assert abs(o["roughness"]) < 1e-6 and o["discretization_error"] is None
    assert "discretization_error_undefined" in [n["code"] for n in o["notes"]]


def _check_object_feel(objects):
    """V 0 on the box's top: below the scale (no lambda), the JND from the reference a bound."""
    [o] = objects
    [row] = o["regions"]
    assert row["roughness_median"] == 0.0 and row["lambda_median_mm"] is None and row["below_scale_fraction"] == 1.0
    assert row["jnd_is_bound"] and row["jnd_median"] < 0


def _check_fuzzy_plain(objects):
    """Fuzzy skin of thickness 0: the plain wall, below the scale, with no wavelength range."""
    [o] = objects
    _below([o])
    assert o["equivalent_lambda_range_mm"] is None and o["roughness"] < 1e-3


# path -> [(arguments, expected exit code, check of the parsed stdout objects)]; exit 2: a clear refusal.
# The 1 um relief needs --units-ok: without it, it is refused as implausible for mm (tests/test_cleanup.py)
CASES = {
    ("predict",): [(["flat.npy", "relief.npy", *MAP, "--units-ok", "--engine", "surrogate", "--json"], 0, _below),
                   (["flat.npy", *MAP, "--map", "flat-map.npy", "--json"], 0, None)],
    ("jnd",): [(["flat.npy", "relief.npy", *MAP, "--units-ok", "--engine", "surrogate", "--json"], 0, _check_jnd_flat),
               (["relief.npy", "bumps.npy", *MAP, "--units-ok", "--engine", "surrogate", "--json"], 0,
                _check_jnd_relief)],
    ("homogeneity",): [(["flat.npy", *MAP, "--n", "5", "--json", "--quiet"], 0, _check_homogeneity),
                       (["relief.npy", *MAP, "--units-ok", "--n", "5", "--json", "--quiet"], 0, _check_homogeneity)],
    ("simulate",): [(["flat.npy", *MAP, "--fidelity", "coarse", "--json"], 0, _check_simulate)],  # one FEM, ~10 s
    ("tune",): [(["flat.npy", *MAP, "--target-lambda", "1.0", "--out", "t.npz", "--json", "--quiet"], 2, None),
                (["relief.npy", *MAP, "--units-ok", "--target-v", "0.001", "--out", "t.npz", "--json", "--quiet"], 2,
                 None)],
    ("palette",): [(["--k", "2", "--family", "flat", "--out", "pal", "--json", "--quiet"], 2, None)],
    ("tactile-image",): [(["picture.png", "--family", "flat", "--out", "plate", "--json", "--quiet"], 2, None)],
    ("dataset", "info"): [(["zero.h5", "--json"], 0, None)],
    # a flat texture on a 30 mm box: nothing displaced; the top's footprints below the scale; nothing to tune
    ("object", "texture"): [(["box.stl", "--texture", "flat.npy", *MAP, "--edge-mm", "3", "--out", "t.stl", "--json",
                              "--quiet"], 0, None)],
    ("object", "feel"): [(["box.stl", "--texture", "flat.npy", *MAP, "--region", "cone:0,0,1,10", "--spacing-mm", "10",
                           "--reference", "standard-1.0", "--json", "--quiet"], 0, _check_object_feel)],
    ("object", "tune"): [(["box.stl", "--texture", "flat.npy", *MAP, "--target-lambda", "1.0", "--out", "t.npz",
                           "--json", "--quiet"], 2, None)],
    ("fuzzy-skin",): [(["--fuzzy-skin-thickness", "0", "--engine", "surrogate", "--json", "--quiet"], 0,
                       _check_fuzzy_plain)],
    # a flat base: the skin touches all of it, so nothing can be hidden from touch (refused)
    ("hidden-shapes",): [(["--shape", "circle", "--texture", "flat.npy", *MAP, "--size-mm", "20", "--mode", "seen",
                           "--out", "plate", "--json", "--quiet"], 2, None)],
}


# the same cases without --json: what the text must say (and it never says nan or inf)
TEXT = {(("predict",), 0): ["below the standard scale"],
        (("jnd",), 0): ["distance: none", "both below the standard scale", "TOO CLOSE"],
        (("jnd",), 1): ["at least", "TELL APART"],
        (("homogeneity",), 0): ["HOMOGENEOUS", "no roughness anywhere"]}  # not simulate: one FEM run is enough


def test_every_json_command_is_swept():
    assert set(CASES) == JSON_COMMANDS


@pytest.fixture()
def near_zero(tmp_path, monkeypatch):
    """A flat map, a 1 um sinusoidal relief, 1 mm standard bumps, a three-colour picture, a dataset of V = 0."""
    x = np.arange(240) * 0.05
    np.save(tmp_path / "flat.npy", np.zeros((240, 240)))
    np.save(tmp_path / "relief.npy", 0.0005 * (1 + np.sin(2 * np.pi * x)[None, :] * np.sin(2 * np.pi * x)[:, None]))
    np.save(tmp_path / "bumps.npy", standard_texture(1.0).heights)
    import trimesh

    trimesh.creation.box((30.0, 30.0, 30.0)).export(tmp_path / "box.stl")
    from PIL import Image

    Image.fromarray(np.repeat(np.uint8([[0, 128, 255]]), 30, axis=0).repeat(3, axis=1)[..., None].repeat(3, axis=2)
                    ).save(tmp_path / "picture.png")
    from roughness.dataset.writer import DatasetWriter
    from test_store import CONFIG, fields, texture_record

    with DatasetWriter(tmp_path / "zero.h5", CONFIG, "test") as writer:
        for i in range(2):
            writer.write_result(texture_record(i), np.zeros((40, 40)), 0.05,
                                {**fields(i), "roughness": 0.0, "roughness_stderr": 0.0, "discretization_error": 0.0},
                                np.zeros((40, 40)))
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _run_case(path, argv, expected, capsys, monkeypatch) -> str:
    """Run one case; its stdout. Exit as expected, no traceback, a refusal (2) says why."""
    if path == ("simulate",):  # the FEM's V of a flat map is 0 or CG noise (1e-7): when 0 at one mesh only
        monkeypatch.setattr("roughness.simulate.converged.richardson", lambda *args: math.inf)
    try:
        code = main([*path, *argv])
    except SystemExit as exit_:
        code = exit_.code
    out, err = capsys.readouterr()
    assert code == expected, f"{path} {argv}: exit {code}, stderr: {err[-800:]}"
    assert "Traceback" not in err
    if code == 2:
        assert err.strip(), "a refusal names its reason"
    return out


CASE_IDS = [(p, i) for p, cases in CASES.items() for i in range(len(cases))]


@pytest.mark.parametrize("path, index", CASE_IDS, ids=lambda v: " ".join(v) if isinstance(v, tuple) else str(v))
def test_json_output_is_strict_and_sane_near_zero(path, index, near_zero, capsys, monkeypatch):
    argv, expected, check = CASES[path][index]
    out = _run_case(path, argv, expected, capsys, monkeypatch)
    objects = [strict_json(line) for line in out.splitlines() if line.strip()]
    assert objects or expected == 2, "an answer prints JSON"
    assert not any("non_finite" in o for o in objects), "undefined numbers are null with a note at their source"
    if check:
        check(objects)


@pytest.mark.parametrize("path, index", [c for c in CASE_IDS if c in TEXT],
                         ids=lambda v: " ".join(v) if isinstance(v, tuple) else str(v))
def test_text_output_says_below_the_scale(path, index, near_zero, capsys, monkeypatch):
    argv, expected, _ = CASES[path][index]
    out = _run_case(path, [a for a in argv if a != "--json"], expected, capsys, monkeypatch)
    assert not re.search(r"\b(nan|inf|infinity)\b", out, re.IGNORECASE), out
    assert "INHOMOGENEOUS" not in out.upper() or path != ("homogeneity",), out
    for phrase in TEXT[path, index]:
        assert phrase in out, out
