"""The studio in a real browser: Playwright driving Debian's Chromium against `roughness studio` (skipped, with
the reason, only where no Chromium is found; `.ci/run` installs one). Screenshots go to a temporary folder, or to
the folder ROUGHNESS_SCREENSHOTS names: ``ROUGHNESS_SCREENSHOTS=docs/_static/studio`` retakes the tutorial's."""
from __future__ import annotations

import re
import subprocess
import sys
import tempfile
from os import environ
from pathlib import Path

import pytest

from roughness.studio.texture_source import example_path
from studio_helpers import README_UNITS, find_chromium, served_studio

CHROMIUM = find_chromium()
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no Chromium found (Debian: apt-get install chromium)")
SCREENSHOTS = Path(environ.get("ROUGHNESS_SCREENSHOTS") or Path(tempfile.gettempdir()) / "roughness-studio-screenshots")
V = re.compile(r"V = (\d+\.\d+)")


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    with served_studio() as url, sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM)
        yield chromium, url
        chromium.close()


@pytest.fixture
def page(browser):
    """A fresh tab; the console errors, uncaught page errors and requests to anywhere but the studio (it works
    offline: no CDN) it saw are checked after the test."""
    chromium, url = browser
    tab = chromium.new_page(viewport={"width": 1280, "height": 900}, base_url=url)
    errors: list[str] = []
    elsewhere: list[str] = []
    tab.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    tab.on("pageerror", lambda e: errors.append(str(e)))
    tab.on("request", lambda r: None if r.url.startswith((url, "data:")) else elsewhere.append(r.url))
    yield tab
    tab.close()
    assert not errors, f"console errors: {errors}"
    assert not elsewhere, f"requests outside the studio: {elsewhere}"


def serious_violations(page) -> list[str]:
    """axe-core's serious and critical violations on the page (axe-playwright-python bundles axe-core)."""
    from axe_playwright_python.sync_playwright import Axe

    found = Axe().run(page).response["violations"]
    return [f"{v['impact']} {v['id']}: {[n['target'] for n in v['nodes']]}" for v in found
            if v["impact"] in ("serious", "critical")]


def answer(page, marker_text: str = "V = ") -> str:
    status = page.locator('[role="status"]', has_text=marker_text).first
    status.wait_for()
    return status.inner_text()


def test_texture_page(page):
    page.goto("/texture")
    page.get_by_role("button", name="Open the bundled example").click()
    shown = answer(page)
    cli = subprocess.run([sys.executable, "-m", "roughness.cli", "predict", str(example_path()), *README_UNITS],
                         capture_output=True, text=True, check=True).stdout
    assert V.search(shown).group(1) == V.search(cli).group(1)
    track = page.get_by_role("slider", name="Height factor").locator('[tabindex="0"]')  # what the keyboard reaches
    track.focus()
    track.press("PageUp")  # ten steps of 0.01: height x 1.10
    risen = page.locator('[role="status"]', has_text="height x 1.10").first
    risen.wait_for(timeout=10_000)
    assert float(V.search(risen.inner_text()).group(1)) > float(V.search(shown).group(1))
    page.get_by_role("button", name="Verify the current texture").click()
    page.get_by_text("Verified: ").wait_for(timeout=60_000)
    page.get_by_label("Engine").click()
    page.get_by_role("option", name="FEM, default").click()
    page.get_by_role("button", name="Verify the current texture").click()
    page.get_by_text("solving").wait_for(timeout=30_000)
    page.get_by_role("button", name="Cancel verify").click()
    page.get_by_text("cancelled").wait_for(timeout=10_000)
    assert page.get_by_text("Verified: ").count() == 1  # the earlier verification is still shown
    assert not serious_violations(page)
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=SCREENSHOTS / "texture.png", full_page=True)


def test_printed_page(page):
    page.goto("/printed")
    page.get_by_role("button", name="Open the bundled example").click()
    page.get_by_text("V digital").wait_for(timeout=20_000)
    assert not serious_violations(page)
    page.screenshot(path=SCREENSHOTS / "printed.png", full_page=True)


def test_start_page(page):
    page.goto("/")
    page.get_by_role("link", name="Texture").first.wait_for()
    assert not serious_violations(page)
    page.screenshot(path=SCREENSHOTS / "start.png")
