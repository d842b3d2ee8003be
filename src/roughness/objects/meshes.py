"""Meshes in and out: read STL, OBJ, OFF, PLY, 3MF, GLB and glTF through trimesh (mm), check them, write STL (streamed)
and 3MF.

Units: a 3MF states its unit; glTF (and GLB) are metres by their specification (trimesh reads them so); STL, OBJ,
OFF and PLY carry none and are read as mm, with a note saying so.

Sizes are checked before anything is allocated: the file's bytes (MAX_MESH_FILE_BYTES; a 3MF's unpacked members and
a glTF's external files, which must lie in its folder, too), a binary STL's declared triangle count and every mesh's
triangles (MAX_MESH_TRIANGLES). trimesh parses the files as
data (no code runs; 3MF's XML with entities, DTDs and network access off). Polygons with more than three corners
(OBJ, PLY) are triangulated by trimesh as it reads them.
"""
from __future__ import annotations

import mmap
import os
import re
import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from roughness.core.errors import InputError
from roughness.core.files import atomic_write
from roughness.core.limits import MAX_MESH_FILE_BYTES, MAX_MESH_TRIANGLES, check_size
from roughness.surface.solid import SolidCheck
from roughness.surface.stl import require_solid, write_stl
from roughness.surface.units import CONFIRM

from . import threemf

READ_SUFFIXES = (".stl", ".obj", ".off", ".ply", ".3mf", ".glb", ".gltf")
WRITE_SUFFIXES = (".stl", ".3mf")
UNIT_MM = {"mm": 1.0, "millimeter": 1.0, "millimeters": 1.0, "millimetre": 1.0, "cm": 10.0, "centimeter": 10.0,
           "m": 1000.0, "meter": 1000.0, "meters": 1000.0, "in": 25.4, "inch": 25.4, "inches": 25.4,
           "um": 1e-3, "micron": 1e-3, "micrometer": 1e-3, "ft": 304.8, "foot": 304.8, "feet": 304.8}


@dataclass
class ReadMesh:
    """A mesh read from ``path`` (a trimesh, mm) and what reading did to it (``notes``)."""

    mesh: Any  # trimesh.Trimesh
    path: str
    notes: list[str] = field(default_factory=list)

    @property
    def triangles(self) -> int:
        return len(self.mesh.faces)


def read_mesh(path: str | Path, watertight: bool = True, parameter: str = "mesh", units_ok: bool = False) -> ReadMesh:
    """The triangle mesh in ``path`` (READ_SUFFIXES; several bodies or a glTF scene's meshes are joined), in mm, with its duplicate
    vertices merged and degenerate faces dropped (noted). InputError for a file that is missing, too large, not a
    mesh, damaged (a binary STL whose triangle count is not its size's, an OBJ face with index 0, vertices that are
    not finite numbers), empty, without triangles, or (``watertight``) open or inconsistently wound; a mesh wound
    inside-out is turned (noted). A size implausible for a touchable object (``check_object_size``) is an
    InputError unless ``units_ok``."""
    import trimesh

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in READ_SUFFIXES:
        raise InputError(f"cannot read {path}: unsupported mesh format {suffix or '(no suffix)'!r}; supported: "
                         f"{', '.join(READ_SUFFIXES)}", parameter=parameter)
    if not path.exists():
        raise InputError(f"cannot read {path}: no such file", parameter=parameter)
    if not path.is_file():
        raise InputError(f"cannot read {path}: not a regular file", parameter=parameter)
    size = path.stat().st_size
    if size > MAX_MESH_FILE_BYTES:
        raise InputError(f"{path} is {size:,} bytes, above the limit of {MAX_MESH_FILE_BYTES:,} (MAX_MESH_FILE_BYTES)",
                         parameter=parameter)
    if size == 0:
        raise InputError(f"{path} is empty", parameter=parameter)
    if suffix == ".stl":
        _check_binary_stl(path, size, parameter)
    if suffix == ".obj":
        _check_obj_indices(path, parameter)
    if suffix == ".3mf":
        _check_zip(path, parameter)
    if suffix == ".gltf":
        _check_gltf_files(path, size, parameter)
    try:  # unprocessed: trimesh's processing would silently drop the faces of non-finite vertices
        loaded = trimesh.load(str(path), file_type=suffix[1:], force="mesh", process=False)
    except Exception as err:  # trimesh raises many kinds for a malformed file
        raise InputError(f"cannot read {path} as a {suffix[1:].upper()} mesh: {err or type(err).__name__}",
                         parameter=parameter) from None
    if not isinstance(loaded, trimesh.Trimesh) or len(getattr(loaded, "faces", ())) == 0:
        raise InputError(f"{path} holds no triangles (points or lines only, or nothing)", parameter=parameter)
    check_size(f"triangles in {path}", len(loaded.faces), MAX_MESH_TRIANGLES, parameter)
    bad = ~np.isfinite(loaded.vertices).all(axis=1)
    if bad.any():
        raise InputError(f"{path}: {int(bad.sum()):,} of its {len(bad):,} vertices have coordinates that are not "
                         "finite numbers (NaN or infinite): the file is damaged; export it again", parameter=parameter)
    loaded.process()
    read = ReadMesh(loaded, str(path))
    stated = _to_mm(read)
    _clean(read)
    if watertight:
        require_closed(read.mesh, str(path), parameter)
        if read.mesh.volume < 0:
            read.mesh.invert()
            read.notes.append(f"{path}: the mesh was wound inside-out (negative volume): turned")
    check_object_size(read, stated, units_ok)
    return read


