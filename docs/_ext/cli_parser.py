"""The ``roughness`` command line's parser for sphinx-argparse, its texts escaped for reStructuredText.

sphinx-argparse reads help texts as reStructuredText, but ours are plain terminal text: ``|R - R_inf|`` would
be a substitution, ``*.png`` emphasis. Escaping every markup character shows them as the terminal does.
"""
from __future__ import annotations

import argparse
import re

from roughness.cli import build_parser

_MARKUP = re.compile(r"([\\`*_|<>\[\]])")


def _escape(text: str | None) -> str | None:
    return None if text is None or text is argparse.SUPPRESS else _MARKUP.sub(r"\\\1", text)


def _escape_parser(parser: argparse.ArgumentParser) -> None:
    parser.description = _escape(parser.description)
    parser.epilog = _escape(parser.epilog)
    for action in parser._actions:
        action.help = _escape(action.help)
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                choice.help = _escape(choice.help)
            for sub in action.choices.values():
                _escape_parser(sub)


def parser() -> argparse.ArgumentParser:
    """``roughness.cli.build_parser()`` with every description and help text escaped."""
    whole = build_parser()
    _escape_parser(whole)
    return whole
