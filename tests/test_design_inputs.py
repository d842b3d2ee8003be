"""Real inputs to the design tools (issue 28): pictures with compression noise and anti-aliasing, relative targets.

Pictures are the bundled 3-colour picture saved as JPEG or resized with anti-aliasing (Pillow); the clustering
is tested directly (milliseconds) and the CLI once with the spectral verifier (seconds).
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.dataset.textures import standard_texture
from roughness.design.colours import TOLERANCE, cluster_colours, lab
from roughness.design.evaluation import Evaluator
from roughness.design.tactile_image import read_image
from roughness.design.tune import target_of, tune
from roughness.models import MODELS_DIR
from roughness.perceptual_scale import jnd
from roughness.surface.heightmap import Heightmap
from roughness.surface.io import save_heightmap
from test_bad_inputs import _expect_refusal

SHAPES = Path(__file__).resolve().parents[1] / "examples" / "design" / "shapes.png"
LUMA = np.array([0.299, 0.587, 0.114])


def _shapes() -> Image.Image:
    return Image.open(SHAPES).convert("RGB")


def _truth(size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """The bundled picture's 3 colours (lightest first) and each pixel's, resized without blending."""
    rgb = np.asarray(_shapes().resize(size, Image.NEAREST))
    colours = np.unique(rgb.reshape(-1, 3), axis=0)
    colours = colours[np.argsort(-(colours.astype(float) @ LUMA))]
    labels = np.argmin(np.abs(rgb[..., None, :].astype(int) - colours.astype(int)).sum(-1), axis=-1)
    return colours, labels


def _jpeg(tmp_path: Path, quality: int = 75, image: Image.Image | None = None) -> Path:
    path = tmp_path / f"shapes-q{quality}.jpg"
    (image or _shapes()).save(path, quality=quality)
    return path


def _check_three(rgb: np.ndarray, size: tuple[int, int], agreement: float):
    found = cluster_colours(rgb)
    colours, labels = _truth(size)
    assert len(found.colours) == 3
    delta_e = np.linalg.norm(lab(found.colours) - lab(colours), axis=1)
    assert delta_e.max() < 5, delta_e  # each found colour is the picture's, not a blend (they are 72+ apart)
    assert (found.labels == labels).mean() >= agreement
    return found


@pytest.mark.parametrize("quality", [95, 75, 30])
def test_a_jpeg_of_the_bundled_picture_has_its_three_colours(quality, tmp_path):
    rgb = np.asarray(Image.open(_jpeg(tmp_path, quality)).convert("RGB"))
    assert len(np.unique(rgb.reshape(-1, 3), axis=0)) > 500  # what the exact count saw as colours
    found = _check_three(rgb, _shapes().size, 0.99)
    assert found.reassigned > 0 and found.merged > 0  # edges and noise, both counted
    assert found.merged + found.reassigned <= found.pixels
    clustered = found.clustered()
    assert len(np.unique(clustered.reshape(-1, 3), axis=0)) == 3


@pytest.mark.parametrize("size, resample", [((150, 100), Image.LANCZOS), ((36, 24), Image.LANCZOS),
                                            ((600, 400), Image.BILINEAR)])
def test_a_picture_resized_with_antialiasing_has_its_three_colours(size, resample, tmp_path):
    """Enlarged smoothly (bilinear x10), the edges are bands of blends several pixels wide: not colours."""
    _shapes().resize(size, resample).save(tmp_path / "resized.png")
    found = _check_three(read_image(tmp_path / "resized.png"), size, 0.98)
    assert found.reassigned > 0


def test_a_large_region_of_a_mixed_colour_is_a_colour_not_an_edge():
    """Grey is a mix of white and black, but a region of a third of the picture is no edge band."""
    rgb = np.zeros((24, 60, 3), dtype=np.uint8)
    rgb[:, :20], rgb[:, 20:40] = 255, 128
    found = cluster_colours(rgb)
    assert [tuple(c) for c in found.colours] == [(255,) * 3, (128,) * 3, (0,) * 3]
    assert found.merged == found.reassigned == 0


def test_the_tolerance_decides_which_colours_are_one():
    rgb = np.zeros((40, 60, 3), dtype=np.uint8)
    rgb[:, :20], rgb[:, 20:40], rgb[:, 40:] = (200, 40, 40), (210, 50, 40), (20, 20, 120)
    close = np.linalg.norm(lab(np.uint8([[200, 40, 40]])) - lab(np.uint8([[210, 50, 40]])))
    assert close < TOLERANCE
    assert len(cluster_colours(rgb).colours) == 2  # the two reds are one colour by default
    assert len(cluster_colours(rgb, tolerance=close / 2).colours) == 3
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(InputError, match="colour_tolerance"):
            cluster_colours(rgb, tolerance=bad)


def test_noise_is_refused_as_not_flat_colours():
    rgb = np.random.default_rng(0).integers(0, 256, (200, 200, 3), dtype=np.uint8)
    with pytest.raises(InputError, match="fewer than 2 flat colours.* 0% of its pixels in flat areas"):
        cluster_colours(rgb, source="noise.png")
    with pytest.raises(InputError, match="not a picture of flat colours") as err:  # flat pixels of many colours
        cluster_colours(np.repeat(np.repeat(rgb[:20, :20], 4, axis=0), 4, axis=1), tolerance=2)
    assert err.value.parameter == "colour_tolerance"


def test_tactile_image_cli_on_a_jpeg_clusters_before_any_simulation(tmp_path, capsys):
    """The issue's case: a JPEG of the bundled picture found 38 colours, ran FEM for 109 s and exited 2."""
    jpeg = _jpeg(tmp_path)
    out = tmp_path / "plate"
    code = main(["tactile-image", str(jpeg), "--out", str(out), "--size-mm", "48", "--verify", "spectral",
                 "--step-mm", "4", "--quiet"])
    text = capsys.readouterr().out
    assert code == 0, text
    summary = json.loads((out / "plate.json").read_text())
    clustering = summary["colour_clustering"]
    assert clustering["flat_colours"] == 3 == len(summary["regions"])
    assert clustering["pixels_reassigned"] > 0 and clustering["tolerance_delta_e"] == TOLERANCE
    assert f"into 3 flat colours (tolerance Delta E {TOLERANCE:g})" in text
    assert f"{clustering['pixels_reassigned']:,} (" in text and "clustered.png" in text
    shown = np.asarray(Image.open(out / "clustered.png").convert("RGB"))
    assert shown.shape == (40, 60, 3)
    assert {"#%02x%02x%02x" % tuple(c) for c in np.unique(shown.reshape(-1, 3), axis=0)} == {
        r["colour"] for r in summary["regions"]}


