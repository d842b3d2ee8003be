"""A picture of a textured mesh: shaded orthographic views, rendered by casting rays on a pixel grid (no 3D
plotting, so meshes of millions of triangles draw in seconds)."""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.figures import new_figure

from .sampling import first_hits

if TYPE_CHECKING:
    from matplotlib.figure import Figure

VIEWS = {"top": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)), "front": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
         "oblique": ((1.0, -1.0, 1.0), (0.0, 0.0, 1.0))}
"""(direction from the object towards the viewer, the direction shown up) of the preview's panels."""
LIGHT = np.array([-0.4, 0.5, 0.77])


def preview_figure(mesh, title: str = "", pixels: int = 500,
                   progress: Callable[[float], object] | None = None) -> Figure:
    """A Figure with the mesh (a trimesh or TexturedMesh) seen from each direction of VIEWS, shaded by the
    surface's slope under a light from the upper left; the scale bar is in mm. ``progress``: called with the
    fraction of the views drawn after each."""
    mesh = getattr(mesh, "mesh", mesh)
    vertices = np.asarray(mesh.vertices)
    centre = (vertices.min(axis=0) + vertices.max(axis=0)) / 2
    radius = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0))) / 2 or 1.0
    fig = new_figure(figsize=(4 * len(VIEWS), 4.4))
    pixel = 2 * radius / pixels
    for k, (name, (direction, up)) in enumerate(VIEWS.items()):
        d = np.asarray(direction) / np.linalg.norm(direction)
        depth = first_hits(mesh, centre, d, pixels, pixel, 2 * radius, up)
        ax = fig.add_subplot(1, len(VIEWS), k + 1)
        ax.imshow(shade(depth, pixel), cmap="gray", vmin=0, vmax=1, origin="lower",
                  extent=(-radius, radius, -radius, radius))
        ax.set_title(name)
        ax.set_xlabel("mm")
        if progress is not None:
            progress((k + 1) / len(VIEWS))
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def shade(depth: np.ndarray, pixel_mm: float) -> np.ndarray:
    """Lambertian shading (0..1) of a depth map (heights towards the viewer, mm; -inf: background, shown white)."""
    hit = np.isfinite(depth)
    filled = np.where(hit, depth, depth[hit].min() if hit.any() else 0.0)
    gy, gx = np.gradient(filled, pixel_mm)
    normal = np.stack([-gx, -gy, np.ones_like(gx)], axis=-1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    light = LIGHT / np.linalg.norm(LIGHT)
    return np.where(hit, 0.15 + 0.85 * np.clip(normal @ light, 0, 1), 1.0)
