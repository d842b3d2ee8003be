"""Per-tab state of the studio: one ``Session`` per browser tab, with its own temporary folder.

Every file the studio makes for a tab (uploads, downloads) lives in its session's folder, which is removed when the
tab goes away or the server stops. Downloads are served only from a session's folder, by a plain file name
(``Session.file``): no path traversal, no file of another session.
"""
from __future__ import annotations

import re
import secrets
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

from roughness.core.errors import InputError

# a download's name: letters, digits, dot, dash, underscore; no separators, not hidden (no leading dot)
_FILE_NAME = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,199}")


@dataclass
class Session:
    """One browser tab's session: its id (a random token, also the secret part of its download addresses) and its
    temporary folder (the page's own state lives in its page object, one per tab)."""

    id: str
    folder: Path

    def path(self, name: str) -> Path:
        """Where the session keeps the file ``name`` (a plain file name, checked: ``InputError`` otherwise)."""
        if not _FILE_NAME.fullmatch(name) or ".." in name:
            raise InputError(f"{name!r} is not a plain file name (letters, digits, '.', '-', '_')")
        return self.folder / name

    def file(self, name: str) -> Path | None:
        """The existing file ``name`` of this session, or None (no such file, or not a plain name)."""
        try:
            path = self.path(name)
        except InputError:
            return None
        return path if path.is_file() and path.resolve().parent == self.folder.resolve() else None

    def download_url(self, name: str) -> str:
        """The address that serves the session's file ``name``."""
        self.path(name)
        return f"/download/{self.id}/{name}"


class Sessions:
    """The live sessions of one server, each folder under one root folder (removed by ``close``)."""

    def __init__(self) -> None:
        self.root = Path(tempfile.mkdtemp(prefix="roughness-studio-"))
        self._live: dict[str, Session] = {}

    def open(self) -> Session:
        """A new session with an empty folder."""
        sid = secrets.token_urlsafe(16)
        folder = self.root / sid
        folder.mkdir()
        self._live[sid] = session = Session(sid, folder)
        return session

    def get(self, sid: str) -> Session | None:
        """The live session ``sid``, or None."""
        return self._live.get(sid)

    def end(self, session: Session) -> None:
        """Forget the session and remove its folder."""
        self._live.pop(session.id, None)
        shutil.rmtree(session.folder, ignore_errors=True)

    def __len__(self) -> int:
        return len(self._live)

    def close(self) -> None:
        """End every session and remove the root folder (the server stops)."""
        for session in list(self._live.values()):
            self.end(session)
        shutil.rmtree(self.root, ignore_errors=True)