def _check_binary_stl(path: Path, size: int, parameter: str) -> None:
    """A binary STL's declared triangle count against the limit and the file's size (an ASCII STL passes): a
    count that does not fit the size is a damaged (truncated, or mis-written) file."""
    with open(path, "rb") as f:
        head = f.read(STL_TEXT_PROBE)
    if len(head) < 84:
        return
    (count,) = struct.unpack("<I", head[80:84])
    if 84 + 50 * count == size:
        check_size(f"triangles declared in {path}", count, MAX_MESH_TRIANGLES, parameter)
    elif not _is_text_stl(head):
        holds = (f"{(size - 84) // 50:,} triangles" if (size - 84) % 50 == 0 else
                 f"{size - 84:,} bytes of triangles, not a whole number of 50-byte records")
        raise InputError(f"{path}: a binary STL whose header declares {count:,} triangles ({84 + 50 * count:,} "
                         f"bytes), but the file has {size:,} bytes ({holds}): it is truncated or its triangle count "
                         "is wrong; export it again", parameter=parameter)


STL_TEXT_PROBE = 1024
"""Bytes read from the start of an STL to tell ASCII from binary."""


def _is_text_stl(head: bytes) -> bool:
    """Whether the start of an STL is ASCII text beginning with ``solid`` (a binary header may begin so too, but its
    count and records hold bytes that are not text)."""
    text = head.lstrip()
    return text[:5].lower() == b"solid" and not any(b < 32 and b not in b"\t\r\n" for b in head)


OBJ_ZERO_INDEX = re.compile(rb"^[ \t]*f[ \t](?:[^\n]*?[ \t])?0(?=[/ \t\r\n]|$)", re.MULTILINE)
"""An OBJ face line with a vertex index 0 (OBJ counts vertices from 1, or from -1 backwards)."""


def _check_obj_indices(path: Path, parameter: str) -> None:
    """InputError if an OBJ face names vertex 0 (an exporter that counts from 0: trimesh would read it as the last
    vertex and build wrong triangles). The file is searched mapped, not loaded."""
    with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
        found = OBJ_ZERO_INDEX.search(data)
        if found is None:
            return
        end, chunk = found.start(), 1 << 24
        line = 1 + sum(data[i:min(i + chunk, end)].count(b"\n") for i in range(0, end, chunk))
    raise InputError(f"{path}, line {line}: a face names vertex 0, but OBJ numbers vertices from 1: the file was "
                     "written with 0-based indices; export it again (or add 1 to every face index)",
                     parameter=parameter)


