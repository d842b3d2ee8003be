"""The ``roughness`` command line: one module per subcommand, errors mapped to exit codes."""
from __future__ import annotations

import argparse
import sys

from . import (
    compare,
    dataset,
    homogeneity,
    jnd,
    palette,
    perception,
    predict,
    simulate,
    tactile_image,
    texture,
    train,
    tune,
)
from .common import error_message

DESCRIPTION = ("Predict how rough a surface texture feels to a fingertip (the FEM model of Tymms, Gardner & Zorin "
               "2018, and a CNN surrogate of it). Units: mm, N, MPa.")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="roughness", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", required=True)
    for command in (simulate, texture, dataset, train, predict, compare, jnd, perception, tune, palette,
                    tactile_image, homogeneity):
        command.add_parser(sub)
    return parser


def _version() -> str:
    from roughness import __version__

    return f"roughness {__version__}"


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # --help, --version, or a usage error (argparse printed it): exit 2
        return exit_.code if isinstance(exit_.code, int) else 2
    from roughness.core.errors import InputError, SimulationError

    try:
        return args.run(args)
    except InputError as err:
        print(f"roughness: error: {error_message(err, getattr(args, 'flags', {}))}", file=sys.stderr)
        return 2
    except SimulationError as err:
        print(f"roughness: simulation failed: {err}", file=sys.stderr)
        return 3
    except OSError as err:
        print(f"roughness: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("roughness: interrupted", file=sys.stderr)
        return 130
