"""A progress line on stderr: rewritten in place on a terminal, a plain line now and then in a log file."""
from __future__ import annotations

import sys
import time

PLAIN_PROGRESS_SECONDS = 30.0  # interval of progress lines when stderr is not a terminal


class StatusLine:
    """``show(text)`` rewrites one line on a terminal; elsewhere (a log file, a pipe) it prints ``text`` as a
    line at most every ``PLAIN_PROGRESS_SECONDS``, and always when ``last``, so logs stay short."""

    def __init__(self) -> None:
        self.terminal = sys.stderr.isatty()
        self.last = time.monotonic()
        self.shown = False

    def show(self, text: str, last: bool = False) -> None:
        if self.terminal:
            print("\r" + text, end="", file=sys.stderr, flush=True)
            self.shown = True
        elif last or time.monotonic() - self.last >= PLAIN_PROGRESS_SECONDS:
            print(text.strip(), file=sys.stderr, flush=True)
            self.last = time.monotonic()

    def close(self) -> None:
        """End the rewritten line on a terminal."""
        if self.terminal and self.shown:
            print(file=sys.stderr)
            self.shown = False
