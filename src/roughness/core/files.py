"""Writing files safely: refuse to replace outputs unasked, never leave a partial file."""
from __future__ import annotations

import csv
import errno
import os
import re
import shutil
import tempfile
from collections.abc import Callable, Iterable, Mapping, Sequence
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


PathLike = str | os.PathLike
NO_SPACE = (errno.ENOSPC, errno.EDQUOT)
LOW_SPACE_BYTES = 1 << 20  # a write that stops short with less than this free in its folder: the device is full
NO_HARD_LINKS = (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.ENOSYS, errno.EMLINK)


def check_distinct(outputs: Mapping[str, PathLike | Iterable[PathLike] | None],
                   inputs: Mapping[str, PathLike | Iterable[PathLike] | None] | None = None) -> None:
    """Refuse an output that is also an input (always: ``overwrite`` never replaces an input), and two
    outputs that name the same file. Keys label the paths in the message (the caller's flags or parameter
    names); a key may hold several paths or None. Paths are compared with symlinks resolved and, when both
    exist, as files (hard links, case-insensitive file systems). Call before any computation."""
    inputs = [(label, p) for label, value in (inputs or {}).items() for p in _paths(value)]
    seen: list[tuple[str, PathLike]] = []
    for label, path in ((label, p) for label, value in outputs.items() for p in _paths(value)):
        for input_label, input_path in inputs:
            if _same_path(path, input_path):
                raise InputError(f"{label} {path} is also an input ({input_label} {input_path}): an output never "
                                 "replaces an input, even with --overwrite; choose another output", parameter=label)
        for other_label, other in seen:
            if _same_path(path, other):
                raise InputError(f"{other_label} and {label} name the same file {path}: one output would replace the "
                                 "other; choose two names", parameter=label)
        seen.append((label, path))


def _paths(value: PathLike | Iterable[PathLike] | None) -> list[PathLike]:
    if value is None:
        return []
    return [value] if isinstance(value, (str, os.PathLike)) else list(value)


def _same_path(a: PathLike, b: PathLike) -> bool:
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet)
        return False


def atomic_write(path: str | Path, write: Callable[[str], object], overwrite: bool = True) -> Path:
    """Call ``write`` on a temporary file beside ``path`` (same suffix), then publish it as ``path``.

    Readers see the old file or the whole new one, never a partial one; the temporary file is
    removed on any error (including KeyboardInterrupt). Permissions follow the umask. Unless
    ``overwrite``, the file is published with a hard link, which fails if ``path`` exists: of
    concurrent writers exactly one wins, the others get OutputExists. A write that fails (a full
    disk, a file size limit) is an InputError "cannot write PATH: <why>".
    """
    path = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    except OSError as err:
        raise InputError(f"cannot write {path}: {_why(err, path.parent)}") from err
    os.close(fd)
    try:
        os.chmod(tmp, 0o666 & ~_umask())
        try:
            write(tmp)
        except OSError as err:
            raise InputError(f"cannot write {path}: {_why(err, path.parent)}") from err
        _publish(tmp, path, overwrite)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _publish(tmp: str, path: Path, overwrite: bool) -> None:
    """Rename ``tmp`` to ``path``; unless ``overwrite``, without ever replacing a file (OutputExists)."""
    if not overwrite:
        try:
            os.link(tmp, path)
        except FileExistsError:
            raise OutputExists(path) from None
        except OSError as err:
            if err.errno not in NO_HARD_LINKS:
                raise
            # no hard links on this file system (FAT, some network shares): check, then rename;
            # a concurrent writer can still slip in between the two
            if os.path.lexists(path):
                raise OutputExists(path) from None
        else:
            os.unlink(tmp)
            return
    os.replace(tmp, path)


def _why(err: OSError, folder: Path) -> str:
    """Why a write failed, in words (numpy reports a short write without an errno: told by the free space)."""
    if err.errno in NO_SPACE:
        return "no space left on device"
    if err.errno is None:
        try:
            full = shutil.disk_usage(folder).free < LOW_SPACE_BYTES
        except OSError:
            full = False
        return "no space left on device" if full else f"the write stopped short ({err})"
    if err.errno == errno.EFBIG:
        return "file too large (for the file system, or over this process's file size limit)"
    return err.strerror.lower() if err.strerror else str(err)


FORMULA_START = ("=", "+", "-", "@", "\t", "\r")  # a spreadsheet may run a cell starting so as a formula
_PLAIN_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


def formula_like(text: str) -> bool:
    """Whether a spreadsheet could read ``text`` as a formula: it starts with one of FORMULA_START and is
    not a plain number (``-0.5``, ``+1e-3`` are numbers to a spreadsheet, and stay as they are)."""
    return text.startswith(FORMULA_START) and not _PLAIN_NUMBER.fullmatch(text)


def write_csv(path: str | Path, header: Sequence[str], rows: Iterable[Sequence[object]],
              overwrite: bool = True) -> Path:
    """A UTF-8 CSV file (LF line ends) of a header and rows, written atomically (``atomic_write``).

    Text cells that a spreadsheet could run as a formula (``formula_like``) are written with a leading
    ``'`` so they open as text; numbers, and text that is a plain number, are written unchanged.
    """
    rows = [[_cell(value) for value in row] for row in rows]

    def write(tmp: str) -> None:
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            out = csv.writer(f, lineterminator="\n")
            out.writerow([_cell(name) for name in header])
            out.writerows(rows)

    return atomic_write(path, write, overwrite)


def _cell(value: object) -> object:
    return "'" + value if isinstance(value, str) and formula_like(value) else value


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask
