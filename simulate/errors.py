"""Errors of the FEM engine (importable without loading it)."""


class SimulationError(RuntimeError):
    """The FEM model could not produce an answer; the message says why."""