def _check_zip(path: Path, parameter: str) -> None:
    """A 3MF (a zip archive) whose members unpack to more than MAX_MESH_FILE_BYTES is refused before unpacking."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as archive:
            unpacked = sum(member.file_size for member in archive.infolist())
    except (zipfile.BadZipFile, OSError) as err:
        raise InputError(f"cannot read {path} as a 3MF mesh (a zip archive): {err}", parameter=parameter) from None
    if unpacked > MAX_MESH_FILE_BYTES:
        raise InputError(f"{path} unpacks to {unpacked:,} bytes, above the limit of {MAX_MESH_FILE_BYTES:,} "
                         "(MAX_MESH_FILE_BYTES)", parameter=parameter)


def _check_gltf_files(path: Path, size: int, parameter: str) -> None:
    """A glTF's external files (buffers and images named by ``uri``; ``data:`` URIs are inside the file) must be
    regular files in its own folder (no ``..``, no absolute path: a file names no device or file elsewhere for the
    reader to read), and the glTF with them within MAX_MESH_FILE_BYTES: checked before any is read."""
    import json
    from urllib.parse import unquote

    try:
        document = json.loads(path.read_bytes())
    except (ValueError, UnicodeDecodeError) as err:
        raise InputError(f"cannot read {path} as a glTF (JSON) mesh: {err}", parameter=parameter) from None
    if not isinstance(document, dict):
        raise InputError(f"cannot read {path} as a glTF mesh: its JSON is not an object", parameter=parameter)
    folder, total = path.parent.resolve(), size
    for kind in ("buffers", "images"):
        entries = document.get(kind, [])
        for entry in entries if isinstance(entries, list) else []:
            uri = entry.get("uri") if isinstance(entry, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:"):
                continue
            target = (folder / unquote(uri)).resolve()
            if Path(unquote(uri)).is_absolute() or folder not in target.parents:
                raise InputError(f"{path} names {uri!r} among its {kind}: a glTF's files must lie in its own folder",
                                 parameter=parameter)
            if not target.is_file():
                raise InputError(f"{path} names {uri!r} among its {kind}, which is not a file beside it: copy the "
                                 "glTF with all its files, or export it as one .glb", parameter=parameter)
            total += target.stat().st_size
    if total > MAX_MESH_FILE_BYTES:
        raise InputError(f"{path} with the files it names is {total:,} bytes, above the limit of "
                         f"{MAX_MESH_FILE_BYTES:,} (MAX_MESH_FILE_BYTES)", parameter=parameter)


def _to_mm(read: ReadMesh) -> str | None:
    """Scale the mesh to mm by the units its file states (noted); returns them (None: none stated, read as mm)."""
    units = getattr(read.mesh, "units", None)
    if not units:
        read.notes.append(f"{read.path}: no units stated: read as mm")
        return None
    scale = UNIT_MM.get(str(units).lower())
    if scale is None:
        raise InputError(f"{read.path} states units {units!r}, which are not a length this tool knows "
                         f"({', '.join(sorted(UNIT_MM))})")
    if scale != 1.0:
        read.mesh.apply_scale(scale)
        read.notes.append(f"{read.path}: units {units}: scaled by {scale:g} to mm")
    return str(units)


MIN_OBJECT_MM = 2.0
MAX_OBJECT_MM = 1000.0
"""Bounds of a mesh's largest extent (mm, its bounding box's longest side) for a touchable object in mm.

The product's objects span a 20 mm tall knob to a 104 mm long handle (examples/textured_objects.py); as for
heightmaps (roughness.surface.units) the bounds lie about ten times beyond them: under 2 mm an object is a
fifth of the 10 mm fingertip footprint, no larger than the features of the coarser textures; over 1 m it is
furniture, not a printed object to texture. A mesh without units in metres (every object under 2 m) or micrometres (every object over 1 mm)
falls outside; in inches or centimetres only objects under 2 inches or 2 cm do: larger ones are read 25.4 or 10
times too small, and only the file's unit (a 3MF states it) can tell."""


def check_object_size(read: ReadMesh, stated: str | None, units_ok: bool = False) -> None:
    """InputError (parameter ``units_ok``) unless the mesh's largest extent (mm) lies within MIN_OBJECT_MM and
    MAX_OBJECT_MM, or ``units_ok`` confirms it is mm."""
    extent = float(np.ptp(read.mesh.vertices, axis=0).max())
    if units_ok or MIN_OBJECT_MM <= extent <= MAX_OBJECT_MM:
        return
    small = extent < MIN_OBJECT_MM
    unit = f"its units {stated!r}" if stated else "no units stated: read as mm"
    likely = ("metres or inches (scale it by 1000 or 25.4)" if small else "micrometres (scale it by 0.001)")
    raise InputError(f"{read.path}: its largest extent is {extent:.3g} mm ({unit}), {'below' if small else 'above'} "
                     f"{MIN_OBJECT_MM if small else MAX_OBJECT_MM:g} mm: implausible for a touchable object (the "
                     f"bounds lie 10 times beyond the product's objects, a 20 mm knob to a 104 mm handle; see "
                     f"roughness.objects.meshes). It looks like {likely}: convert the file to mm (or save it as 3MF "
                     f"with its unit), or pass {CONFIRM} if it really is this size in mm", parameter=CONFIRM)


