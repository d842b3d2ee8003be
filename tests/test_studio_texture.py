"""The Texture page through NiceGUI's test client (no browser): every flow, each number the library's own."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from nicegui import ui

import roughness
from roughness.design.palette import variant
from roughness.studio.texture_source import example_path
from studio_helpers import README_UNITS, text_of, wait_for

pytestmark = pytest.mark.anyio


def cli_line(*args: str) -> str:
    """The text line `roughness predict` prints."""
    return subprocess.run([sys.executable, "-m", "roughness.cli", "predict", *args], capture_output=True, text=True,
                          check=True).stdout.strip()


def v_of(line: str) -> float:
    return float(line.split("V = ", 1)[1].split(" ", 1)[0])


async def open_example(studio) -> None:
    await studio.user.open("/texture")
    studio.user.find(marker="open-example").click()
    await studio.user.should_see(marker="answer", content="V = ")


async def test_bundled_example_reads_what_the_cli_prints(studio):
    await open_example(studio)
    line = cli_line(str(example_path()), *README_UNITS)
    shown = text_of(studio.user, "answer")
    assert shown.split(" (")[0] == line.split(" (")[0].replace(str(example_path()), "standard-1.0mm.png")
    assert "ensemble spread" in shown and "surrogate" in shown  # its uncertainty and its engine
    assert "JND" in text_of(studio.user, "placement") and "standard-" in text_of(studio.user, "placement")


async def test_height_slider_makes_it_rougher_live(studio):
    await open_example(studio)
    before = v_of(text_of(studio.user, "answer"))
    [slider] = studio.user.find(marker="height-slider").elements
    slider.value = 1.5
    await studio.user.should_see(marker="answer", content="height x 1.50")
    after = v_of(text_of(studio.user, "answer"))
    hm = roughness.load_heightmap(str(example_path()), pixel_mm=0.05, height_mm=1.0)
    [p] = roughness.predict(variant(hm, 1.5), engine="surrogate")
    assert after > before and after == pytest.approx(p.roughness, abs=5e-5)  # the shown V is rounded to 4 decimals


async def test_named_family_with_parameters_and_a_bad_one(studio):
    await studio.user.open("/texture")
    studio.user.find(marker="texture-name").elements.pop().value = "bumps"
    studio.user.find(marker="params").type("lambda_mm=1.25")
    studio.user.find(marker="make").click()
    await studio.user.should_see(marker="answer", content="bumps: V = ")
    studio.user.find(marker="params").clear().type("lambda_mm=1.25, wobble=2")
    studio.user.find(marker="make").click()
    run = subprocess.run([sys.executable, "-m", "roughness.cli", "texture", "make", "bumps", "--param",
                          "lambda_mm=1.25", "--param", "wobble=2", "--out", "never.npy"], capture_output=True, text=True)
    assert run.returncode == 2
    cli_message = run.stderr.strip().removeprefix("roughness: error: ")
    await studio.user.should_see(marker="source-error", content=cli_message)


async def test_upload_asks_only_for_the_units_the_file_lacks(studio, tmp_path):
    await studio.user.open("/texture")
    upload = studio.user.find(marker="upload").elements.pop()
    await upload.handle_uploads([ui.upload.SmallFileUpload("grey.png", "image/png", example_path().read_bytes())])
    await studio.user.should_see(marker="source-error", content="need --pixel-mm")
    pixel, height = (studio.user.find(marker=m).elements.pop() for m in ("pixel-mm", "height-mm"))
    assert pixel.visible and height.visible  # (find sees only visible elements)
    pixel.value, height.value = 0.05, 1.0
    studio.user.find(marker="read-units").click()
    await studio.user.should_see(marker="answer", content="grey.png: V = ")
    mm = tmp_path / "mm.npz"
    roughness.save_heightmap(roughness.standard_texture(1.0), mm)  # states its pixel size: nothing asked
    await upload.handle_uploads([ui.upload.SmallFileUpload("mm.npz", "application/octet-stream", mm.read_bytes())])
    await studio.user.should_see(marker="answer", content="mm.npz: V = ")
    await studio.user.should_not_see(marker="read-units")  # the row of units is hidden again


async def test_verify_runs_in_the_background_and_cancel_keeps_the_answer(studio):
    await open_example(studio)
    studio.user.find(marker="verify").click()
    text = await wait_for(studio.user, "verify-result", "Verified: ")
    assert "(spectral, " in text
    answer = text_of(studio.user, "answer")
    studio.user.find(marker="verify-engine").elements.pop().value = "FEM, default"
    studio.user.find(marker="verify").click()
    await wait_for(studio.user, "verify-progress", "solving")
    studio.user.find(marker="verify-cancel").click()
    await wait_for(studio.user, "verify-progress", "cancelled")
    assert text_of(studio.user, "verify-result") == text and text_of(studio.user, "answer") == answer


async def test_tune_to_a_target_lambda(studio):
    await open_example(studio)
    studio.user.find(marker="tune-value").elements.pop().value = 1.25
    studio.user.find(marker="tune").click()
    text = await wait_for(studio.user, "tune-result", "Tuned: ", timeout_s=300)
    assert "tuned (height x" in text_of(studio.user, "answer")
    assert "lambda" in text


async def test_a_job_error_is_the_clis_message(studio):
    await open_example(studio)
    studio.user.find(marker="tune-value").elements.pop().value = 0.0001
    studio.user.find(marker="tune").click()
    shown = await wait_for(studio.user, "tune-progress", "error: ", timeout_s=300)
    run = subprocess.run([sys.executable, "-m", "roughness.cli", "tune", str(example_path()), *README_UNITS,
                          "--target-lambda", "0.0001", "--verify", "spectral", "--out", "never.npz"],
                         capture_output=True, text=True)
    assert run.returncode == 2 and "Traceback" not in shown
    assert shown == run.stderr.strip().splitlines()[-1].removeprefix("roughness: ")  # after its progress line
    assert text_of(studio.user, "tune-result") == ""  # nothing made, nothing lost: the texture is as it was


async def test_compare_gives_the_jnd_matrix_and_verdicts(studio):
    await studio.user.open("/texture")
    for name in ("standard-0.75", "standard-1.5"):
        studio.user.find(marker="texture-name").elements.pop().value = name
        studio.user.find(marker="make").click()
        await studio.user.should_see(marker="answer", content=f"{name}: V = ")
        studio.user.find(marker="compare-add").click()
    studio.user.find(marker="compare").click()
    await studio.user.should_see(content="1 vs 2: distance: ")
    [table] = studio.user.find(ui.table).elements
    jnd = float(table.rows[1]["0"])
    assert jnd > 2  # 1.5 mm bumps against 0.75 mm: four steps of 19% in wavelength, more than 2 JND rougher
    assert float(table.rows[0]["1"]) == pytest.approx(-jnd, abs=0.011)


async def test_downloads_are_the_texture_as_files(studio, tmp_path):
    import trimesh

    await open_example(studio)
    links = {}
    for kind in ("npz", "stl", "3mf", "json"):
        studio.user.find(marker=f"download-{kind}").click()
        await studio.user.should_see(content=f"texture.{kind} (" if kind != "json" else "report.json (")
    for link in studio.user.find(ui.link).elements:
        if "/download/" in link.props.get("href", ""):
            links[link.props["href"].rsplit(".", 1)[1]] = link.props["href"]
    got = {kind: (await studio.http.get(url)).content for kind, url in links.items()}
    report = json.loads(got["json"])
    assert report["prediction"]["roughness"] == pytest.approx(v_of(text_of(studio.user, "answer")), abs=5e-5)
    hm = roughness.load_heightmap(str(example_path()), pixel_mm=0.05, height_mm=1.0)
    (tmp_path / "got.npz").write_bytes(got["npz"])
    saved = roughness.load_heightmap(tmp_path / "got.npz")  # states its pixel size
    assert saved.pixel_mm == hm.pixel_mm and np.array_equal(saved.heights, hm.heights)
    for kind in ("stl", "3mf"):
        mesh = trimesh.load(trimesh.util.wrap_as_stream(got[kind]), file_type=kind, force="mesh")
        assert mesh.is_watertight and mesh.extents[0] == pytest.approx(hm.shape[1] * 0.05 - 0.05, rel=1e-3)
