"""Helpers shared by the subcommands: argument types, progress messages, flag checks."""
from __future__ import annotations

import argparse
import inspect
import json
import math
import os
import re
import sys
from typing import TYPE_CHECKING

from roughness.core.errors import InputError, OutputExists
from roughness.core.limits import (
    MAX_BATCH,
    MAX_CHANNELS,
    MAX_FORCE_N,
    MAX_HEIGHT_MM,
    MAX_JND,
    MAX_LENGTH_MM,
    MAX_PARALLEL,
    MAX_PIXEL_MM,
    MAX_SCALE_FACTOR,
    MAX_WAVELENGTH_MM,
)
from roughness.surface.cleanup import LEVELS, MAX_DESPIKE, MAX_FILL_FRACTION

if TYPE_CHECKING:
    from roughness.surface.heightmap import Heightmap
    from roughness.surface.loading import Loaded


def float_pair(text: str) -> tuple[float, float]:
    """``X,Y`` in mm, both finite, for argparse."""
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y in mm, got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise argparse.ArgumentTypeError(f"expected X,Y in mm, two finite numbers, got {text!r}")
    return x, y


def count_list(text: str) -> tuple[int, ...]:
    """``A,B,...``: positive integers (e.g. channel widths), for argparse."""
    try:
        values = tuple(int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated positive integers, got {text!r}") from None
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"expected comma-separated positive integers, got {text!r}")
    if max(values) > MAX_CHANNELS:
        raise argparse.ArgumentTypeError(f"{max(values):,} is above the limit of {MAX_CHANNELS:,} "
                                         f"({MAX_CHANNELS.name})")
    return values


class Number:
    """An argparse type for a number with a declared domain; ``invalid`` lists values it refuses.

    Every numeric option uses one with an upper bound (tests/test_bad_inputs.py sweeps each option's
    ``invalid`` values through the whole CLI), so no option accepts NaN, infinity or an out-of-range
    value, nor a size that nothing touchable needs. A bound that is a named limit (roughness.core.limits)
    is shown with its name.
    """

    def __init__(self, kind: type, low: float | None = None, high: float | None = None,
                 low_open: bool = False, high_open: bool = False) -> None:
        self.kind, self.low, self.high, self.low_open, self.high_open = kind, low, high, low_open, high_open
        self.__name__ = self.describe()  # argparse names the type in its messages

    def describe(self) -> str:
        what = "an integer" if self.kind is int else "a number"
        parts = []
        for bound, sign in ((self.low, ">" if self.low_open else ">="), (self.high, "<" if self.high_open else "<=")):
            if bound is not None:
                parts.append(f"{sign} {_bound_text(bound)}")
        return what + (" " + " and ".join(parts) if parts else "")

    def __call__(self, text: str) -> int | float:
        try:
            value = self.kind(text)
        except (TypeError, ValueError):
            raise argparse.ArgumentTypeError(f"expected {self.describe()}, got {text!r}") from None
        if self.kind is float and not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
        too_low = self.low is not None and (value <= self.low if self.low_open else value < self.low)
        too_high = self.high is not None and (value >= self.high if self.high_open else value > self.high)
        if too_low or too_high:
            raise argparse.ArgumentTypeError(f"expected {self.describe()}, got {text!r}")
        return value

    @property
    def invalid(self) -> list[str]:
        """Values this type must refuse: not numbers, not finite, just outside the domain."""
        out = ["abc", "", "nan", "inf"] + (["1.5"] if self.kind is int else [])
        for bound, is_open, sign in ((self.low, self.low_open, -1), (self.high, self.high_open, 1)):
            if bound is not None:
                out.append(_just_outside(self.kind, bound, is_open, sign))
        return out


def _just_outside(kind: type, bound: float, is_open: bool, sign: int) -> str:
    """The text of the value just outside ``bound`` (the bound itself if open; ``sign`` +1: above, -1: below)."""
    if kind is int:
        return str(int(bound) + sign * (0 if is_open else 1))  # exact at any size (.12g would print 9.2e+18)
    return f"{bound:g}" if is_open else f"{bound + sign * 1e-9 * max(1.0, abs(bound)):.12g}"


