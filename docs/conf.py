"""Sphinx configuration of the roughness manual.

Build (as CI does): ``python -m pip install ".[docs]" && python -m sphinx -W --keep-going -b html docs OUT``.
The committed results the manual links to (benchmark and study reports, the model card, the examples'
tables and pictures) are mirrored into ``docs/repo/`` at build time, each Markdown file as a page that
includes it. Pages link to the files where they are in the repository (``../../benchmarks/results/x.md``,
which also works on a code host); the build points those links at the mirror, so a link to a result that no
longer exists fails the build.
"""
from __future__ import annotations

import os
import re
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = Path(__file__).resolve().parent
MIRROR = DOCS / "repo"
sys.path.insert(0, str(DOCS / "_ext"))  # cli_parser: the parser for sphinx-argparse
# committed results shown in the manual: (folder, glob) relative to the repository root
RESULTS = [("benchmarks/results", "**/*"), ("studies/results", "*"), ("models", "MODEL_CARD.md"),
           ("examples", "**/*")]
PAGE = """# {path}

```{{include}} {source}
:heading-offset: 1
```
"""

project = "roughness"
author = "The roughness developers"
copyright = "the roughness developers (BSD-3-Clause)"
extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinxarg.ext"]
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build"]
myst_heading_anchors = 3  # [text](page.md#a-section-title) links, checked by the build
html_theme = "alabaster"
html_theme_options = {"description": "How rough will a texture feel?", "fixed_sidebar": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_google_docstring = False


def _mirror_results(app) -> None:
    """Write docs/repo/: a page per committed result (.md) and a copy of each picture (.png) beside it."""
    shutil.rmtree(MIRROR, ignore_errors=True)
    for folder, pattern in RESULTS:
        for path in sorted((ROOT / folder).glob(pattern)):
            relative = path.relative_to(ROOT)
            target = MIRROR / relative
            if path.suffix == ".md":
                target.parent.mkdir(parents=True, exist_ok=True)
                source = Path(os.path.relpath(path, target.parent)).as_posix()
                target.write_text(PAGE.format(path=relative.as_posix(), source=source))
            elif path.suffix == ".png":
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(path, target)


_LINK = re.compile(r"\]\(([^)\s#]+)(#[^)\s]*)?\)")  # a Markdown link or image target: ](path#anchor)


def _link_results(app, docname: str, source: list[str]) -> None:
    """Point links from a page to a mirrored repository file (outside docs/) at its mirror in docs/repo/."""
    if docname.startswith("repo/"):
        return
    here = (DOCS / docname).parent

    def mirrored(match: re.Match) -> str:
        target = (here / match[1]).resolve()
        if "://" in match[1] or DOCS in target.parents or ROOT not in target.parents:
            return match[0]
        mirror = MIRROR / target.relative_to(ROOT)
        return f"]({os.path.relpath(mirror, here)}{match[2] or ''})" if mirror.exists() else match[0]

    source[0] = _LINK.sub(mirrored, source[0])


def setup(app) -> None:
    app.connect("builder-inited", _mirror_results)
    app.connect("source-read", _link_results)
