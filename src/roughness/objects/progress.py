"""Progress of the long steps of texturing a mesh (refinement rounds, the self-intersection check, writing, the
preview) on stderr, with an estimate of the time left (``roughness.core.status_line.StatusLine``: one line
rewritten on a terminal, a plain line now and then in a log).

A step reports the fraction of its work done (0..1); the time left is the step's time so far scaled by the work
left, ``elapsed x (1 - done) / done`` (the steps' work grows about linearly with the fraction reported: triangles
made, slabs of faces tested, triangles written, views drawn).
"""
from __future__ import annotations

import time
from collections.abc import Callable

from roughness.core.status_line import StatusLine

Fraction = Callable[[float], object]
"""A step's progress callback: called with the fraction (0..1) of its work done."""


def eta_seconds(elapsed_s: float, done: float) -> float | None:
    """Seconds left of a step ``done`` (0..1) of the way through after ``elapsed_s`` seconds (None before any work
    is done: no rate yet)."""
    if done <= 0:
        return None
    return elapsed_s * max(1.0 - done, 0.0) / done


class StageMeter:
    """``stage(name)`` gives the ``Fraction`` callback of one step; each call shows "name: 42%, 12 s, about 16 s
    left" on a ``StatusLine``. ``close()`` ends the line before other output."""

    def __init__(self, prefix: str = "") -> None:
        self.prefix = prefix
        self.line = StatusLine()

    def stage(self, name: str) -> Fraction:
        """The progress callback of step ``name`` (its clock starts now)."""
        start = time.monotonic()

        def report(done: float) -> None:
            self.line.show(self.text(name, done, time.monotonic() - start), last=done >= 1.0)

        return report

    def text(self, name: str, done: float, elapsed_s: float) -> str:
        """The progress line of step ``name`` ``done`` (0..1) of the way after ``elapsed_s`` seconds."""
        left = eta_seconds(elapsed_s, done)
        eta = "time left unknown" if left is None else f"about {left:.0f} s left"
        return f"{self.prefix}{name}: {100 * min(done, 1.0):3.0f}%, {elapsed_s:.0f} s, {eta}".ljust(60)

    def close(self) -> None:
        """End the rewritten line (on a terminal) so the next output starts on its own line."""
        self.line.close()
