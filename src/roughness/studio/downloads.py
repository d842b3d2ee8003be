"""Files a page offers for download, written into the tab's session folder by the library's own writers: the
heightmap (.npz, mm), the printable plate (binary STL or 3MF, checked closed before it is written) and a JSON
report. Each call replaces the session's earlier file of that name (the session's folder is the tab's own)."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

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
