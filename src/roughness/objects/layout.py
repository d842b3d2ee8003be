"""Lay a texture on a mesh the way a user names it: build the mapping (``triplanar``, ``cylinder``, ``sphere``,
``uv``) with its axis, centre and radius fitted to the textured faces unless given."""
from __future__ import annotations

import math

import numpy as np

from roughness.core.checks import positive
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from .fitting import centroid, principal_axis, wrap_radius
from .mapping import DEFAULT_BLEND_DEG, Axis, Triplanar, UVMapping, axis_of, wrap

MAPPINGS = ("triplanar", "cylinder", "sphere", "uv")


def make_mapping(kind: str, texture: Heightmap, mesh, faces: np.ndarray | None = None, axis: Axis | None = None,
                 radius_mm: float | None = None, blend_deg: float = DEFAULT_BLEND_DEG, uv_mm: float | None = None):
    """The mapping ``kind`` of ``texture`` on ``mesh`` (a trimesh, mm), fitted to the faces ``faces`` (a mask; default
    all): a cylinder's axis is the surface's principal axis (``fitting.principal_axis``) and its radius the median
    distance of the side from it; a sphere's centre is the surface's centroid (axis along z) and its radius the
    median distance from it; UV's mm per UV unit keep the texture at its own size on average
    (sqrt(surface area / UV area))."""
    if kind not in MAPPINGS:
        raise InputError(f"unknown mapping {kind!r}; valid: {', '.join(MAPPINGS)}", parameter="mapping")
    vertices = np.asarray(mesh.vertices, dtype=float)
    all_faces = np.asarray(mesh.faces)
    selected = all_faces if faces is None else all_faces[np.asarray(faces, dtype=bool)]
    if len(selected) == 0:
        raise InputError("the region selects no face of the mesh", parameter="region")
    if kind == "triplanar":
        return Triplanar(texture, blend_deg)
    if kind == "uv":
        return _uv(texture, mesh, uv_mm)
    if axis is None:
        axis = principal_axis(vertices, selected) if kind == "cylinder" else axis_of(centroid(vertices, selected),
                                                                                     (0.0, 0.0, 1.0))
    radius = positive("radius_mm", radius_mm) if radius_mm is not None else wrap_radius(vertices, selected, axis, kind)
    return wrap(texture, kind, axis, radius, blend_deg)


def _uv(texture: Heightmap, mesh, uv_mm: float | None) -> UVMapping:
    uv = getattr(getattr(mesh, "visual", None), "uv", None)
    if uv is None or len(uv) != len(mesh.vertices):
        raise InputError("the mesh has no texture coordinates (UVs): use another mapping", parameter="mapping")
    uv = np.asarray(uv, dtype=float)
    if uv_mm is None:
        faces = np.asarray(mesh.faces)
        t = uv[faces]
        uv_area = 0.5 * np.abs(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])).sum()
        if not uv_area > 0:
            raise InputError("the mesh's texture coordinates cover no area: use another mapping", parameter="mapping")
        uv_mm = math.sqrt(float(mesh.area) / uv_area)
    return UVMapping(texture, mesh, positive("uv_mm", uv_mm))
