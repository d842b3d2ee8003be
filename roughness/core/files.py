"""Writing files safely: refuse to replace outputs unasked, never leave a partial file."""
from __future__ import annotations

import csv
import os
import re
import tempfile
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from .errors import InputError, OutputExists


def check_output(path: str | Path, overwrite: bool = False, name: str = "out") -> Path:
    """``path`` if it may be written: its folder exists and is writable, and it does not exist
    unless ``overwrite``. Call before any computation, so that nothing is lost at the end."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path} is a folder, not a file", parameter=name)
    if path.exists() and not overwrite:
        raise OutputExists(path, name)
    parent = path.parent
    if not parent.is_dir():
        raise InputError(f"cannot write {path}: folder {parent} does not exist", parameter=name)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"cannot write {path}: folder {parent} is not writable", parameter=name)
    return path


def check_output_folder(path: str | Path, overwrite: bool = False, name: str = "out") -> Path:
    """``path`` if it may become an output folder: new, empty, or (with ``overwrite``) any folder,
    inside a folder that exists and is writable. Call before any computation."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"{path} is a file, not a folder", parameter=name)
    if path.is_dir() and any(path.iterdir()) and not overwrite:
        raise OutputExists(path, name)
    parent = path.resolve().parent
    if not path.exists() and not parent.is_dir():
        raise InputError(f"cannot create {path}: folder {parent} does not exist", parameter=name)
    if not os.access(path if path.exists() else parent, os.W_OK | os.X_OK):
        raise InputError(f"cannot write into {path if path.exists() else parent}: not writable", parameter=name)
    return path


def atomic_write(path: str | Path, write: Callable[[str], object]) -> Path:
    """Call ``write`` on a temporary file beside ``path`` (same suffix), then rename it over ``path``.

    Readers see the old file or the whole new one, never a partial one; the temporary file is
    removed on any error (including KeyboardInterrupt). Permissions follow the umask.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(fd)
    try:
        os.chmod(tmp, 0o666 & ~_umask())
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


FORMULA_START = ("=", "+", "-", "@", "\t", "\r")  # a spreadsheet may run a cell starting so as a formula
_PLAIN_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


def formula_like(text: str) -> bool:
    """Whether a spreadsheet could read ``text`` as a formula: it starts with one of FORMULA_START and is
    not a plain number (``-0.5``, ``+1e-3`` are numbers to a spreadsheet, and stay as they are)."""
    return text.startswith(FORMULA_START) and not _PLAIN_NUMBER.fullmatch(text)


def write_csv(path: str | Path, header: Sequence[str], rows: Iterable[Sequence[object]]) -> Path:
    """A UTF-8 CSV file (LF line ends) of a header and rows, written atomically.

    Text cells that a spreadsheet could run as a formula (``formula_like``) are written with a leading
    ``'`` so they open as text; numbers, and text that is a plain number, are written unchanged.
    """
    rows = [[_cell(value) for value in row] for row in rows]

    def write(tmp: str) -> None:
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            out = csv.writer(f, lineterminator="\n")
            out.writerow([_cell(name) for name in header])
            out.writerows(rows)

    return atomic_write(path, write)


def _cell(value: object) -> object:
    return "'" + value if isinstance(value, str) and formula_like(value) else value


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask
