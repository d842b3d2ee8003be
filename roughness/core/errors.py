"""The project's two error kinds, importable without loading any engine."""


class InputError(ValueError):
    """Bad user input: the message names the parameter and the problem; the CLI exits with code 2."""


class SimulationError(RuntimeError):
    """The FEM model could not produce an answer; the message says why (the CLI exits with code 3)."""
