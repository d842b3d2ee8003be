"""Which faces of a mesh get the texture: all, those whose normal lies in a cone or at an angle range from a
direction, those in a box, those painted in a colour (the mesh's vertex or face colours), or a list of faces."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.core.limits import MAX_MESH_TRIANGLES

KINDS = ("all", "cone", "angle", "box", "colour", "faces")
MAX_FACE_LIST_BYTES = 16 * MAX_MESH_TRIANGLES
"""Bytes of a face list read (every face of the largest mesh, up to 15 digits and a separator each)."""


@dataclass(frozen=True)
class Region:
    """A selection of faces. ``kind``:

    - ``all``: every face;
    - ``cone``: faces whose unit normal lies within ``half_angle_deg`` of ``axis`` (e.g. (0, 0, 1), 60: the top);
    - ``angle``: faces whose unit normal makes an angle from ``min_deg`` to ``max_deg`` with ``axis`` (e.g. (0, 0, 1),
      45, 135: the walls; 0, 170: all but the bottom);
    - ``box``: faces whose centroid lies in the axis-aligned box ``low``..``high`` (mm);
    - ``colour``: faces painted ``colour`` (RGB, 0-255): a face whose colour (face colours, else the mean of its
      vertices' colours) is within ``tolerance`` (per channel, 0-255) of it;
    - ``faces``: the triangles numbered ``ids`` (from 0, in the file's order).
    """

    kind: str = "all"
    axis: tuple[float, float, float] | None = None
    half_angle_deg: float | None = None
    low: tuple[float, float, float] | None = None
    high: tuple[float, float, float] | None = None
    colour: tuple[float, float, float] | None = None
    tolerance: float = 0.0
    min_deg: float | None = None
    max_deg: float | None = None
    ids: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InputError(f"unknown region {self.kind!r}; valid: {', '.join(KINDS)}", parameter="region")
        needs = {"cone": ("axis", "half_angle_deg"), "angle": ("axis", "min_deg", "max_deg"), "box": ("low", "high"),
                 "colour": ("colour",), "faces": ("ids",)}.get(self.kind, ())
        for name in needs:
            if getattr(self, name) is None:
                raise InputError(f"a {self.kind} region needs {name}", parameter="region")
        if self.kind == "cone":
            _vector("the cone's axis", self.axis, nonzero=True)
            _number_between("the cone's half angle (degrees)", self.half_angle_deg, 0.0, 180.0)
        if self.kind == "angle":
            _vector("the direction", self.axis, nonzero=True)
            low = _number_between("the smallest angle (degrees)", self.min_deg, 0.0, 180.0)
            if _number_between("the largest angle (degrees)", self.max_deg, 0.0, 180.0) < low:
                raise InputError(f"the angle range {self.min_deg:g}-{self.max_deg:g} degrees is empty: the smallest "
                                 "angle comes first", parameter="region")
        if self.kind == "faces" and (not self.ids or min(self.ids) < 0):
            raise InputError("a face list holds face numbers from 0 (at least one)", parameter="region")
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
        if self.kind in ("cone", "angle"):
            axis = _vector("the cone's axis", self.axis, nonzero=True)
            cosine = np.asarray(mesh.face_normals) @ (axis / np.linalg.norm(axis))
            low, high = (0.0, self.half_angle_deg) if self.kind == "cone" else (self.min_deg, self.max_deg)
            return ((cosine >= math.cos(math.radians(float(high or 0.0))) - 1e-12) &
                    (cosine <= math.cos(math.radians(float(low or 0.0))) + 1e-12))
        if self.kind == "faces":
            ids = np.asarray(self.ids, dtype=np.int64)
            if ids.max() >= n:
                raise InputError(f"the face list names face {int(ids.max())}, but the mesh has {n:,} faces (numbered "
                                 f"from 0 to {n - 1:,})", parameter="region")
            out = np.zeros(n, dtype=bool)
            out[ids] = True
            return out
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
        if self.kind == "angle":
            axis = ", ".join(f"{c:g}" for c in self.axis or ())
            return f"faces whose normal lies {self.min_deg:g} to {self.max_deg:g} degrees from ({axis})"
        if self.kind == "faces":
            return f"{len(set(self.ids or ())):,} listed faces"
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
    """A Region from the CLI's text: ``all``, ``cone:AX,AY,AZ,DEG``, ``angle:AX,AY,AZ,MIN,MAX``,
    ``box:X0,Y0,Z0,X1,Y1,Z1``, ``colour:R,G,B[,TOL]`` or ``faces:FILE``."""
    kind, _, rest = text.partition(":")
    kind = kind.strip().lower().replace("color", "colour")
    if kind == "faces":
        return Region("faces", ids=read_face_list(rest.strip()))
    try:
        values = [float(v) for v in rest.split(",")] if rest.strip() else []
    except ValueError:
        raise InputError(f"region {text!r}: the values after ':' must be numbers", parameter="region") from None
    counts = {"all": (0,), "cone": (4,), "angle": (5,), "box": (6,), "colour": (3, 4)}
    if kind not in counts:
        raise InputError(f"unknown region {text!r}; valid: all, cone:AX,AY,AZ,DEG, angle:AX,AY,AZ,MIN,MAX, "
                         "box:X0,Y0,Z0,X1,Y1,Z1, colour:R,G,B[,TOL], faces:FILE", parameter="region")
    if len(values) not in counts[kind]:
        raise InputError(f"region {text!r}: {kind} takes {' or '.join(map(str, counts[kind]))} numbers, got "
                         f"{len(values)}", parameter="region")
    if kind == "cone":
        return Region("cone", axis=(values[0], values[1], values[2]), half_angle_deg=values[3])
    if kind == "angle":
        return Region("angle", axis=(values[0], values[1], values[2]), min_deg=values[3], max_deg=values[4])
    if kind == "box":
        return Region("box", low=(values[0], values[1], values[2]), high=(values[3], values[4], values[5]))
    if kind == "colour":
        return Region("colour", colour=(values[0], values[1], values[2]), tolerance=values[3] if len(values) == 4 else 0.0)
    return Region()


def read_face_list(path: str) -> tuple[int, ...]:
    """Face numbers (from 0) from a text file: integers and ranges A-B (both ends included) separated by commas,
    spaces or new lines; lines from '#' on are comments. Read as numbers only; InputError naming the first word
    that is not one."""
    file = Path(path)
    if not path or not file.is_file():
        raise InputError(f"faces:FILE needs a text file of face numbers; {path!r} is not a file", parameter="region")
    if file.stat().st_size > MAX_FACE_LIST_BYTES:
        raise InputError(f"the face list {file.name} is {file.stat().st_size:,} bytes, above the "
                         f"{MAX_FACE_LIST_BYTES:,} bytes of a list of every face of the largest mesh", parameter="region")
    ids: list[np.ndarray] = []
    text = file.read_text(encoding="utf-8", errors="replace")
    for number, line in enumerate(text.splitlines(), 1):
        for word in line.split("#", 1)[0].replace(",", " ").split():
            first, dash, last = word.partition("-")
            if not _is_count(first) or (dash and not _is_count(last)):
                raise InputError(f"the face list {file.name}, line {number}: {word[:40]!r} is not a face number (from 0) "
                                 "or a range A-B", parameter="region")
            a, b = int(first), int(last) if dash else int(first)
            if b < a or b - a >= MAX_MESH_TRIANGLES:
                raise InputError(f"the face list {file.name}, line {number}: the range {word[:40]} is empty or longer "
                                 "than the largest mesh", parameter="region")
            ids.append(np.arange(a, b + 1, dtype=np.int64))
    if not ids:
        raise InputError(f"the face list {file.name} holds no face number", parameter="region")
    return tuple(int(i) for i in np.unique(np.concatenate(ids)))


def _is_count(word: str) -> bool:
    """``word`` is a whole number of at most 15 ASCII digits (no sign, no exponent)."""
    return 0 < len(word) <= 15 and word.isascii() and word.isdigit()
