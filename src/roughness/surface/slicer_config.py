"""Fuzzy skin settings and the printer's layer and line from a slicer's exported config, read as data.

PrusaSlicer ``.ini`` (``key = value`` lines): ``fuzzy_skin_thickness``, ``fuzzy_skin_point_dist``,
``layer_height``, ``nozzle_diameter`` (the first extruder's) and ``external_perimeter_extrusion_width`` (mm; a
percentage is of the layer height; 0: ``extrusion_width``, else 1.125 x nozzle). OrcaSlicer ``.json`` (an object of
strings): ``fuzzy_skin_thickness``, ``fuzzy_skin_point_distance``, the noise keys (``fuzzy_skin_noise_type``,
``fuzzy_skin_scale``, ``fuzzy_skin_octaves``, ``fuzzy_skin_persistence``, ``fuzzy_skin_mode``; OrcaSlicer's defaults
where absent), ``layer_height``, ``nozzle_diameter``, ``outer_wall_line_width`` (a percentage is of the nozzle) and
``wall_generator`` (its classic generator ignores ``fuzzy_skin_mode``: judged as displacement, with a note).
Only these keys are read; a missing or bad one is an InputError naming it and the file.

A ``.3mf`` project (a zip archive) is read for its embedded print config: PrusaSlicer's ``Metadata/Slic3r_PE.config``
(the .ini's lines, each commented out as ``; key = value``: PrusaSlicer 2.9, src/libslic3r/Format/3mf.cpp,
``_add_print_config_file_to_archive``), or OrcaSlicer's and Bambu Studio's ``Metadata/project_settings.config`` (the
.json's object). The member's declared size is checked before it is unpacked, and no more than that is unpacked;
nothing else in the archive is read (per-object settings and painted fuzzy skin are not: said in a note).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

from roughness.core.errors import InputError

from .fuzzy_skin import FuzzySkin
from .printing import AUTO_WIDTH, MAX_PROFILE_BYTES, PROFILES, FdmProfile

MAX_CONFIG_BYTES = 4 * MAX_PROFILE_BYTES  # a slicer's full exported config is some 20-60 kB
MAX_EMBEDDED_BYTES = 64 * MAX_PROFILE_BYTES  # a 3MF's embedded config (Orca's holds every preset: ~100 kB)
MAX_PROJECT_BYTES = 2**31  # a 3MF project: its meshes are not read, but its zip directory is
PROJECT_CONFIGS = {"Metadata/project_settings.config": "json", "Metadata/Slic3r_PE.config": "ini"}
OBJECT_CONFIGS = ("Metadata/model_settings.config", "Metadata/Slic3r_PE_model.config")  # per-object overrides
_CLOSING = PROFILES["fdm-0.4-0.2"].closing_radius_mm  # PrusaSlicer's slice_closing_radius (no effect on a wall)


@dataclass(frozen=True)
class SlicerSettings:
    """What a slicer config says about a fuzzy-skin wall, and what it leaves out (notes)."""

    skin: FuzzySkin
    profile: FdmProfile
    notes: tuple[str, ...]


def read_slicer_config(path: str | Path) -> SlicerSettings:
    """The fuzzy skin and printer of a PrusaSlicer .ini or OrcaSlicer .json config, or of a .3mf project's embedded
    config."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"slicer config {path} does not exist", parameter="config")
    if not path.is_file():
        raise InputError(f"slicer config {path} is not a file", parameter="config")
    suffix = path.suffix.lower()
    if suffix == ".3mf":
        return _project(path)
    if suffix not in (".ini", ".json"):
        raise InputError(f"slicer config {path}: a PrusaSlicer .ini, an OrcaSlicer .json or a .3mf project expected",
                         parameter="config")
    if path.stat().st_size > MAX_CONFIG_BYTES:
        raise InputError(f"slicer config {path}: {path.stat().st_size:,} bytes, above {MAX_CONFIG_BYTES:,}",
                         parameter="config")
    return _parse(_text(path.read_bytes(), path), suffix[1:], path)


