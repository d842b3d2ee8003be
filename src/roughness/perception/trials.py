"""Triplet trials files: reading, validating and writing them.

A trials file is a CSV with a header and one row per judgement::

    subject,reference,left,right,answer[,any extra columns]

``reference``, ``left`` and ``right`` are stimulus ids (non-empty strings, three different ones in a
row); ``answer`` is ``left`` or ``right``: the comparison that felt closer in roughness to the
reference. Extra columns (response time, trial number, ...) are kept and written back unchanged.

A row answers the triplet (reference, closer, farther). Two rows of one subject on the same
reference and the same pair of comparisons that give opposite answers are *contradictory
duplicates*. Repeated trials with different answers are normal in psychophysics (and what
``perception simulate`` writes): both answers are used by default (``repeats="keep"``);
``repeats="error"`` refuses them, to catch a data-entry or merge mistake in data with no repeats.
"""
from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.core.files import formula_like, write_csv

COLUMNS = ("subject", "reference", "left", "right", "answer")
ANSWERS = ("left", "right")
REPEATS = ("error", "keep")
MAX_LISTED = 5  # problems listed in one error message


@dataclass(frozen=True)
class Trials:
    """Validated judgements: stimulus ids and, per row, the triplet (reference, closer, farther) as indices."""

    stimuli: tuple[str, ...]
    triplets: np.ndarray  # (rows, 3) int: reference, closer, farther (indices into ``stimuli``)
    subjects: tuple[str, ...]  # per row
    rows: tuple[dict[str, str], ...]  # the rows as read, extra columns included
    fieldnames: tuple[str, ...]

    def __len__(self) -> int:
        return len(self.triplets)

    def unique(self) -> tuple[np.ndarray, np.ndarray]:
        """(distinct triplets (U, 3), index of each row's triplet in them (rows,))."""
        keys, inverse = np.unique(self.triplets, axis=0, return_inverse=True)
        return keys, inverse.reshape(-1)

    def groups(self) -> tuple[tuple[str, ...], ...]:
        """The stimuli in groups never compared with each other (the connected components of the graph whose
        edges join each trial's reference to its comparisons), largest first; one group if the design is connected."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        n = len(self.stimuli)
        ref = np.repeat(self.triplets[:, 0], 2)
        graph = coo_matrix((np.ones(len(ref)), (ref, self.triplets[:, 1:].ravel())), shape=(n, n))
        count, label = connected_components(graph, directed=False)
        groups = [tuple(s for s, g in zip(self.stimuli, label) if g == k) for k in range(count)]
        return tuple(sorted(groups, key=len, reverse=True))


def read_trials(path: str | Path, stimuli: Sequence[str] | None = None, repeats: str = "keep") -> Trials:
    """Trials from a CSV file; ``stimuli`` (ids of a stimuli table), when given, must contain every id used."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"trials file not found: {path}", parameter="trials")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{path}: cannot read the trials file as UTF-8 text ({err})", parameter="trials") from None
    return parse_trials(text, str(path), stimuli, repeats)


def parse_trials(text: str, source: str = "trials", stimuli: Sequence[str] | None = None,
                 repeats: str = "keep") -> Trials:
    """Trials from CSV text; InputError names the file, the line and the problem."""
    if repeats not in REPEATS:
        raise InputError(f"repeats must be one of {', '.join(REPEATS)}, got {repeats!r}", parameter="repeats")
    reader = csv.DictReader(io.StringIO(text), strict=True)
    try:
        header = tuple(reader.fieldnames or ())
    except csv.Error as err:
        raise InputError(f"{source}: not a CSV file ({err})", parameter="trials") from None
    if not header:
        raise InputError(f"{source}: empty file; expected the header {','.join(COLUMNS)}", parameter="trials")
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise InputError(f"{source}: missing column(s) {', '.join(missing)}; the header must contain "
                         f"{','.join(COLUMNS)} (found {','.join(header)})", parameter="trials")
    if len(set(header)) != len(header):
        raise InputError(f"{source}: repeated column names in the header", parameter="trials")
    rows, problems = [], []
    try:
        for row in reader:
            line = reader.line_num
            problem = _row_problem(row, len(header))
            if problem:
                problems.append(f"line {line}: {problem}")
            else:
                rows.append((line, {k: v.strip() for k, v in row.items()}))
    except csv.Error as err:
        problems.append(f"line {reader.line_num}: {err}")
    if problems:
        raise InputError(listed(f"{source}: malformed rows", problems), parameter="trials")
    if not rows:
        raise InputError(f"{source}: no trials (a header and no rows)", parameter="trials")
    used = sorted({row[c] for _, row in rows for c in ("reference", "left", "right")})
    if stimuli is not None:
        unknown = [s for s in used if s not in set(stimuli)]
        if unknown:
            raise InputError(listed(f"{source}: stimuli not in the stimuli table", unknown), parameter="trials")
        ids = tuple(s for s in stimuli if s in set(used))  # table order; stimuli without trials are not embedded
    else:
        ids = tuple(used)
    index = {s: i for i, s in enumerate(ids)}
    triplets = np.array([_triplet(row, index) for _, row in rows], dtype=np.int64)
    if repeats == "error":
        _refuse_contradictions(source, [line for line, _ in rows], [row["subject"] for _, row in rows], triplets)
    return Trials(ids, triplets, tuple(row["subject"] for _, row in rows), tuple(row for _, row in rows), header)


