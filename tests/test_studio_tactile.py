"""The Tactile picture page through NiceGUI's test client (no browser): open a picture, make a palette and a plate,
read the guidelines and download a watertight STL and a 3MF, all as text a screen reader reads."""
from __future__ import annotations

import io

import numpy as np
import pytest
import trimesh
from nicegui import ui
from PIL import Image

from roughness.design.colours import cluster_colours
from roughness.studio.pages.tactile import example_path

pytestmark = pytest.mark.anyio
JOB_RETRIES = 600  # should_see waits 0.1 s a try: a job (a fresh process, then the library) within a minute


def two_squares() -> bytes:
    """A 40 x 30 pixel picture: white background, a red and a blue square, each wide enough to read a texture."""
    rgb = np.full((30, 40, 3), 255, np.uint8)
    rgb[5:25, 3:18] = (200, 30, 30)
    rgb[5:25, 22:37] = (30, 30, 200)
    buffer = io.BytesIO()
    Image.fromarray(rgb).save(buffer, format="PNG")
    return buffer.getvalue()


async def upload(user, name: str, data: bytes) -> None:
    [element] = user.find(ui.upload).elements
    await element.handle_uploads([ui.upload.SmallFileUpload(name, "image/png", data)])


async def test_example_shows_its_clustered_colours_as_the_library_finds_them(studio):
    from roughness.design.tactile_image import read_image

    found = cluster_colours(read_image(example_path("shapes")))
    await studio.user.open("/tactile")
    studio.user.find("Open example: shapes").click()
    await studio.user.should_see(f"clustered into {len(found.colours)} flat colours")
    await studio.user.should_see("left flat (background)")


async def test_upload_palette_plate_guidelines_and_watertight_downloads(studio):
    user = studio.user
    await user.open("/tactile")
    await upload(user, "two squares.png", two_squares())
    await user.should_see("two_squares.png: 40 x 30 pixels")
    await user.should_see("2 to texture")
    user.find("Make the palette").click()
    await user.should_see("closest pair", retries=JOB_RETRIES)
    await user.should_see("texture-2: V = ")
    user.find("Make the plate").click()
    await user.should_see("PASS at most 5 area textures: 2", retries=JOB_RETRIES)
    await user.should_see("#c81e1e -> texture-1: V ")
    await user.should_see("neighbours >= 2 JND apart on the plate")
    [session] = studio.sessions._live.values()
    for kind in ("stl", "3mf"):
        [link] = [e for e in user.find(ui.link).elements if f"plate-1.{kind} (" in e.text]
        response = await studio.http.get(link.props["href"])
        assert response.status_code == 200
        mesh = trimesh.load(io.BytesIO(response.content), file_type=kind, force="mesh")
        assert mesh.is_watertight and mesh.is_volume
        width_mm = 60.0  # the page's default plate width
        assert mesh.extents[0] == pytest.approx(width_mm, abs=0.2)  # one pixel (0.1 mm) each side at most
    assert {f.name for f in session.folder.iterdir()} >= {"plate-1.npz", "plate-1.json", "plate-1.stl", "plate-1.3mf"}


async def test_plate_before_a_palette_is_a_message_not_a_job(studio):
    await studio.user.open("/tactile")
    studio.user.find("Open example: four colours").click()
    await studio.user.should_see("to texture")
    studio.user.find("Make the plate").click()
    await studio.user.should_see("error: make a palette first")


async def test_unreadable_upload_is_the_cli_message(studio):
    await studio.user.open("/tactile")
    await upload(studio.user, "broken.png", b"not a picture")
    await studio.user.should_see("is not a readable image")


async def test_tolerance_merges_colours_when_clustered_again(studio):
    rgb = np.full((30, 40, 3), 255, np.uint8)
    rgb[5:25, 3:18] = (200, 30, 30)
    rgb[5:25, 22:37] = (210, 40, 30)  # Delta E about 5 from the other red
    buffer = io.BytesIO()
    Image.fromarray(rgb).save(buffer, format="PNG")
    user = studio.user
    await user.open("/tactile")
    [tolerance] = [e for e in user.find(ui.number).elements if "Delta E" in e.props["label"]]
    tolerance.set_value(1.0)
    await upload(user, "reds.png", buffer.getvalue())
    await user.should_see("into 3 flat colours")
    tolerance.set_value(20.0)
    user.find("Cluster the colours again").click()
    await user.should_see("into 2 flat colours")


async def test_a_failed_plate_says_why_and_a_cancelled_palette_keeps_the_last(studio):
    user = studio.user
    await user.open("/tactile")
    user.find("Open example: four colours").click()
    await user.should_see("3 to texture")
    [k] = [e for e in user.find(ui.number).elements if "(--k)" in e.props["label"]]
    k.set_value(2)  # fewer textures than colours to texture
    user.find("Make the palette").click()
    await user.should_see("closest pair", retries=JOB_RETRIES)
    shown = sorted(e.text for e in user.find(ui.label).elements if e.text.startswith("texture-"))  # a set: sorted
    user.find("Make the plate").click()
    await user.should_see("error: the picture has 3 flat colours to texture", retries=JOB_RETRIES)
    [verifier] = [e for e in user.find(ui.select).elements if "(--verify)" in e.props["label"]]
    verifier.set_value("FEM, default (many minutes)")
    user.find("Make the palette").click()
    await user.should_see("palette: making 2 textures 2 JND apart, verified by default", retries=JOB_RETRIES)
    user.find(kind=ui.button, content="Cancel").click()  # the palette's (the plate's job has ended)
    await user.should_see("palette: cancelled")
    assert sorted(e.text for e in user.find(ui.label).elements if e.text.startswith("texture-")) == shown


@pytest.mark.parametrize("label, value, message", [
    ("Plate width", -5, "--size-mm must be a positive finite number, got -5"),
    ("Colour tolerance", None, "--colour-tolerance: give a number"),
    ("(--k)", 2.5, "--k must be an integer, got 2.5")])
async def test_bad_numbers_are_refused_with_their_flag(studio, label, value, message):
    user = studio.user
    await user.open("/tactile")
    user.find("Open example: shapes").click()
    await user.should_see("to texture")
    [field] = [e for e in user.find(ui.number).elements if label in e.props["label"]]
    field.set_value(value)
    user.find("Cluster the colours again" if label != "(--k)" else "Make the palette").click()
    await user.should_see(f"error: {message}")