def test_more_colours_than_k_is_refused_before_the_palette(workdir, capsys):  # noqa: F811
    _jpeg(workdir)
    _expect_refusal(["tactile-image", "shapes-q75.jpg", "--out", "plate", "--k", "2", "--background", "none"],
                    workdir, capsys,
                    ("--k", "3 flat colours"))


@pytest.mark.parametrize("value", ["0", "-5", "nan", "inf"])
def test_a_bad_colour_tolerance_is_refused(value, workdir, capsys):  # noqa: F811
    _expect_refusal(["tactile-image", "picture.png", "--out", "plate", "--colour-tolerance", value], workdir, capsys,
                    ("--colour-tolerance",))


def test_noise_is_refused_naming_the_tolerance(workdir, capsys):  # noqa: F811
    Image.fromarray(np.random.default_rng(1).integers(0, 256, (120, 120, 3), dtype=np.uint8)).save(workdir / "p.png")
    _expect_refusal(["tactile-image", "p.png", "--out", "plate"], workdir, capsys, ("--colour-tolerance",))


# --- tune: relative targets, and the factor that would reach a refused target ------------------------------------

SPECTRAL = Evaluator(fidelity="spectral")  # tens of ms a texture (about 1 s for reliefs 3x the standard's)
# a surrogate whose V peaks inside the height range: model version 2, kept beside the shipped model
PEAKED = Evaluator(model_path=str(MODELS_DIR / "roughness-cnn-v2.onnx"), fidelity="spectral")


@pytest.fixture(scope="module")
def standard():
    return standard_texture(1.0, seed=0)


@pytest.mark.parametrize("steps", [1.0, -0.5])
def test_a_relative_target_counts_jnds_from_the_inputs_verified_lambda(steps, standard):
    start = SPECTRAL.verify(standard)
    target = target_of(SPECTRAL, jnd=steps, heightmap=standard)
    assert target.lambda_mm == pytest.approx(start.equivalent_lambda_mm * 1.19**steps, rel=1e-12)
    assert jnd(target.lambda_mm, start.equivalent_lambda_mm) == pytest.approx(steps, abs=1e-9)
    assert target.reference.roughness == start.roughness and target.parameter == "jnd"
    assert f"{steps:+g} JND from the input: V {start.roughness:.4f}" in target.describe()
    assert (target.roughness > start.roughness) == (steps > 0)


def test_a_relative_target_is_refused_when_ill_posed(standard):
    for bad in (float("nan"), float("inf"), 31.0):
        with pytest.raises(InputError, match="jnd") as err:
            target_of(SPECTRAL, jnd=bad, heightmap=standard)
        assert err.value.parameter == "jnd"
    with pytest.raises(InputError, match="exactly one target"):
        target_of(SPECTRAL, lambda_mm=1.0, jnd=1.0, heightmap=standard)
    with pytest.raises(InputError, match="needs the texture"):
        target_of(SPECTRAL, jnd=1.0)
    flat = Heightmap(np.zeros((240, 240)), 0.05)
    with pytest.raises(InputError, match="below the standard scale's floor"):
        target_of(SPECTRAL, jnd=1.0, heightmap=flat)


