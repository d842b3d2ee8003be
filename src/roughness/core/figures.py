"""Figures without pyplot: no backend is chosen or changed, no global figure list is touched.

A notebook's backend stays as it was; a returned ``Figure`` shows inline in Jupyter (its display
renders through the figure's own Agg canvas) and saves with ``fig.savefig``.
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def new_figure(**kwargs) -> Figure:
    """A ``matplotlib.figure.Figure(**kwargs)`` on its own Agg canvas (the one the labels are measured with)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig: Figure, path: str | Path | None, dpi: int, overwrite: bool = True) -> Figure:
    """Write ``fig`` to ``path`` atomically (nothing if ``path`` is None, refused if it exists and not
    ``overwrite``); returns ``fig``."""
    if path is not None:
        from roughness.core.files import atomic_write

        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi), overwrite)
    return fig
