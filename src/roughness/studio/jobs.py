"""Background jobs of the studio: slow work (the FEM, the spectral engine, a tune) in its own process, with
progress, cancel, and errors as the command line's one-line message.

A job is a module-level function ``function(report, *args)`` that returns a picklable result and calls
``report(done, text)`` now and then (``done``: the fraction 0..1 of its work, None where unknown). It runs in a
fresh process (``spawn``: no state of the server's threads is copied), so cancelling it ends the process at once,
even inside a long solve. A job writes nothing: the page stores its result only once it is done, so a failed or
cancelled job loses nothing made before it.
"""
from __future__ import annotations

import multiprocessing
import queue
import time
from collections.abc import Callable
from dataclasses import dataclass

from roughness.objects.progress import eta_seconds

RUNNING, DONE, FAILED, CANCELLED = "running", "done", "failed", "cancelled"
Report = Callable[[float | None, str], None]
"""A job's progress callback: ``report(done, text)``, ``done`` the fraction (0..1) of its work, None if unknown."""


@dataclass
class JobState:
    """What the page shows of a job: its status, progress (fraction 0..1, None: unknown), a line of text, and
    at the end its result or its error message."""

    name: str
    status: str = RUNNING
    done: float | None = 0.0
    text: str = "starting"
    result: object = None
    error: str | None = None
    seconds: float = 0.0

    def progress_text(self) -> str:
        """The progress in words: "name: text, 42%, 3 s, about 4 s left" (what a screen reader reads too)."""
        parts = [f"{self.name}: {self.text}"]
        if self.done is not None:
            parts.append(f"{100 * min(self.done, 1.0):.0f}%")
        parts.append(f"{self.seconds:.0f} s")
        left = eta_seconds(self.seconds, self.done) if self.done is not None and self.status == RUNNING else None
        if left is not None:
            parts.append(f"about {left:.0f} s left")
        return ", ".join(parts)


def _child(function: Callable, args: tuple, flags: dict[str, str], messages) -> None:
    """The job's process: run ``function`` and send its progress, then its result or its error message (parameters
    named by ``flags``, as the command line names them)."""
    from roughness.cli.common import error_message
    from roughness.core.errors import InputError, SimulationError

    def report(done: float | None, text: str) -> None:
        messages.put(("progress", done, text))

    try:
        messages.put((DONE, function(report, *args)))
    except InputError as err:
        messages.put((FAILED, f"error: {error_message(err, flags)}"))
    except SimulationError as err:
        messages.put((FAILED, f"failed: {err}"))
    except Exception as err:  # noqa: BLE001  # any other: one line, not a traceback
        messages.put((FAILED, f"failed: {type(err).__name__}: {err}"))


def cli_flags(command: str) -> dict[str, str]:
    """The flags of `roughness COMMAND` (an action's too: "object feel") by the library's parameter names (its
    parser's own map)."""
    import argparse

    from roughness.cli import build_parser

    words = command.split()
    parser = build_parser(words[0])
    for word in words:
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[word]
    return parser.get_default("flags")


class Job:
    """One background job: ``poll()`` gives its state, ``cancel()`` ends it. ``flags``: the command line's flags by
    the library's parameter names (``cli_flags``), so that an error names them as the CLI would."""

    def __init__(self, name: str, function: Callable, *args: object, flags: dict[str, str] | None = None) -> None:
        context = multiprocessing.get_context("spawn")
        self._messages = context.Queue()
        self._process = context.Process(target=_child, args=(function, args, flags or {}, self._messages),
                                        daemon=True)
        self._start = time.monotonic()
        self.state = JobState(name)
        self._process.start()

    def poll(self) -> JobState:
        """The job's state after the messages it sent so far."""
        if self.state.status != RUNNING:
            return self.state
        self.state.seconds = time.monotonic() - self._start
        while True:
            try:
                message = self._messages.get_nowait()
            except queue.Empty:
                break
            if message[0] == "progress":
                self.state.done, self.state.text = message[1], message[2]
            elif message[0] == DONE:
                self.state.status, self.state.result, self.state.done, self.state.text = DONE, message[1], 1.0, "done"
            else:
                self.state.status, self.state.error, self.state.text = FAILED, message[1], "failed"
        if self.state.status == RUNNING and not self._process.is_alive() and self._messages.empty():
            self.state.status, self.state.text = FAILED, "failed"
            self.state.error = f"failed: the job's process ended unexpectedly (exit code {self._process.exitcode})"
        if self.state.status != RUNNING:
            self._process.join(timeout=5)
        return self.state

    def cancel(self) -> None:
        """End the job's process now (its work so far is dropped; nothing it would have made is kept)."""
        if self.state.status == RUNNING:
            self._process.terminate()
            self._process.join(timeout=5)
            self.state.status, self.state.text = CANCELLED, "cancelled"
            self.state.seconds = time.monotonic() - self._start
