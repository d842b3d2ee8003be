"""Uploaded files: a stated size limit, stored in the tab's session folder, read as the command line reads them.

A heightmap, scan or picture is loaded by the command line's own loader (``roughness.cli.common.load``: the
library's ``roughness.surface.loading`` with the CLI's options), so its checks (sizes before allocation, units,
plausibility) and its messages are the CLI's, word for word. Where the file does not state its pixel size or its
height, ``missing_units`` says which, and the page asks for just those.
"""
from __future__ import annotations

import argparse
import re
from dataclasses import dataclass
from pathlib import Path

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap
from roughness.surface.loading import Loaded

from .sessions import Session

MAX_UPLOAD_BYTES = 256 * 2**20
"""Largest upload (bytes): a 100-megapixel 16-bit heightmap (roughness.core.limits.MAX_HEIGHTMAP_PIXELS) fits."""
MISSING = "the file does not state it"  # the loader's words where a file needs a unit it does not state


@dataclass(frozen=True)
class Opened:
    """A heightmap as loaded from a file, and the record of what loading did (its notes in the CLI's words)."""

    heightmap: Heightmap
    loaded: Loaded

    def notes(self) -> list[str]:
        return self.loaded.lines()


def stored_name(name: str) -> str:
    """``name`` as a plain file name for the session folder: its last part, other characters as '_'."""
    base = re.sub(r"[^A-Za-z0-9._-]", "_", Path(name.replace("\\", "/")).name).lstrip(".")
    return base[-120:] or "upload"


def upload_path(session: Session, name: str, size: int) -> Path:
    """Where the session keeps the uploaded file ``name`` of ``size`` bytes; InputError above the size limit
    (checked before anything is read or written)."""
    if size > MAX_UPLOAD_BYTES:
        raise InputError(f"{name}: {size:,} bytes is above the upload limit of {MAX_UPLOAD_BYTES:,} bytes "
                         f"({MAX_UPLOAD_BYTES // 2**20} MiB)")
    return session.path(stored_name(name))


def reading_args(pixel_mm: float | None = None, height_mm: float | None = None,
                 units_ok: bool = False) -> argparse.Namespace:
    """The command line's reading options (``--pixel-mm``, ``--height-mm``, ``--units-ok``, clean-up off) as a
    parsed namespace, with their flags for messages."""
    from roughness.cli.common import add_reading_args, finish

    parser = argparse.ArgumentParser(add_help=False)
    add_reading_args(parser)
    finish(parser, None)
    args = parser.parse_args([])
    args.pixel_mm, args.height_mm, args.units_ok = pixel_mm, height_mm, units_ok
    return args


def open_heightmap(path: Path, pixel_mm: float | None = None, height_mm: float | None = None,
                   units_ok: bool = False) -> Opened:
    """The heightmap in ``path`` loaded as ``roughness predict FILE --pixel-mm .. --height-mm ..`` loads it
    (InputError with the CLI's message otherwise)."""
    from roughness.cli.common import load

    hm, loaded = load(reading_args(pixel_mm, height_mm, units_ok), str(path))
    return Opened(hm, loaded)


def missing_units(err: InputError) -> tuple[str, ...]:
    """The units (``pixel_mm``, ``height_mm``) that ``err`` says the file lacks; () for any other error."""
    text = str(err)
    if MISSING not in text:
        return ()
    return tuple(name for name, flag in (("pixel_mm", "--pixel-mm"), ("height_mm", "--height-mm"))
                 if flag in text or name in text)
