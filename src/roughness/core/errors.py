"""The project's two error kinds, importable without loading any engine."""
from __future__ import annotations


class InputError(ValueError):
    """Bad user input: the message names the problem; the CLI prints it and exits with code 2.

    ``parameter`` is the Python name of the offending parameter (e.g. ``force_n``); the CLI,
    and only the CLI, turns it into its flag (``--force``).
    """

    def __init__(self, message: str, parameter: str | None = None) -> None:
        super().__init__(message)
        self.parameter = parameter


class OutputExists(InputError):
    """An output file or folder exists and replacing it was not asked for."""

    def __init__(self, path: object, parameter: str | None = None) -> None:
        super().__init__(f"{path} already exists (overwrite=True replaces it)", parameter)
        self.path = path


class SimulationError(RuntimeError):
    """An engine could not produce an answer, or a result failed its own check (e.g. a mesh about to be written
    that is not a closed solid); the message says why (the CLI exits with code 3)."""
