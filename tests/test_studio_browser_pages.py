"""The Tactile picture and Object pages in a real browser (the browser, tab and axe-core scan of
tests/test_studio_browser.py: skipped, with the reason, only where no Chromium is found). The tactile flow runs from
the keyboard alone, as a screen-reader user would; screenshots go where test_studio_browser's go."""
from __future__ import annotations

import pytest
import trimesh

import test_studio_browser as shared
from test_studio_browser import CHROMIUM, SCREENSHOTS, serious_violations

browser = shared.browser  # fixtures: the served studio and Chromium, and
page = shared.page  # a fresh tab whose console errors are checked after the test

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no Chromium found (Debian: apt-get install chromium)")
JOB_MS = 120_000  # a background job on a shared machine


def press(tab, name: str) -> None:
    """Reach the button ``name`` from the keyboard and press Enter."""
    button = tab.get_by_role("button", name=name)
    button.focus()
    button.press("Enter")


def test_tactile_page_from_the_keyboard_to_a_watertight_stl(page, tmp_path):
    page.goto("/tactile")
    press(page, "Open example: shapes")
    page.get_by_text("flat colours (tolerance").wait_for()
    press(page, "Make the palette")
    page.get_by_text("closest pair").wait_for(timeout=JOB_MS)
    press(page, "Make the plate")
    page.get_by_text("PASS at most 5 area textures").wait_for(timeout=JOB_MS)
    link = page.get_by_role("link", name="Download the plate (STL)")
    link.focus()
    with page.expect_download() as download:
        link.press("Enter")
    path = tmp_path / "plate.stl"
    download.value.save_as(path)
    mesh = trimesh.load(path)
    assert mesh.is_watertight and mesh.is_volume
    assert not serious_violations(page)
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=SCREENSHOTS / "tactile.png", full_page=True)


def test_object_page_feel_legend(page):
    page.goto("/object")
    page.get_by_role("button", name="Open the example knob").click()
    page.get_by_text("knob.stl: 128 triangles, 24 x 24 x 24 mm").wait_for()
    page.get_by_label("Engine (--engine)").click()
    page.get_by_role("option", name="surrogate").click()
    page.get_by_role("button", name="Map the feel").click()
    page.get_by_text("Colours: JND from standard-1.0").wait_for(timeout=JOB_MS)
    page.get_by_text("The 3D view shows the feel map on the object").wait_for()
    page.wait_for_timeout(1000)  # the view loads the coloured object
    assert not serious_violations(page)
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=SCREENSHOTS / "object.png", full_page=True)
