"""The studio's web app (NiceGUI): pages from ``PAGES``, per-tab sessions, downloads, the access token.

Adding a page is one module under ``roughness.studio.pages`` (``PATH``, ``TITLE``, ``SUMMARY`` and
``build(session)``) and one line in ``PAGES``. Every page gets a fresh ``Session`` per browser tab, removed when the
tab goes away; the server removes them all when it stops.
"""
from __future__ import annotations

import secrets
from dataclasses import dataclass
from http.cookies import SimpleCookie
from importlib import import_module
from types import ModuleType
from urllib.parse import parse_qs

from nicegui import app, ui
from starlette.responses import FileResponse, PlainTextResponse

from .sessions import Sessions

PAGES = ["roughness.studio.pages.texture", "roughness.studio.pages.printed",
         "roughness.studio.pages.tactile",
         "roughness.studio.pages.object"]
"""The studio's pages, in the order of its navigation bar (module names)."""
TITLE = "Roughness Studio"
PRIMARY = "#1d4e89"  # buttons: white text on it has a contrast of 8.6:1 (WCAG AA asks 4.5:1)
# Quasar's file picker is an unlabelled <input type=file> inside an unnamed button: the input, which the keyboard
# reaches and which opens the file dialog, gets the uploader's label; the button around it is only its frame.
LABEL_UPLOADERS = """<script>
new MutationObserver(() => document.querySelectorAll('.q-uploader').forEach(up => {
  const label = (up.querySelector('.q-uploader__title') || {}).textContent || 'Choose a file';
  up.querySelectorAll('.q-uploader__input').forEach(input => {
    input.setAttribute('aria-label', label);
    const frame = input.closest('.q-btn');
    if (frame) { frame.setAttribute('role', 'none'); frame.removeAttribute('tabindex'); }
  });
})).observe(document.documentElement, {childList: true, subtree: true});
</script>"""
TOKEN_COOKIE = "roughness_studio_token"
LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")


@dataclass(frozen=True)
class StudioSettings:
    """How the studio serves: address, port, whether to open a browser, and the access token every request must
    carry (None: local only, no token)."""

    host: str = "127.0.0.1"
    port: int = 8080
    show: bool = True
    token: str | None = None


class TokenGate:
    """ASGI middleware: every HTTP and websocket request carries the token, as ``?token=`` (then kept in a
    cookie) or as the cookie; others get 403."""

    def __init__(self, inner, token: str) -> None:
        self.inner, self.token = inner, token

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] not in ("http", "websocket"):
            return await self.inner(scope, receive, send)
        given = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token", [None])[0]
        headers = dict(scope.get("headers") or [])
        cookie = SimpleCookie(headers.get(b"cookie", b"").decode("latin-1"))
        held = cookie[TOKEN_COOKIE].value if TOKEN_COOKIE in cookie else None
        if not any(value is not None and secrets.compare_digest(value, self.token) for value in (given, held)):
            if scope["type"] == "websocket":
                return await send({"type": "websocket.close", "code": 1008})
            return await PlainTextResponse("roughness studio: this server needs its access token (?token=...)",
                                           status_code=403)(scope, receive, send)
        if given is None:
            return await self.inner(scope, receive, send)

        async def with_cookie(message) -> None:  # keep the token so the page's own requests carry it
            if message["type"] == "http.response.start":
                message.setdefault("headers", [])
                message["headers"] = [*message["headers"], (b"set-cookie", f"{TOKEN_COOKIE}={self.token}; "
                                                            "HttpOnly; SameSite=Strict; Path=/".encode())]
            await send(message)

        return await self.inner(scope, receive, with_cookie)


def page_modules() -> list[ModuleType]:
    """The modules of ``PAGES``."""
    return [import_module(name) for name in PAGES]


def frame(current: ModuleType | None, pages: list[ModuleType]) -> None:
    """The header every page shares: the studio's name and a link to each page (the current one marked)."""
    ui.colors(primary=PRIMARY)
    ui.add_body_html(LABEL_UPLOADERS)
    with ui.header().classes("items-center gap-6 bg-blue-10"):
        ui.link(TITLE, "/").classes("text-lg font-bold text-white no-underline")
        with ui.element("nav").props('aria-label="Pages"').classes("flex gap-4"):
            for page in pages:
                link = ui.link(page.TITLE, page.PATH).classes("text-white")
                if page is current:
                    link.props('aria-current="page"').classes("underline font-bold")


def build_app(settings: StudioSettings = StudioSettings()) -> Sessions:
    """Register the pages, the download route and (with a token) the gate on NiceGUI's app; the sessions."""
    sessions = Sessions()
    pages = page_modules()
    app.on_shutdown(sessions.close)
    if settings.token is not None:
        app.add_middleware(TokenGate, token=settings.token)

    @ui.page("/", title=TITLE)
    def index() -> None:
        frame(None, pages)
        with ui.column().classes("p-4 gap-2"):
            ui.label(TITLE).classes("text-2xl").props('role="heading" aria-level="1"')
            ui.label("Design textures by feel: every number comes from the roughness library.")
            for page in pages:
                with ui.row().classes("items-baseline"):
                    ui.link(page.TITLE, page.PATH).classes("text-lg text-primary")
                    ui.label(page.SUMMARY)

    for page in pages:
        _register(page, pages, sessions)

    @app.get("/download/{sid}/{name}")
    def download(sid: str, name: str):
        session = sessions.get(sid)
        path = None if session is None else session.file(name)
        if path is None:
            return PlainTextResponse("no such file", status_code=404)
        return FileResponse(path, filename=name)

    return sessions


def _register(page: ModuleType, pages: list[ModuleType], sessions: Sessions) -> None:
    @ui.page(page.PATH, title=f"{page.TITLE} · {TITLE}")
    def show() -> None:
        session = sessions.open()
        ui.context.client.on_delete(lambda: sessions.end(session))
        frame(page, pages)
        with ui.column().classes("w-full p-4 gap-4"):
            ui.label(page.TITLE).classes("text-2xl").props('role="heading" aria-level="1"')
            page.build(session)


def serve(settings: StudioSettings) -> None:
    """Build the app and serve it until interrupted (opening a browser if ``settings.show``)."""
    build_app(settings)
    show = settings.show and ("/" if settings.token is None else f"/?token={settings.token}")
    ui.run(host=settings.host, port=settings.port, show=show, reload=False, title=TITLE, favicon="🖐", language="en-US",
           show_welcome_message=settings.token is None, uvicorn_logging_level="warning")