def _row_problem(row: dict, width: int) -> str | None:
    if None in row:
        return f"{width + len(row[None])} fields, the header has {width}"
    if any(v is None for v in row.values()):
        return f"fewer fields than the header's {width}"
    empty = [c for c in COLUMNS if not row[c].strip()]
    if empty:
        return f"empty {', '.join(empty)}"
    answer = row["answer"].strip()
    if answer not in ANSWERS:
        return f"answer must be 'left' or 'right' (the comparison closer to the reference), got {answer!r}"
    ref, left, right = (row[c].strip() for c in ("reference", "left", "right"))
    if len({ref, left, right}) < 3:
        return f"reference, left and right must be three different stimuli, got {ref!r}, {left!r}, {right!r}"
    return next((id_problem(s) for s in (ref, left, right) if id_problem(s)), None)


def id_problem(ident: str) -> str | None:
    """Why a stimulus id is refused (None: it is fine): one that a spreadsheet could run as a formula
    (``roughness.core.files.formula_like``), since ids are written into the CSV files the tools make."""
    if formula_like(ident):
        return (f"stimulus id {ident!r} starts with {ident[0]!r}, so a spreadsheet opening the results could run "
                "it as a formula; rename it (ids that are plain numbers, such as -1, are fine)")
    return None


def _triplet(row: dict[str, str], index: dict[str, int]) -> tuple[int, int, int]:
    closer, farther = (row["left"], row["right"]) if row["answer"] == "left" else (row["right"], row["left"])
    return index[row["reference"]], index[closer], index[farther]


def _refuse_contradictions(source: str, lines: list[int], subjects: list[str], triplets: np.ndarray) -> None:
    first: dict[tuple, tuple[int, int]] = {}
    problems = []
    for line, subject, (r, c, f) in zip(lines, subjects, triplets.tolist()):
        key = (subject, r, min(c, f), max(c, f))
        if key in first and first[key][1] != c:
            problems.append(f"line {line} contradicts line {first[key][0]} (subject {subject!r})")
        first.setdefault(key, (line, c))
    if problems:
        raise InputError(listed(f"{source}: contradictory duplicates (same subject, reference and pair, opposite "
                                 "answers; refused by --repeats error)",
                                 problems),
                         parameter="trials")


def disconnection_warning(groups: Sequence[Sequence[str]]) -> str | None:
    """A warning naming the groups of stimuli never compared with each other, or None for one group."""
    if len(groups) < 2:
        return None
    named = " | ".join(", ".join(g[:MAX_LISTED]) + (f" and {len(g) - MAX_LISTED} more" if len(g) > MAX_LISTED else "")
                       for g in groups[:MAX_LISTED])
    more = f" | and {len(groups) - MAX_LISTED} more groups" if len(groups) > MAX_LISTED else ""
    return (f"the trials fall into {len(groups)} groups of stimuli never compared with each other ({named}{more}): "
            "the embedding cannot place one group against another (their relative positions are arbitrary and "
            "a group may collapse to a point); add trials that compare stimuli across the groups")


def listed(what: str, items: list[str]) -> str:
    """``what: a; b; c and 4 more``: an error message listing the first problems."""
    more = f" and {len(items) - MAX_LISTED} more" if len(items) > MAX_LISTED else ""
    return f"{what}: {'; '.join(items[:MAX_LISTED])}{more}"


def write_trials(path: str | Path, rows: Iterable[dict[str, object]], fieldnames: Sequence[str],
                 overwrite: bool = True) -> Path:
    """Write rows (dicts with at least COLUMNS) as a trials CSV, atomically (``write_csv``: text that a
    spreadsheet could run as a formula is written as text; ``path`` is replaced only if ``overwrite``)."""
    return write_csv(path, fieldnames, ([row.get(name, "") for name in fieldnames] for row in rows), overwrite)
