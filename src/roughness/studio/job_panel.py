"""The studio's view of a background job: a progress bar, its progress in words, a cancel button, and the
result or the error message when it ends (``roughness.studio.jobs``)."""
from __future__ import annotations

from collections.abc import Callable

from nicegui import ui

from .jobs import DONE, RUNNING, Job, JobState

POLL_SECONDS = 0.1


class JobPanel:
    """Runs one job at a time; ``on_done(result)`` is called with a finished job's result (only then: a failed or
    cancelled job changes nothing the page holds)."""

    def __init__(self, label: str) -> None:
        with ui.column().classes("w-full gap-1") as self.box:
            self.bar = ui.linear_progress(value=0, show_value=False).props(f'aria-label="{label} progress"')
            with ui.row().classes("items-center"):
                self.text = ui.label("").props('role="status" aria-live="polite"').mark(f"{label}-progress")
                self.cancel_button = ui.button("Cancel", on_click=self.cancel).props(f'aria-label="Cancel {label}"').mark(f"{label}-cancel")
        self.box.set_visibility(False)
        self.job: Job | None = None
        self._on_done: Callable[[object], None] | None = None
        self._timer = ui.timer(POLL_SECONDS, self._poll, active=False)

    @property
    def running(self) -> bool:
        return self.job is not None and self.job.state.status == RUNNING

    def start(self, name: str, function: Callable, *args: object, on_done: Callable[[object], None],
              flags: dict[str, str] | None = None) -> None:
        """Start ``function(report, *args)`` as a background job (one at a time: a running one is cancelled);
        ``flags``: the command line's, to word its errors (``jobs.cli_flags``)."""
        if self.running:
            self.cancel()
        self.job, self._on_done = Job(name, function, *args, flags=flags), on_done
        self.box.set_visibility(True)
        self.cancel_button.set_visibility(True)
        self._show(self.job.state)
        self._timer.activate()

    def cancel(self) -> None:
        if self.job is not None:
            self.job.cancel()
            self._poll()

    def _poll(self) -> None:
        if self.job is None:
            return
        state = self.job.poll()
        self._show(state)
        if state.status == RUNNING:
            return
        self._timer.deactivate()
        self.cancel_button.set_visibility(False)
        if state.status == DONE and self._on_done is not None:
            self._on_done(state.result)

    def _show(self, state: JobState) -> None:
        self.bar.set_value(state.done or 0.0)
        self.bar.props(remove="indeterminate") if state.done is not None else self.bar.props("indeterminate")
        self.text.set_text(state.error if state.error else state.progress_text())