@pytest.mark.parametrize("relief_mm", [0.0, 1e-4])
def test_every_target_measured_on_a_texture_refuses_a_flat_one(standard, relief_mm):
    """A target taken from a texture (like REF, or JNDs from the input) has no V to aim at when the texture is
    flat or nearly (it raised "math domain error" for like): each is refused, naming its own parameter."""
    near_flat = Heightmap(relief_mm * standard.heights / np.ptp(standard.heights), standard.pixel_mm)
    for kwargs, parameter in (({"like": near_flat}, "like"), ({"jnd": 1.0, "heightmap": near_flat}, "jnd")):
        with pytest.raises(InputError, match="below the standard scale's floor") as err:
            target_of(SPECTRAL, **kwargs)
        assert err.value.parameter == parameter


def test_tune_cli_one_jnd_rougher_says_the_input_and_the_target(tmp_path, capsys):
    path = tmp_path / "standard.npz"
    save_heightmap(standard_texture(1.0, seed=0), path)
    code = main(["tune", str(path), "--jnd", "+1", "--out", str(tmp_path / "rougher.npz"), "--verify", "spectral",
                 "--quiet", "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert code == 0 and summary["reached"] and summary["target_given_as"] == "jnd" and summary["target_jnd"] == 1
    assert summary["target_lambda_mm"] == pytest.approx(summary["input_lambda_mm"] * 1.19, rel=1e-9)
    assert abs(jnd(summary["achieved_lambda_mm"], summary["input_lambda_mm"]) - 1) <= 0.1  # the tolerance
    assert summary["factor"] > 1 and summary["input_roughness"] > 0 and summary["input_roughness_stderr"] > 0
    code = main(["tune", str(path), "--jnd", "-0.5", "--out", str(tmp_path / "smoother.npz"), "--verify", "spectral",
                 "--quiet"])
    text = capsys.readouterr().out
    assert code == 0 and "(-0.5 JND from the input: V " in text and "lambda" in text


def test_a_target_beyond_the_surrogates_reach_within_the_range_is_searched_with_the_spectral_engine(standard):
    """Model version 2's V peaks near height x1.8 (lambda 1.35 mm, far out of its domain) and falls beyond;
    the physics does not: lambda 1.7 mm, past the coarsest standard (1.625 mm), is reached beyond that peak, at
    about x2.25 on the spectral scale extrapolated from its end."""
    result = tune(standard, target_of(PEAKED, lambda_mm=1.7), "height", PEAKED)
    assert result.search_engine == "spectral" and result.reached
    assert 1.9 < result.factor < 3.0 and any("spectral engine searched instead" in n for n in result.notes)
    assert "the scaled texture lies outside the surrogate's training domain (verified by spectral)" in result.notes
    assert result.summary()["steps"][0]["search_roughness"] != result.summary()["steps"][0]["surrogate_roughness"]


def test_a_refused_target_names_the_factor_that_reaches_it(standard):
    """lambda 2 mm lies beyond the default factors (about x3.4 on the spectral scale), and beyond model version 2's
    reach, so the spectral engine searches and names the factor."""
    with pytest.raises(InputError, match=r"about (\d+\.\d+): widen the range \(max_factor=(\d+\.?\d*)\)") as err:
        tune(standard, target_of(PEAKED, lambda_mm=2.0), "height", PEAKED)
    about, flag = (float(x) for x in re.search(r"about (\d+\.\d+).*max_factor=(\d+\.?\d*)", str(err.value)).groups())
    assert 3.0 < about < flag
    result = tune(standard, target_of(PEAKED, lambda_mm=2.0), "height", PEAKED, factor_range=(3.0, flag))
    assert result.reached and result.factor == pytest.approx(about, rel=0.05)
    with pytest.raises(InputError, match=r"no height factor in 0\.0333\.\.0\.5 reaches it on the spectral engine"):
        tune(standard, target_of(PEAKED, lambda_mm=0.1), "height", PEAKED, factor_range=(0.1, 0.5))


def test_tune_refuses_two_targets_and_bad_jnds(workdir, capsys):  # noqa: F811
    base = ["tune", "map.npy", "--pixel-mm", "0.05", "--out", "new.npz"]
    _expect_refusal(base + ["--jnd", "1", "--target-lambda", "1.0"], workdir, capsys, ("--jnd",))
    for value in ("nan", "inf", "-31", "abc"):
        _expect_refusal(base + ["--jnd", value], workdir, capsys, ("--jnd",))
    np.save(workdir / "flat.npy", np.zeros((240, 240)))
    _expect_refusal(["tune", "flat.npy", "--pixel-mm", "0.05", "--out", "new.npz", "--jnd", "1", "--verify",
                     "spectral"], workdir, capsys, ("--jnd",))