def _bound_text(bound: float) -> str:
    """A bound for messages: ``<= 10,000 (MAX_WINDOWS)`` for a named limit, else the number."""
    name = getattr(bound, "name", None)
    if not isinstance(bound, int):
        number = f"{bound:g}"
    else:
        number = f"{bound:,}" if name else str(bound)
    return f"{number} ({name})" if name else number


def positive(high: float) -> Number:
    """A number > 0 and <= ``high``."""
    return Number(float, low=0, high=high, low_open=True)


def count(high: int, low: int = 1) -> Number:
    """A whole number from ``low`` to ``high``."""
    return Number(int, low=low, high=high)


# The option domains the commands share; each upper end is what a touchable texture or object can need (the
# physical ones are roughness.core.limits' bounds, with their reasons there).
SEED = Number(int, low=0, high=2**32 - 1)
POISSON = Number(float, low=-1, high=0.5, low_open=True, high_open=True)
FRACTION = Number(float, low=0, high=1, low_open=True, high_open=True)
BATCH = count(MAX_BATCH)
PARALLEL = count(MAX_PARALLEL)  # threads or worker processes
LENGTH = positive(MAX_LENGTH_MM)  # mm: sizes, steps, widths, radii of textures, plates and objects
PIXEL = positive(MAX_PIXEL_MM)
HEIGHT = positive(MAX_HEIGHT_MM)
FORCE = positive(MAX_FORCE_N)
WAVELENGTH = positive(MAX_WAVELENGTH_MM)  # an equivalent wavelength on the standard scale (mm)
FACTOR = positive(MAX_SCALE_FACTOR)  # a scale factor of a texture's heights or lateral size
JND = positive(MAX_JND)  # a distance in JND of equivalent wavelength
# Textures of a palette, colours of a tactile image: --min-jnd apart on the 22 JND from the standard scale's floor
# to the footprint, a palette holds tens at most.
MAX_PALETTE = 100


def add_heightmap_args(p: argparse.ArgumentParser) -> None:
    """The heightmap input and how to read it (one file)."""
    p.add_argument("heightmap", metavar="HEIGHTMAP", help="heightmap file: .npy (mm), 8/16-bit .png/.tif, .h5, "
                   "or a measured scan in any format SurfaceTopography reads with units (.x3p, .sur, .plu, .datx, "
                   ".gwy, .sdf, .spm, .ibw, a Park Systems .tiff, ...: see docs/how-to/real-surfaces.md); "
                   "FILE:pixel-mm=MM,height-mm=MM gives its units")
    add_reading_args(p)
    p.add_argument("--tile", action="store_true", help="repeat a small heightmap as a periodic texture")
    p.add_argument("--centre", type=float_pair, metavar="X,Y", help="footprint centre in mm (default: map centre)")


def add_reading_args(p: argparse.ArgumentParser) -> None:
    """How heightmaps are loaded: --pixel-mm, --height-mm, --resample-square, the unit check's --units-ok, and
    the scan clean-up options (roughness.surface.loading)."""
    p.add_argument("--pixel-mm", type=PIXEL, metavar="MM",
                   help="pixel size in mm (required unless the file states it; refused if it differs from what a "
                        "file states, except TIFF resolution tags, which it replaces with a note; "
                        "FILE:pixel-mm=MM for one file)")
    p.add_argument("--height-mm", type=HEIGHT, metavar="MM",
                   help="height of full-scale white in mm (8/16-bit PNG/TIFF; unless the file states it; with several "
                        "inputs it applies to those that need it; FILE:height-mm=MM for one file)")
    p.add_argument("--resample-square", action="store_true",
                   help="resample non-square pixels (e.g. a scan's 10 x 12 um) bilinearly to square pixels of the "
                        "finer size, reported and recorded in the JSON (default: refuse them; sizes within 0.1%% are "
                        "read as square, noted)")
    p.add_argument("--units-ok", action="store_true",
                   help="the heights and pixel size are mm even though their relief, slope or pixel size look like "
                        "metres or micrometres (default: refuse them)")
    p.add_argument("--fill", action="store_true",
                   help="interpolate missing points (NaN) of a scan, reported (default: refuse them)")
    p.add_argument("--max-fill", type=FRACTION, default=MAX_FILL_FRACTION, metavar="FRACTION",
                   help=f"--fill refuses maps with more missing than this fraction (default: {MAX_FILL_FRACTION:g})")
    p.add_argument("--despike", type=positive(MAX_DESPIKE), metavar="K",
                   help="replace spikes: pixels further than K RMS height steps from their 3 x 3 median "
                        "(5 leaves the product's textures untouched; default: off)")
    p.add_argument("--level", choices=tuple(LEVELS),
                   help="subtract the least-squares plane or polynomial of degree 2 or 3 (default: off)")


