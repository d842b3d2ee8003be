"""Which faces of a mesh get the texture: all, those whose normal lies in a cone, those in a box, or those painted
in a colour (the mesh's vertex or face colours)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError

KINDS = ("all", "cone", "box", "colour")


@dataclass(frozen=True)
class Region:
    """A selection of faces. ``kind``:

    - ``all``: every face;
    - ``cone``: faces whose unit normal lies within ``half_angle_deg`` of ``axis`` (e.g. (0, 0, 1), 60: the top);
    - ``box``: faces whose centroid lies in the axis-aligned box ``low``..``high`` (mm);
    - ``colour``: faces painted ``colour`` (RGB, 0-255): a face whose colour (face colours, else the mean of its
      vertices' colours) is within ``tolerance`` (per channel, 0-255) of it.
    """

    kind: str = "all"
    axis: tuple[float, float, float] | None = None
    half_angle_deg: float | None = None
    low: tuple[float, float, float] | None = None
    high: tuple[float, float, float] | None = None
    colour: tuple[float, float, float] | None = None
    tolerance: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InputError(f"unknown region {self.kind!r}; valid: {', '.join(KINDS)}", parameter="region")
        needs = {"cone": ("axis", "half_angle_deg"), "box": ("low", "high"), "colour": ("colour",)}.get(self.kind, ())
        for name in needs:
            if getattr(self, name) is None:
                raise InputError(f"a {self.kind} region needs {name}", parameter="region")
        if self.kind == "cone":
            _vector("the cone's axis", self.axis, nonzero=True)
            _number_between("the cone's half angle (degrees)", self.half_angle_deg, 0.0, 180.0)
        if self.kind == "box":
            low, high = _vector("the box's low corner", self.low), _vector("the box's high corner", self.high)
            if not np.all(low < high):
                raise InputError(f"the box's low corner {self.low} must lie below its high corner {self.high} on "
                                 "every axis", parameter="region")
        if self.kind == "colour":
            rgb = np.asarray(self.colour, dtype=float).reshape(-1)
            if rgb.shape != (3,) or not np.all((rgb >= 0) & (rgb <= 255)):
                raise InputError(f"a colour is three numbers 0-255 (R, G, B), got {self.colour!r}", parameter="region")
            _number_between("the colour's tolerance (per channel, 0-255)", self.tolerance, 0.0, 255.0)

    def faces(self, mesh) -> np.ndarray:
        """Boolean mask (faces,) of the faces selected in ``mesh`` (a trimesh)."""
        n = len(mesh.faces)
        if self.kind == "all":
            return np.ones(n, dtype=bool)
        if self.kind == "cone":
            axis = _vector("the cone's axis", self.axis, nonzero=True)
            cosine = np.asarray(mesh.face_normals) @ (axis / np.linalg.norm(axis))
            return cosine >= math.cos(math.radians(float(self.half_angle_deg or 0.0))) - 1e-12
        if self.kind == "box":
            centre = np.asarray(mesh.triangles_center)
            return np.all((centre >= np.asarray(self.low)) & (centre <= np.asarray(self.high)), axis=1)
        colours = face_colours(mesh)
        if colours is None:
            raise InputError("the mesh has no vertex or face colours to select a painted region by", parameter="region")
        return np.all(np.abs(colours - np.asarray(self.colour, dtype=float)) <= self.tolerance + 1e-9, axis=1)

    def describe(self) -> str:
        if self.kind == "all":
            return "all faces"
        if self.kind == "cone":
            axis = ", ".join(f"{c:g}" for c in self.axis or ())
            return f"faces whose normal lies within {self.half_angle_deg:g} degrees of ({axis})"
        if self.kind == "box":
            return f"faces whose centre lies in the box {self.low}..{self.high} mm"
        return f"faces painted {self.colour} (within {self.tolerance:g} per channel)"


def face_colours(mesh) -> np.ndarray | None:
    """(faces, 3) RGB 0-255 of each face: its own colour, else the mean of its vertices'; None if the mesh has no
    colours (trimesh's default grey counts as none)."""
    visual = getattr(mesh, "visual", None)
    if visual is None or getattr(visual, "kind", None) != "vertex" and getattr(visual, "kind", None) != "face":
        return None
    if visual.kind == "face":
        return np.asarray(visual.face_colors, dtype=float)[:, :3]
    vertex = np.asarray(visual.vertex_colors, dtype=float)[:, :3]
    return vertex[np.asarray(mesh.faces)].mean(axis=1)


def _vector(what: str, value: object, nonzero: bool = False) -> np.ndarray:
    """``value`` as three finite numbers (not all 0 if ``nonzero``); InputError naming ``what`` (a part of the
    region, in words: the CLI's --region has no flag per part)."""
    try:
        v = np.asarray(value, dtype=float).reshape(-1) if value is not None else np.empty(0)
    except (TypeError, ValueError):
        v = np.empty(0)
    if v.shape != (3,) or not np.all(np.isfinite(v)) or (nonzero and not np.any(v)):
        raise InputError(f"{what} must be three finite numbers{' not all 0' if nonzero else ''}, got {value!r}",
                         parameter="region")
    return v


def _number_between(what: str, value: object, low: float, high: float) -> float:
    """``value`` as a number in [low, high]; InputError naming ``what`` in words, as ``_vector``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not (
            low <= float(value) <= high):
        raise InputError(f"{what} must be a number from {low:g} to {high:g}, got {value!r}", parameter="region")
    return float(value)


def parse_region(text: str) -> Region:
    """A Region from the CLI's text: ``all``, ``cone:AX,AY,AZ,DEG``, ``box:X0,Y0,Z0,X1,Y1,Z1`` or
    ``colour:R,G,B[,TOL]``."""
    kind, _, rest = text.partition(":")
    kind = kind.strip().lower().replace("color", "colour")
    try:
        values = [float(v) for v in rest.split(",")] if rest.strip() else []
    except ValueError:
        raise InputError(f"region {text!r}: the values after ':' must be numbers", parameter="region") from None
    counts = {"all": (0,), "cone": (4,), "box": (6,), "colour": (3, 4)}
    if kind not in counts:
        raise InputError(f"unknown region {text!r}; valid: all, cone:AX,AY,AZ,DEG, box:X0,Y0,Z0,X1,Y1,Z1, "
                         "colour:R,G,B[,TOL]", parameter="region")
    if len(values) not in counts[kind]:
        raise InputError(f"region {text!r}: {kind} takes {' or '.join(map(str, counts[kind]))} numbers, got "
                         f"{len(values)}", parameter="region")
    if kind == "cone":
        return Region("cone", axis=(values[0], values[1], values[2]), half_angle_deg=values[3])
    if kind == "box":
        return Region("box", low=(values[0], values[1], values[2]), high=(values[3], values[4], values[5]))
    if kind == "colour":
        return Region("colour", colour=(values[0], values[1], values[2]), tolerance=values[3] if len(values) == 4 else 0.0)
    return Region()
