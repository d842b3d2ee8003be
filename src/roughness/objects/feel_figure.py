"""A picture of an object coloured by how it feels: V, or JNDs from a reference texture (``feel_figure``; the
faces and their colours alone: ``feel_colours``, for other views such as the studio's 3D view).

Each face takes the value of the nearest evaluation point of the ``FeelMap`` (within 1.5 spacings);
faces outside the textured regions are light grey, faces whose nearest point was refused dark grey.
Two views, front and back. Long faces are split to half the spacing for the drawing; at most
``MAX_FACES`` faces are drawn (a sample where there are more, said in the title).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError
from roughness.core.figures import new_figure

from .feel import FeelMap

MAX_FACES = 40_000
UNTEXTURED = (0.85, 0.85, 0.85, 1.0)
REFUSED = (0.3, 0.3, 0.3, 1.0)
COLOURINGS = ("roughness", "jnd")


@dataclass(frozen=True)
class FeelColours:
    """An object's faces coloured by how they feel: ``triangles`` (n, 3, 3) mm as drawn (long faces split),
    ``colours`` (n, 4) RGBA 0..1, the colour scale (``norm``, ``cmap``: matplotlib's) and its ``label``; ``note``
    says when only a sample of the faces is drawn."""

    triangles: np.ndarray
    colours: np.ndarray
    norm: object
    cmap: object
    label: str
    note: str = ""


def feel_colours(mesh, feel: FeelMap, textured: np.ndarray | None = None, by: str = "roughness") -> FeelColours:
    """The faces of ``mesh`` (trimesh.Trimesh) coloured by ``by`` (``roughness``: V; ``jnd``: JNDs from the map's
    reference; module docstring); ``textured``: bool per face (default: all)."""
    from matplotlib import colormaps
    from matplotlib.colors import Normalize, TwoSlopeNorm
    from scipy.spatial import cKDTree

    if by not in COLOURINGS:
        raise InputError(f"unknown colouring {by!r}; choose one of {', '.join(COLOURINGS)}", parameter="by")
    if by == "jnd" and feel.reference is None:
        raise InputError("colouring by JND needs a reference texture", parameter="reference")
    values = feel.roughness if by == "roughness" else feel.jnd
    textured = np.ones(len(mesh.faces), bool) if textured is None else textured
    triangles, textured = _drawn(mesh, textured, feel.spacing_mm / 2)
    faces = np.arange(len(triangles))
    note = ""
    if len(faces) > MAX_FACES:
        faces = np.sort(np.random.default_rng(0).choice(faces, MAX_FACES, replace=False))
        note = f" ({MAX_FACES:,} of {len(triangles):,} faces drawn)"
    triangles = triangles[faces]
    centres = triangles.mean(axis=1)
    distance, nearest = cKDTree(feel.points).query(centres)
    face_values = values[nearest]
    finite = values[np.isfinite(values)]
    if by == "jnd":
        reach = max(float(np.abs(finite).max()) if len(finite) else 1.0, 0.1)
        norm, cmap, label = TwoSlopeNorm(0.0, -reach, reach), colormaps["coolwarm"], \
            f"JND from {feel.reference.name} (positive: rougher)"
    else:
        lo, hi = (float(finite.min()), float(finite.max())) if len(finite) else (0.0, 1.0)
        norm, cmap, label = Normalize(lo, hi if hi > lo else lo + 1e-6), colormaps["viridis"], \
            f"V ({feel.engine}, curvature included)"
    colours = np.array([UNTEXTURED] * len(faces))
    mapped = textured[faces] & (distance <= 1.5 * feel.spacing_mm)
    ok = mapped & np.isfinite(face_values)
    colours[ok] = cmap(norm(face_values[ok]))
    colours[mapped & ~np.isfinite(face_values)] = REFUSED
    return FeelColours(triangles, colours, norm, cmap, label, note)


def feel_figure(mesh, feel: FeelMap, textured: np.ndarray | None = None, by: str = "roughness", title: str = ""):
    """The object (trimesh.Trimesh) coloured by ``by`` (``roughness``: V; ``jnd``: JNDs from the map's
    reference), with a colour bar; ``textured``: bool per face (default: all). Returns a matplotlib Figure."""
    from matplotlib.cm import ScalarMappable
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    drawn = feel_colours(mesh, feel, textured, by)
    fig = new_figure(figsize=(10, 5), layout="constrained")
    lo, hi = mesh.bounds
    for k, azimuth in enumerate((-60, 120)):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        ax.add_collection3d(Poly3DCollection(drawn.triangles, facecolors=drawn.colours, edgecolors="none",
                                             linewidths=0))
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]), xlabel="x (mm)", ylabel="y (mm)",
               zlabel="z (mm)")
        ax.set_box_aspect(hi - lo)
        ax.view_init(elev=25, azim=azimuth)
    fig.colorbar(ScalarMappable(drawn.norm, drawn.cmap), ax=fig.axes, shrink=0.7, label=drawn.label)
    refused = feel.method.count("refused")
    fig.suptitle((title + "\n" if title else "") + f"{len(feel.points)} footprints {feel.spacing_mm:g} mm apart, "
                 f"{refused} refused (dark grey), untextured light grey" + drawn.note)
    return fig


def _drawn(mesh, textured: np.ndarray, max_edge_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """Triangles (n, 3, 3) to draw, long ones split to ``max_edge_mm`` (each face then shows its own point's
    colour; longer where that would pass ``MAX_FACES``), and whether each is textured."""
    from trimesh.remesh import subdivide_to_size

    edges = np.linalg.norm(mesh.triangles - np.roll(mesh.triangles, 1, axis=1), axis=2).max(axis=1)
    max_edge_mm = max(max_edge_mm, 2 * float(np.sqrt(np.sum(edges**2) / MAX_FACES)))  # each split quarters a face
    if edges.max() <= max_edge_mm or len(edges) >= MAX_FACES:
        return mesh.triangles, textured
    vertices, faces, index = subdivide_to_size(mesh.vertices, mesh.faces, max_edge_mm, max_iter=12,
                                               return_index=True)
    return vertices[faces], textured[index]
