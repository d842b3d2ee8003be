"""Helpers shared by the subcommands: argument types, progress messages, flag checks."""
from __future__ import annotations

import argparse
import os
import sys

from roughness.core.errors import InputError, OutputExists


def float_pair(text: str) -> tuple[float, float]:
    """``X,Y`` in mm, for argparse."""
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y in mm, got {text!r}") from None
    return x, y


def add_heightmap_args(p: argparse.ArgumentParser) -> None:
    """The heightmap input and how to read it (one file)."""
    p.add_argument("heightmap", metavar="HEIGHTMAP", help="heightmap file: .npy (mm), 8/16-bit .png/.tif, .h5")
    add_reading_args(p)
    p.add_argument("--tile", action="store_true", help="repeat a small heightmap as a periodic texture")
    p.add_argument("--centre", type=float_pair, metavar="X,Y", help="footprint centre in mm (default: map centre)")


def add_reading_args(p: argparse.ArgumentParser) -> None:
    """--pixel-mm and --height-mm."""
    p.add_argument("--pixel-mm", type=float, help="pixel size in mm (required unless the file states it)")
    p.add_argument("--height-mm", type=float, help="height of full-scale white in mm (PNG/TIFF)")


def add_quiet(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quiet", action="store_true", help="no progress messages on stderr")


def log(args: argparse.Namespace, message: str) -> None:
    """A progress message on stderr unless --quiet."""
    if not getattr(args, "quiet", False):
        print(message, file=sys.stderr, flush=True)


def at_least_one(flag: str, value: int) -> int:
    if value < 1:
        raise InputError(f"{flag} must be at least 1, got {value}")
    return value


def add_overwrite(p: argparse.ArgumentParser) -> None:
    p.add_argument("--overwrite", action="store_true", help="replace existing output files (default: refuse)")


def finish(p: argparse.ArgumentParser, run, **aliases: str) -> None:
    """Set the subcommand's function and its map from Python parameter names to flags.

    Flags map from their argparse ``dest`` (``--pixel-mm`` -> ``pixel_mm``); ``aliases`` add the
    names lower layers use for the same value (``force_n="--force"``).
    """
    flags = {a.dest: a.option_strings[-1] for a in p._actions if a.option_strings and a.dest != "help"}
    p.set_defaults(run=run, flags=flags | aliases)


def error_message(err: InputError, flags: dict[str, str]) -> str:
    """An InputError in the CLI's words: parameters named by their flags."""
    if isinstance(err, OutputExists):
        return f"{err.path} already exists; pass --overwrite to replace it"
    flag = flags.get(err.parameter or "")
    return f"{flag}: {err}" if flag else str(err)


def write_stdout(text: str) -> None:
    """Print ``text``; if the reader has gone (``| head``), the rest of the output goes nowhere, quietly."""
    try:
        print(text, flush=True)
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # so the flush at exit cannot fail
