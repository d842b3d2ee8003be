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
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
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


@asynccontextmanager
async def running_studio(settings: StudioSettings = StudioSettings(show=False)) -> AsyncIterator[Studio]:
    """The studio built on a reset NiceGUI, served to an in-process client (nicegui.testing.user_simulation, with
    the studio's own app instead of a root function)."""
    with nicegui_reset_globals():
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
