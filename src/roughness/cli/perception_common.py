"""What the `roughness perception` actions share: option types, the stimuli and their true V, the output
folder and the limit on trials."""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from .common import SEED, Number

if TYPE_CHECKING:
    import numpy as np

    from roughness.perception.observer import Observer

PROBABILITY = Number(float, low=0, high=1)
SIGMA = Number(float, low=0, high=10.0)  # observer noise SD on ln(V)/2 (default 0.18): at 10 the answers are random


def number_list(kind: Number, what: str):
    """An argparse type for ``a,b,c``: each parsed by ``kind`` (a common.Number, kept as the type's ``kind``
    attribute), sorted, duplicates dropped."""
    def parse(text: str) -> list:
        try:
            return sorted({kind(v) for v in text.split(",")})
        except argparse.ArgumentTypeError:
            raise argparse.ArgumentTypeError(f"expected comma-separated {what}, each {kind.describe()}, got "
                                             f"{text!r}") from None
    parse.kind = kind
    return parse


def add_truth_args(p: argparse.ArgumentParser) -> None:
    """The stimuli and where their true V comes from (simulate and plan)."""
    p.add_argument("--stimuli", required=True, metavar="TABLE", help="stimuli table (ids -> heightmaps)")
    p.add_argument("--truth", metavar="CSV", help="known V per stimulus (columns stimulus,roughness) instead of "
                                                  "computing it with --engine")
    p.add_argument("--engine", choices=("fem:coarse", "fem:default", "fem:fine", "surrogate", "auto"),
                   default="surrogate", help="engine for the true V (default surrogate)")
    p.add_argument("--cache", metavar="DIR", help="FEM result cache (default: DIR/fem-cache)")


def add_observer_args(p: argparse.ArgumentParser, seed_of: str, outputs: str) -> None:
    """The simulated observer (``--sigma``, ``--lapse``), ``--seed`` (of ``seed_of``) and ``--out`` (``outputs``)."""
    p.add_argument("--sigma", type=SIGMA, default=None,
                   help="the observer's noise SD on the coordinate ln(V)/2 (default 0.18, from the Weber fraction 0.19)")
    p.add_argument("--lapse", type=PROBABILITY, default=0.0,
                   help="the observer's lapse rate: the probability of a random answer (default 0)")
    p.add_argument("--seed", type=SEED, default=0, help=f"seed of {seed_of} (default: %(default)s)")
    p.add_argument("--out", required=True, metavar="DIR", help=f"output folder: {outputs}")


@dataclass(frozen=True)
class ObserverRun:
    """What a simulated observer's command reads first: the stimuli, the observer, the truth if given, the outputs."""

    stimuli: list
    ids: list[str]
    observer: Observer
    truth: np.ndarray | None  # V per stimulus from --truth (None: from the engine)
    files: dict[str, Path]


def observer_run(args: argparse.Namespace, outputs: tuple[str, ...]) -> ObserverRun:
    """The stimuli, the simulated observer (``add_observer_args``), the truth and the output files, checked."""
    from roughness.perception.observer import DEFAULT_SIGMA, Observer
    from roughness.perception.stimuli import read_stimuli

    stimuli = read_stimuli(args.stimuli)
    ids = [s.stimulus for s in stimuli]
    observer = Observer(DEFAULT_SIGMA if args.sigma is None else args.sigma, args.lapse)
    truth = read_truth(args.truth, ids) if args.truth else None
    files = output_files(args.out, outputs, args.overwrite, {"--stimuli": args.stimuli, "--truth": args.truth})
    return ObserverRun(stimuli, ids, observer, truth, files)


def output_files(folder: str, names: tuple[str, ...], overwrite: bool, inputs: dict) -> dict[str, Path]:
    """The output files in ``folder``, checked before any computation (the folder is made by ``made``);
    none of them may be one of ``inputs`` (label -> path)."""
    from roughness.core.files import check_distinct, check_output, check_output_folder

    out = Path(folder)
    check_distinct({"--out": [out, *(out / name for name in names)]}, inputs)
    if not out.is_dir():  # a new folder (its parent must be writable), or a file in the way: refused
        check_output_folder(out, name="out")
        return {name: out / name for name in names}
    return {name: check_output(out / name, overwrite, "out") for name in names}


def made(files: dict[str, Path]) -> dict[str, Path]:
    """``files`` after creating their folder (once the inputs have been read and the work is done)."""
    next(iter(files.values())).parent.mkdir(exist_ok=True)
    return files


def check_trials(args: argparse.Namespace) -> None:
    """--trials x --subjects within MAX_TRIALS, before the subjects' list or any FEM run is made."""
    from roughness.core.limits import MAX_TRIALS, check_size

    check_size(f"trials of all subjects together ({args.trials:,} x {args.subjects:,} subjects)",
               args.trials * args.subjects, MAX_TRIALS, "trials")


def read_truth(path: str, ids: list[str]) -> np.ndarray:
    """V of each stimulus in ``ids`` from a CSV table with columns stimulus,roughness; InputError for ``truth``."""
    import csv

    import numpy as np

    from roughness.core.errors import InputError
    from roughness.perception.trials import listed

    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rows = {r["stimulus"].strip(): float(r["roughness"]) for r in csv.DictReader(f)}
    except FileNotFoundError:
        raise InputError(f"truth file not found: {path}", parameter="truth") from None
    except (KeyError, TypeError, ValueError, AttributeError, csv.Error):  # UnicodeDecodeError is a ValueError
        raise InputError(f"{path}: expected a CSV table with columns stimulus,roughness (numbers)",
                         parameter="truth") from None
    missing = [i for i in ids if i not in rows]
    if missing:
        raise InputError(listed(f"{path}: no roughness for", missing), parameter="truth")
    return np.array([rows[i] for i in ids])
