"""The ``roughness`` command line: one module per subcommand, errors mapped to exit codes."""
from __future__ import annotations

import argparse
import sys
from importlib import import_module

DESCRIPTION = ("Predict how rough a surface texture feels to a fingertip (the FEM model of Tymms, Gardner & Zorin "
               "2018, and a CNN surrogate of it). Units: mm, N, MPa.")


# subcommand -> module of roughness.cli that defines it (imported only when its parser is built)
COMMANDS = {"simulate": "simulate", "texture": "texture", "dataset": "dataset", "train": "train",
            "predict": "predict", "compare": "compare", "jnd": "jnd", "perception": "perception", "tune": "tune",
            "palette": "palette", "tactile-image": "tactile_image", "homogeneity": "homogeneity",
            "object": "object", "fuzzy-skin": "fuzzy_skin", "hidden-shapes": "hidden_shapes", "ensemble": "ensemble",
            "card": "card", "model-version": "model_version", "studio": "studio"}


class _VersionAction(argparse.Action):
    """``--version``, looked up only when asked (reading the package metadata costs ~20 ms at start-up)."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help="show the program's version number and exit")

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        from roughness import __version__

        print(f"roughness {__version__}")
        parser.exit()


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The whole command line, or only ``command``'s part of it (a subcommand's options take their defaults
    from the modules that use them, so building every subcommand would import the FEM and design stacks
    before a millisecond prediction: about 0.3 s of a fresh process's start)."""
    parser = argparse.ArgumentParser(prog="roughness", description=DESCRIPTION)
    parser.add_argument("--version", action=_VersionAction)
    sub = parser.add_subparsers(dest="command", required=True)
    for name, module in COMMANDS.items():
        if command in (None, name):
            import_module(f"roughness.cli.{module}").add_parser(sub)
    return parser


def _command(argv: list[str]) -> str | None:
    """The subcommand named on the command line (the first word: top-level options take no values)."""
    word = next((arg for arg in argv if not arg.startswith("-")), None)
    return word if word in COMMANDS else None


# the optional dependencies (pyproject.toml's extras) by the name they import as
EXTRA_OF = {"trimesh": "objects", "rtree": "objects", "lxml": "objects", "torch": "train", "onnx": "train",
            "onnxscript": "train", "sklearn": "train", "cvxpy": "perception", "SurfaceTopography": "scans",
            "nicegui": "studio"}


def main(argv: list[str] | None = None) -> int:
    """Run the command line ``argv`` (default: the process's); its exit code. Ctrl-C at any point, building the
    parser included, ends with "interrupted" and 130, not a traceback."""
    try:
        return _main(sys.argv[1:] if argv is None else argv)
    except KeyboardInterrupt:
        print("roughness: interrupted", file=sys.stderr)
        return 130


def _main(argv: list[str]) -> int:
    parser = build_parser(_command(argv))
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # --help, --version, or a usage error (argparse printed it): exit 2
        return exit_.code if isinstance(exit_.code, int) else 2
    from roughness.core.errors import InputError, SimulationError

    from .common import error_message

    try:
        return args.run(args)
    except InputError as err:
        print(f"roughness: error: {error_message(err, getattr(args, 'flags', {}))}", file=sys.stderr)
        return 2
    except SimulationError as err:
        print(f"roughness: failed: {err}", file=sys.stderr)
        return 3
    except ModuleNotFoundError as err:  # an optional dependency of this command: name the extra that installs it
        extra = EXTRA_OF.get((err.name or "").partition(".")[0])
        if extra is None:
            raise
        print(f"roughness: error: this command needs {err.name}, which the '{extra}' extra installs: pip install "
              f"\"roughness[{extra}]\" (from a checkout: pip install \".[{extra}]\")", file=sys.stderr)
        return 2
    except OSError as err:
        print(f"roughness: error: {err}", file=sys.stderr)
        return 2
