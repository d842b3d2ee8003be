"""`roughness perception ACTION`: triplet experiments and the fit of V to them (one module per action:
``perception_<action>.py``)."""
from __future__ import annotations

from importlib import import_module

# action -> module of roughness.cli that defines it
ACTIONS = {"embed": "perception_embed", "fit": "perception_fit", "design": "perception_design",
           "simulate": "perception_simulate", "plan": "perception_plan"}


def add_parser(sub) -> None:
    per = sub.add_parser("perception", help="triplet experiments: design trials, simulate an observer, embed the "
                                            "answers, fit V to the embedding")
    actions = per.add_subparsers(dest="perception_command", required=True)
    for module in ACTIONS.values():
        import_module(f"roughness.cli.{module}").add_parser(actions)
