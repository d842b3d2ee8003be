"""Files a page offers for download, written into the tab's session folder by the library's own writers: the
heightmap (.npz, mm), the printable plate (binary STL or 3MF, checked closed before it is written) and a JSON
report (``write_download``), and the card of buttons that offers them (``DownloadPanel``). Each call replaces the
session's earlier file of that name (the session's folder is the tab's own)."""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from nicegui import ui

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from .sessions import Session

KINDS = {"npz": "heightmap (.npz, mm)", "stl": "plate (STL)", "3mf": "plate (3MF)", "json": "report (JSON)"}


@dataclass(frozen=True)
class PlateMesh:
    """The plate of a heightmap as ``write_mesh`` takes it (``vertices``, ``faces``; mm)."""

    vertices: np.ndarray
    faces: np.ndarray


def write_download(session: Session, stem: str, kind: str, heightmap: Heightmap, report: dict) -> Path:
    """Write ``kind`` (a key of ``KINDS``) of the texture into the session folder as ``stem.kind``; its path."""
    from roughness.surface.io import save_heightmap

    path = session.path(f"{stem}.{kind}")
    if kind in ("npz", "stl"):
        save_heightmap(heightmap, path, overwrite=True)
    elif kind == "3mf":
        from roughness.objects.meshes import write_mesh
        from roughness.surface.stl import plate

        made = plate(heightmap)
        write_mesh(PlateMesh(made.vertices, made.triangles), path, overwrite=True)
    else:
        from roughness.cli.common import json_text

        path.write_text(json_text(report, indent=2) + "\n")
    return path


class DownloadPanel:
    """A card of download buttons, one per kind of ``KINDS``; ``current()`` gives (heightmap, report) of what the
    page shows, or None if it shows nothing yet. Each file written appears as a link too (keyboard, screen reader)."""

    def __init__(self, session: Session, current: Callable[[], tuple[Heightmap, dict] | None],
                 stem: str = "texture") -> None:
        self.session, self.current, self.stem = session, current, stem
        with ui.card().classes("w-full"):
            ui.label("Downloads").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("gap-4"):
                for kind, label in KINDS.items():
                    ui.button(f"Download {label}", on_click=lambda k=kind: self.download(k)).mark(f"download-{kind}")
            self.links = ui.column().mark("download-links")

    def download(self, kind: str) -> None:
        shown = self.current()
        if shown is None:
            with self.links:
                ui.label("Open or make a texture first.")
            return
        heightmap, report = shown
        try:
            path = write_download(self.session, self.stem if kind != "json" else "report", kind, heightmap, report)
        except InputError as err:
            with self.links:
                ui.label(f"error: {err}").props('role="alert"')
            return
        url = self.session.download_url(path.name)
        with self.links:
            ui.link(f"{path.name} ({path.stat().st_size:,} bytes)", url).props(f'download="{path.name}"')
        ui.download(url, path.name)
