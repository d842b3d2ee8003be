"""Helpers of the studio's tests: the app under NiceGUI's browser-less test client, one fresh app per test.

    pytestmark = pytest.mark.anyio  # the fixture ``studio`` is in conftest.py


    async def test_page(studio):
        await studio.user.open("/texture")
        studio.user.find("Open the bundled example").click()
        await studio.user.should_see("V = 0.09")

``studio.user`` is NiceGUI's ``nicegui.testing.User``; ``studio.sessions`` the app's live sessions;
``studio.http`` an httpx client on the same app (downloads, the token gate).
"""
from __future__ import annotations

import asyncio
import os
import sys
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager, contextmanager
from dataclasses import dataclass

import httpx
from nicegui import core, ui
from nicegui.testing.general import nicegui_reset_globals, prepare_simulation
from nicegui.testing.user import User

from roughness.studio.app import StudioSettings, build_app
from roughness.studio.sessions import Sessions

README_UNITS = ("--pixel-mm", "0.05", "--height-mm", "1")  # the README's units of the bundled example


@dataclass
class Studio:
    user: User
    sessions: Sessions
    http: httpx.AsyncClient

    def new_user(self) -> User:
        """Another browser tab on the same server."""
        return User(httpx.AsyncClient(transport=httpx.ASGITransport(core.app), base_url="http://test"))


@contextmanager
def package_kept():
    """NiceGUI's reset (``nicegui_reset_globals``) removes from ``sys.modules`` the module of every page function and
    all its parents: ``roughness`` itself. The next import then made a second package ``roughness`` without the
    attributes of the subpackages already imported (``roughness.objects``), and whatever ran after a studio test
    reached them in vain. The package and its modules outside the studio are put back; the studio's go, as NiceGUI
    intends."""
    kept = {name: module for name, module in sys.modules.items()
            if name.split(".")[0] == "roughness" and not name.startswith("roughness.studio")}
    try:
        yield
    finally:
        sys.modules.update(kept)


@asynccontextmanager
async def running_studio(settings: StudioSettings = StudioSettings(show=False)) -> AsyncIterator[Studio]:
    """The studio built on a reset NiceGUI, served to an in-process client (nicegui.testing.user_simulation, with
    the studio's own app instead of a root function)."""
    with package_kept(), nicegui_reset_globals():
        os.environ["NICEGUI_USER_SIMULATION"] = "true"
        try:
            prepare_simulation()
            sessions = build_app(settings)
            ui.run(storage_secret="simulated secret", show=False, reload=False)
            async with core.app.router.lifespan_context(core.app):
                async with httpx.AsyncClient(transport=httpx.ASGITransport(core.app),
                                             base_url="http://test") as client:
                    yield Studio(User(client), sessions, client)
        finally:
            os.environ.pop("NICEGUI_USER_SIMULATION", None)


def text_of(user, marker: str) -> str:
    """The text of the one visible element marked ``marker``."""
    [element] = user.find(marker=marker).elements
    return element.text


async def wait_for(user, marker: str, words: str, timeout_s: float = 120.0) -> str:
    """The text of the element ``marker`` once it contains ``words`` (a background job's answer)."""
    for _ in range(int(timeout_s / 0.1)):
        text = text_of(user, marker)
        if words in text:
            return text
        await asyncio.sleep(0.1)
    raise AssertionError(f"{marker!r} never showed {words!r}; it shows {text!r}")


# --- a real server and a real browser (tests/test_studio_browser.py, benchmarks/studio_latency.py) ---------------

CHROMIUM_PATHS = ("/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/lib/chromium/chromium")
"""Debian's chromium (`.ci/run` installs it when missing); Playwright's own browser download cannot work here."""


def find_chromium() -> str | None:
    """The path of a Chromium executable, or None."""
    import shutil

    found = [p for p in CHROMIUM_PATHS if os.path.exists(p)] + [shutil.which("chromium") or ""]
    return next((p for p in found if p), None)


def free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextmanager
def served_studio(timeout_s: float = 60.0):
    """`roughness studio --no-browser` in its own process on a free port; yields its base URL, stops it after."""
    import subprocess
    import sys
    import time
    import urllib.request

    port = free_port()
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST"}  # NiceGUI serves differently under it
    server = subprocess.Popen([sys.executable, "-m", "roughness.cli", "studio", "--no-browser", "--port", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    url = f"http://127.0.0.1:{port}"
    try:
        end = time.monotonic() + timeout_s
        while True:
            try:
                urllib.request.urlopen(url, timeout=1).close()
                break
            except OSError:
                if server.poll() is not None or time.monotonic() > end:
                    raise RuntimeError(f"the studio did not start: {server.stderr.read()}") from None
                time.sleep(0.2)
        yield url
    finally:
        server.terminate()
        server.wait(timeout=10)