def load(args: argparse.Namespace, text: str, several: bool = False) -> tuple[Heightmap, Loaded]:
    """One input file (``FILE`` or ``FILE:pixel-mm=..,height-mm=..``) loaded as the command's options say
    (roughness.surface.loading), and the record of it; nothing printed. ``several``: the command reads other
    inputs too (a --height-mm is then for those that need it)."""
    from roughness.surface.cleanup import Cleanup
    from roughness.surface.loading import load_surface
    from roughness.surface.units import split_input

    path, units = split_input(text)
    footprint = None
    if getattr(args, "tile", False):
        from roughness.simulate.config import SimConfig

        footprint = SimConfig().width_mm
    try:
        return load_surface(path, units.over(args.pixel_mm, args.height_mm), args.resample_square,
                            Cleanup(args.fill, args.max_fill, args.despike, args.level), args.units_ok, several,
                            tile_footprint_mm=footprint)
    except InputError as err:  # in the CLI's words also where a batch collects the message (predict FOLDER)
        raise InputError(error_message(err, getattr(args, "flags", {})), parameter=err.parameter) from None


def load_input(args: argparse.Namespace, text: str, several: bool = False) -> Heightmap:
    """``load``, with what loading did printed as notes on stderr (even with --quiet) and kept in
    ``args.readings`` for the JSON output (``readings``)."""
    hm, loaded = load(args, text, several)
    show_notes(args, loaded.lines())
    args.readings = [*getattr(args, "readings", []), loaded]
    return hm


def show_notes(args: argparse.Namespace, lines: list[str]) -> None:
    """Notes on stderr, in the CLI's words, even with --quiet: nothing done to a user's surface is silent."""
    for line in lines:
        print(f"note: {in_flags(line, getattr(args, 'flags', {}))}", file=sys.stderr, flush=True)


def readings(args: argparse.Namespace) -> list[dict]:
    """The records of the heightmaps ``load_input`` loaded, in order, for the JSON output."""
    return [loaded.as_dict() for loaded in getattr(args, "readings", [])]


def add_cluster_args(p: argparse.ArgumentParser, what: str, workers: int, default: int | None) -> None:
    """Where the command does ``what`` (a verb phrase) on Dask (roughness.cluster): ``--workers`` local
    processes (argparse ``default``; ``workers``: the number shown), or a running cluster's ``--scheduler`` or
    ``--scheduler-file``."""
    p.add_argument("--workers", type=PARALLEL, default=default,
                   help=f"local Dask worker processes to {what}, one thread each (default {workers}; ignored with "
                        "--scheduler or --scheduler-file)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help=f"{what} on the running Dask scheduler at ADDRESS, e.g. tcp://host:8786 (default: a "
                            "local cluster)")
    where.add_argument("--scheduler-file", metavar="FILE",
                       help=f"{what} on the cluster whose scheduler wrote FILE (dask scheduler --scheduler-file "
                            "FILE); its workers must run this roughness version (checked)")