def _text(data: bytes, path: Path) -> str:
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise InputError(f"slicer config {path} is not UTF-8 text: {err}", parameter="config") from None


def _parse(text: str, kind: str, path: Path, commented: bool = False) -> SlicerSettings:
    """The settings of a config's text: ``kind`` "ini" (PrusaSlicer; ``commented``: each line as ``; key = value``,
    as in a 3MF) or "json" (OrcaSlicer)."""
    if kind == "ini":
        return _prusa(_ini(text, commented), path)
    try:
        data = json.loads(text)
    except (ValueError, RecursionError) as err:
        raise InputError(f"slicer config {path} is not valid JSON: {err}", parameter="config") from None
    if not isinstance(data, dict):
        raise InputError(f"slicer config {path}: a JSON object of settings expected", parameter="config")
    return _orca(data, path)


def _project(path: Path) -> SlicerSettings:
    """The settings embedded in a 3MF project (module docstring), each size checked before anything is unpacked."""
    import zipfile

    if path.stat().st_size > MAX_PROJECT_BYTES:
        raise InputError(f"3MF project {path}: {path.stat().st_size:,} bytes, above {MAX_PROJECT_BYTES:,}",
                         parameter="config")
    try:
        with zipfile.ZipFile(path) as archive:
            names = set(archive.namelist())
            member = next((m for m in PROJECT_CONFIGS if m in names), None)
            if member is None:
                raise InputError(f"3MF project {path} has no slicer config ({' or '.join(PROJECT_CONFIGS)}): save "
                                 "the project from PrusaSlicer, OrcaSlicer or Bambu Studio, or export the config "
                                 "(.ini or .json) and give that", parameter="config")
            info = archive.getinfo(member)
            if info.file_size > MAX_EMBEDDED_BYTES:
                raise InputError(f"3MF project {path}: {member} unpacks to {info.file_size:,} bytes, above "
                                 f"{MAX_EMBEDDED_BYTES:,} (a config is some 100 kB): not unpacked", parameter="config")
            with archive.open(info) as f:  # zipfile unpacks no more than the declared size (then checks the CRC)
                data = f.read()
    except (zipfile.BadZipFile, OSError, EOFError, RuntimeError, NotImplementedError) as err:
        raise InputError(f"cannot read {path} as a 3MF project (a zip archive): {err}", parameter="config") from None
    read = _parse(_text(data, path), PROJECT_CONFIGS[member], path, commented=True)
    notes = (f"read {member} of the 3MF project",)
    overrides = [m for m in OBJECT_CONFIGS if m in names]
    if overrides:
        notes += (f"the project has per-object settings ({', '.join(overrides)}), which may change fuzzy skin for an "
                  "object: not read (nor painted fuzzy skin); these are the project's print settings",)
    return replace(read, notes=notes + read.notes)


def _ini(text: str, commented: bool = False) -> dict[str, str]:
    """``key = value`` lines (``commented``: only those written ``; key = value``, the marker removed)."""
    values = {}
    for line in text.splitlines():
        line = line.strip()
        if commented:
            if not line.startswith(";"):
                continue
            line = line[1:]
        elif line.startswith(("#", ";")):
            continue
        key, sep, value = line.partition("=")
        if sep:
            values[key.strip()] = value.strip()
    return values


def _number(values: dict, key: str, path: Path, percent_of: float | None = None) -> float:
    """The finite number (or percentage of ``percent_of``) at ``key``; the first of a list or comma list."""
    if key not in values:
        raise InputError(f"slicer config {path}: {key} is missing", parameter="config")
    raw = values[key]
    if isinstance(raw, list):
        raw = raw[0] if raw else ""
    text = str(raw).split(",")[0].strip()
    scale = 1.0
    if percent_of is not None and text.endswith("%"):
        text, scale = text[:-1], percent_of / 100
    try:
        value = float(text) * scale
    except ValueError:
        value = math.nan
    if isinstance(raw, bool) or not math.isfinite(value):
        raise InputError(f"slicer config {path}: {key} must be a number, got {values[key]!r}", parameter="config")
    return value


