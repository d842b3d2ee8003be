"""The stimuli table: stimulus ids and the heightmaps they were printed from.

A CSV with a header and one row per stimulus::

    stimulus,file,pixel_mm,height_mm,dataset,texture,seed,params

``stimulus`` (a unique, non-empty id) is required, and each row names its heightmap in one of two ways:

- ``file``: a heightmap file (relative paths are relative to the table's folder) read with
  ``roughness.load_heightmap``; ``pixel_mm`` and ``height_mm`` where the file does not state them;
  ``dataset`` selects a heightmap inside an HDF5 file (a dataset sample, e.g.
  ``samples/<id>/heightmap``);
- ``texture``: a texture the tool makes (``roughness texture list``: ``standard-0.75``, ``flattop-0.3``,
  ``bumps``, or a natural family such as ``knit``) with ``seed`` (default 0) and ``params``
  (``key=value`` pairs separated by ``;``, e.g. ``wale_mm=1.2;height_mm=0.5``).

An optional ``homogeneity`` column gives the stimulus's spread in just-noticeable differences (the
``spread_jnd`` of ``roughness homogeneity``: larger = less homogeneous, >= 0); ``perception fit
--exclude-least-homogeneous`` uses it where given instead of computing it. Other columns are ignored
(e.g. a description). Empty cells are absent values.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

from roughness.core.errors import InputError

from .trials import id_problem, listed


@dataclass(frozen=True)
class Stimulus:
    stimulus: str
    file: Path | None = None
    pixel_mm: float | None = None
    height_mm: float | None = None
    dataset: str | None = None
    texture: str | None = None
    seed: int = 0
    params: dict = field(default_factory=dict)
    homogeneity: float | None = None  # spread in JNDs (larger = less homogeneous), if the table gives it

    def heightmap(self):
        """The stimulus's Heightmap (mm)."""
        if self.file is not None:
            import roughness

            return roughness.load_heightmap(self.file, self.pixel_mm, self.height_mm, self.dataset)
        from roughness.dataset.catalogue import make_texture

        hm, _ = make_texture(self.texture, seed=self.seed, params=self.params)
        return hm

    def plate_heightmap(self, size_mm: float):
        """The stimulus as a square map of side ``size_mm`` (mm) for printing: a texture made at that
        size, or the centre of its file's map (InputError if the map is smaller)."""
        if self.file is None:
            from roughness.dataset.catalogue import make_texture

            hm, _ = make_texture(self.texture, seed=self.seed, size_mm=size_mm, params=self.params)
            return hm
        hm = self.heightmap()
        n = round(size_mm / hm.pixel_mm)
        ny, nx = hm.shape
        if n > min(ny, nx):
            raise InputError(f"stimulus {self.stimulus}: its map ({self.describe()}) is {nx * hm.pixel_mm:g} x "
                             f"{ny * hm.pixel_mm:g} mm, smaller than the {size_mm:g} mm plate", parameter="plate_mm")
        i, j = (ny - n) // 2, (nx - n) // 2
        return type(hm)(hm.heights[i:i + n, j:j + n], hm.pixel_mm)

    def describe(self) -> str:
        if self.file is not None:
            return str(self.file) + (f":{self.dataset}" if self.dataset else "")
        params = ";".join(f"{k}={v}" for k, v in self.params.items())
        return f"{self.texture} (seed {self.seed}{', ' + params if params else ''})"


def read_stimuli(path: str | Path) -> list[Stimulus]:
    """The stimuli of a table, in table order; InputError names the line and the problem."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"stimuli table not found: {path}", parameter="stimuli")
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            reader = csv.DictReader(f, strict=True)
            header = reader.fieldnames or []
            if "stimulus" not in header or not ({"file", "texture"} & set(header)):
                raise InputError(f"{path}: the header needs a 'stimulus' column and a 'file' or 'texture' column "
                                 f"(found {','.join(header) or 'nothing'})", parameter="stimuli")
            out, problems = [], []
            for row in reader:
                try:
                    out.append(_stimulus(row, path.parent))
                except (InputError, ValueError) as err:
                    problems.append(f"line {reader.line_num}: {err}")
    except (csv.Error, UnicodeDecodeError) as err:
        raise InputError(f"{path}: not a readable CSV table ({err})", parameter="stimuli") from None
    if problems:
        raise InputError(listed(f"{path}: bad rows", problems), parameter="stimuli")
    ids = [s.stimulus for s in out]
    repeated = sorted({s for s in ids if ids.count(s) > 1})
    if repeated:
        raise InputError(listed(f"{path}: repeated stimulus ids", repeated), parameter="stimuli")
    if len(out) < 3:
        raise InputError(f"{path}: need at least 3 stimuli, found {len(out)}", parameter="stimuli")
    return out


def _stimulus(row: dict, folder: Path) -> Stimulus:
    if None in row or any(v is None for v in row.values()):
        raise InputError("the number of fields differs from the header's")
    cell = {k: v.strip() for k, v in row.items() if v and v.strip()}
    ident = cell.get("stimulus")
    if not ident:
        raise InputError("empty stimulus id")
    if id_problem(ident):
        raise InputError(id_problem(ident))
    spread = _number(cell, "homogeneity")
    if spread is not None and not (math.isfinite(spread) and spread >= 0):
        raise InputError(f"stimulus {ident!r}: homogeneity (spread in JNDs) must be a finite number >= 0, "
                         f"got {cell['homogeneity']!r}")
    if ("file" in cell) == ("texture" in cell):
        raise InputError(f"stimulus {ident!r} needs exactly one of file or texture")
    if "file" in cell:
        file = Path(cell["file"])
        file = file if file.is_absolute() else folder / file
        if not file.is_file():
            raise InputError(f"stimulus {ident!r}: heightmap file not found: {file}")
        return Stimulus(ident, file=file, pixel_mm=_number(cell, "pixel_mm"), height_mm=_number(cell, "height_mm"),
                        dataset=cell.get("dataset"), homogeneity=spread)
    seed = cell.get("seed", "0")
    if not seed.isdigit():
        raise InputError(f"stimulus {ident!r}: seed must be a whole number >= 0, got {seed!r}")
    return Stimulus(ident, texture=cell["texture"], seed=int(seed), params=_params(ident, cell.get("params", "")),
                    homogeneity=spread)


def _number(cell: dict, name: str) -> float | None:
    if name not in cell:
        return None
    try:
        return float(cell[name])
    except ValueError:
        raise InputError(f"{name} must be a number, got {cell[name]!r}") from None


def _params(ident: str, text: str) -> dict:
    from roughness.dataset.catalogue import parse_params

    items = [t.strip() for t in text.split(";") if t.strip()]
    try:
        return parse_params(items)
    except InputError as err:
        raise InputError(f"stimulus {ident!r}: {err}") from None