def add_quiet(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quiet", action="store_true", help="no progress messages on stderr")


def log(args: argparse.Namespace, message: str) -> None:
    """A progress message on stderr unless --quiet."""
    if not getattr(args, "quiet", False):
        print(message, file=sys.stderr, flush=True)




def defaults(function) -> dict:
    """The keyword defaults of a library function or dataclass: the CLI's one source of them."""
    return {name: p.default for name, p in inspect.signature(function).parameters.items()
            if p.default is not inspect.Parameter.empty}


def add_overwrite(p: argparse.ArgumentParser) -> None:
    p.add_argument("--overwrite", action="store_true", help="replace existing output files (default: refuse)")


def add_model_tail(p: argparse.ArgumentParser, json_help: str) -> None:
    """The closing options of the surrogate-backed design commands: --model, --verify, --json, --quiet, --overwrite."""
    from roughness.design.evaluation import VERIFIERS

    p.add_argument("--model", help="ONNX surrogate (default: the shipped model)")
    p.add_argument("--verify", choices=VERIFIERS,
                   help="what checks the surrogate's answers: the FEM at a fidelity, or the spectral engine (tens of "
                        "milliseconds instead of seconds; see docs/how-to/spectral.md) (default: the FEM at the "
                        "fidelity of the model's training labels)")
    p.add_argument("--json", action="store_true", help=json_help)
    add_quiet(p)
    add_overwrite(p)


def finish(p: argparse.ArgumentParser, run, **aliases: str) -> None:
    """Set the subcommand's function and its map from Python parameter names to flags.

    Flags map from their argparse ``dest`` (``--pixel-mm`` -> ``pixel_mm``); ``aliases`` add the
    names lower layers use for the same value (``force_n="--force"``).
    """
    flags = {a.dest: a.option_strings[-1] for a in p._actions if a.option_strings and a.dest != "help"}
    if "centre" in flags:  # the library's name for --centre's value, whichever command takes it
        flags["centre_mm"] = flags["centre"]
    p.set_defaults(run=run, flags=flags | aliases)


def error_message(err: InputError, flags: dict[str, str]) -> str:
    """An InputError in the CLI's words: parameters named by their flags."""
    if isinstance(err, OutputExists):
        return f"{err.path} already exists; pass --overwrite to replace it"
    flag = flags.get(err.parameter or "")
    message = in_flags(str(err), flags, [err.parameter] if err.parameter else [])
    return f"{flag}: {message}" if flag and flag not in message else message


def in_flags(text: str, flags: dict[str, str], names: list[str] | None = None) -> str:
    """``text`` with the library's Python names of parameters as the command's flags: a call's keywords anywhere
    (``fill=True`` as ``--fill``, ``max_factor=2.5`` or ``engine='fem'`` as ``--max-factor 2.5``, ``--engine fem``),
    and bare ``names`` with an underscore (``pixel_mm`` as ``--pixel-mm``; default: every flag's name). An error
    converts only its own parameter's: other words may name other things, as ``height_mm`` in ``--param
    height_mm=2``."""
    before, after = r"(?<![\w.-])", r"(?![\w-])"
    for name, flag in flags.items():
        text = re.sub(rf"{before}{re.escape(name)}=True{after}", flag, text)
        text = re.sub(rf"{before}{re.escape(name)}=(['\"]?)([\w.+-]+)\1", lambda m: f"{flag} {m.group(2)}", text)
    for name in flags if names is None else names:
        if "_" in name and name in flags:
            text = re.sub(rf"{before}{re.escape(name)}{after}", flags[name], text)
    return text


def json_text(value: object, indent: int | None = None, default=None) -> str:
    """``value`` as strict JSON, which has no NaN or Infinity (strict parsers refuse them).

    Where a number is undefined the command writes null with a note at its source; a non-finite float
    that still gets here (a bug there) becomes null too, and a top-level object lists where under
    ``non_finite``, so the output stays valid and says what is missing."""
    where: list[str] = []
    clean = _finite(value, "", where)
    if where and isinstance(clean, dict):
        clean = {**clean, "non_finite": where}
    return json.dumps(clean, indent=indent, default=default, allow_nan=False)


def _finite(value: object, path: str, where: list[str]) -> object:
    """``value`` with every non-finite float replaced by None (its path appended to ``where``)."""
    if isinstance(value, float) and not math.isfinite(value):
        where.append(path or "(value)")
        return None
    if isinstance(value, dict):
        return {k: _finite(v, f"{path}.{k}" if path else str(k), where) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v, f"{path}[{i}]", where) for i, v in enumerate(value)]
    return value


def write_stdout(text: str) -> None:
    """Print ``text``; if the reader has gone (``| head``), the rest of the output goes nowhere, quietly."""
    try:
        print(text, flush=True)
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # so the flush at exit cannot fail