def _profile(path: Path, nozzle: float, layer: float, width: float, source: str) -> FdmProfile:
    try:
        return FdmProfile(path.name, nozzle, layer, width, _CLOSING, f"{source} config {path.name}")
    except InputError as err:
        raise InputError(f"slicer config {path}: {err}", parameter="config") from None


def _skin(path: Path, **settings) -> FuzzySkin:
    try:
        return FuzzySkin(**settings)
    except InputError as err:
        raise InputError(f"slicer config {path}: {err}", parameter="config") from None


def _off_note(values: dict) -> tuple[str, ...]:
    state = str(values.get("fuzzy_skin", "")).strip()
    return (f"the config has fuzzy_skin = {state} (off): its fuzzy skin settings are judged as if it were on",) \
        if state == "none" else ()


def _prusa(values: dict[str, str], path: Path) -> SlicerSettings:
    nozzle = _number(values, "nozzle_diameter", path)
    layer = _number(values, "layer_height", path)
    width = _number(values, "external_perimeter_extrusion_width", path, layer) \
        if "external_perimeter_extrusion_width" in values else 0.0
    if width == 0 and "extrusion_width" in values:
        width = _number(values, "extrusion_width", path, layer)
    width = width or AUTO_WIDTH * nozzle
    skin = _skin(path, fuzzy_skin_thickness=_number(values, "fuzzy_skin_thickness", path),
                 fuzzy_skin_point_distance=_number(values, "fuzzy_skin_point_dist", path))
    return SlicerSettings(skin, _profile(path, nozzle, layer, width, "PrusaSlicer"), _off_note(values))


def _orca(values: dict, path: Path) -> SlicerSettings:
    nozzle = _number(values, "nozzle_diameter", path)
    layer = _number(values, "layer_height", path)
    width = _number(values, "outer_wall_line_width", path, nozzle) if "outer_wall_line_width" in values else 0.0
    width = width or AUTO_WIDTH * nozzle
    default = FuzzySkin()
    octaves = _number(values, "fuzzy_skin_octaves", path) if "fuzzy_skin_octaves" in values \
        else default.fuzzy_skin_octaves
    if octaves != int(octaves):
        raise InputError(f"slicer config {path}: fuzzy_skin_octaves must be a whole number, got {octaves:g}",
                         parameter="config")
    skin = _skin(path, fuzzy_skin_thickness=_number(values, "fuzzy_skin_thickness", path),
                 fuzzy_skin_point_distance=_number(values, "fuzzy_skin_point_distance", path),
                 fuzzy_skin_noise_type=str(values.get("fuzzy_skin_noise_type", default.fuzzy_skin_noise_type)),
                 fuzzy_skin_scale=_number(values, "fuzzy_skin_scale", path) if "fuzzy_skin_scale" in values
                 else default.fuzzy_skin_scale, fuzzy_skin_octaves=int(octaves),
                 fuzzy_skin_persistence=_number(values, "fuzzy_skin_persistence", path)
                 if "fuzzy_skin_persistence" in values else default.fuzzy_skin_persistence,
                 fuzzy_skin_mode=str(values.get("fuzzy_skin_mode", default.fuzzy_skin_mode)))
    notes = _off_note(values)
    if skin.fuzzy_skin_mode != "displacement" and values.get("wall_generator") == "classic":
        notes += (f"fuzzy_skin_mode {skin.fuzzy_skin_mode} applies to Arachne walls only; with wall_generator = classic "
                  "OrcaSlicer displaces the points (judged so)",)
        skin = replace(skin, fuzzy_skin_mode="displacement")
    return SlicerSettings(skin, _profile(path, nozzle, layer, width, "OrcaSlicer"), notes)
