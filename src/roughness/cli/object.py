"""`roughness object ACTION`: textured 3D objects (one module per action: ``object_<action>.py``)."""
from __future__ import annotations

from importlib import import_module

# action -> module of roughness.cli that defines it
ACTIONS = {"texture": "object_texture", "feel": "object_feel", "tune": "object_tune"}


def add_parser(sub) -> None:
    p = sub.add_parser("object", help="textured 3D objects: put a texture on a mesh, map how each part feels, "
                                      "tune the texture to a target on the object")
    actions = p.add_subparsers(dest="action", required=True)
    for module in ACTIONS.values():
        import_module(f"roughness.cli.{module}").add_parser(actions)