def _clean(read: ReadMesh) -> None:
    mesh = read.mesh
    if not np.all(np.isfinite(mesh.vertices)):
        raise InputError(f"{read.path} has vertices that are not finite numbers")
    keep = mesh.nondegenerate_faces()
    if not keep.all():
        mesh.update_faces(keep)
        mesh.remove_unreferenced_vertices()
        read.notes.append(f"{read.path}: dropped {int((~keep).sum()):,} degenerate (zero-area) triangles")
    if len(mesh.faces) == 0:
        raise InputError(f"{read.path} has only degenerate (zero-area) triangles")


def require_closed(mesh, what: str, parameter: str | None = "mesh") -> None:
    """InputError unless ``mesh`` is watertight (every edge shared by exactly two faces) and consistently wound."""
    if not mesh.is_watertight:
        open_edges = _open_edges(mesh)
        raise InputError(f"{what} is not watertight ({open_edges:,} edges are not shared by exactly two triangles): "
                         "a textured object must be a closed solid; repair it (e.g. in a slicer or MeshLab) first",
                         parameter=parameter)
    if not mesh.is_winding_consistent:
        raise InputError(f"{what} is not consistently wound (neighbouring triangles face opposite ways): repair it "
                         "first", parameter=parameter)


def _open_edges(mesh) -> int:
    import trimesh

    groups = trimesh.grouping.group_rows(mesh.edges_sorted, require_count=2)
    return len(mesh.edges_sorted) - 2 * len(groups)


@dataclass(frozen=True)
class Written:
    """A mesh file written: its path, triangles, bytes, and the independent check it passed before it was written."""

    path: str
    triangles: int
    bytes: int
    check: SolidCheck

    def line(self) -> str:
        return f"wrote {self.path}: {self.triangles:,} triangles, {self.bytes / 1e6:.1f} MB; {self.check.line()}"


def require_mesh_format(path: str | Path, parameter: str = "out") -> Path:
    """``path`` if its suffix names a mesh format ``write_mesh`` writes (WRITE_SUFFIXES); InputError otherwise."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in WRITE_SUFFIXES:
        raise InputError(f"cannot write {path}: unsupported mesh format {suffix or '(no suffix)'!r}; supported: "
                         f"{', '.join(WRITE_SUFFIXES)}", parameter=parameter)
    return path


def write_mesh(mesh, path: str | Path, overwrite: bool = False, parameter: str = "out",
               progress: Callable[[float], object] | None = None) -> Written:
    """Write ``mesh`` as binary STL or 3MF (mm; both streamed, a 3MF compact: ``threemf``), atomically, after the
    independent check of the mesh as the file will hold it (``roughness.surface.solid``: float32 corners in an STL,
    the 3MF's rounded ones in float64): SimulationError, and nothing written, unless it is a closed solid; refused if
    the file exists and not ``overwrite``. ``progress``: called with the fraction written after each chunk."""
    path = require_mesh_format(path, parameter)
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    if path.suffix.lower() == ".stl":
        check = require_solid(vertices, faces, str(path), np.float32)
        atomic_write(path, lambda tmp: _write_stl(vertices, faces, tmp, progress), overwrite)
    else:
        vertices, faces = threemf.ordered(vertices, faces)
        level = threemf.decimals_needed(vertices, faces)
        vertices = threemf.rounded(vertices, level)
        check = require_solid(vertices, faces, str(path), np.float64)
        atomic_write(path, lambda tmp: threemf.write_3mf(tmp, vertices, faces, level, progress), overwrite)
    return Written(str(path), len(faces), os.path.getsize(path), check)


def _write_stl(vertices: np.ndarray, faces: np.ndarray, tmp: str,
               progress: Callable[[float], object] | None = None) -> None:
    with open(tmp, "wb") as f:
        write_stl(f, vertices, faces, b"roughness textured object, mm", progress)


def stl_bytes(triangles: int) -> int:
    """Size (bytes) of a binary STL of ``triangles``."""
    return 84 + 50 * triangles

