"""Argument checks that name the parameter in their error (the CLI maps names to flags): numbers, flags,
choices, callbacks and paths."""
from __future__ import annotations

import math
import numbers
import os
import sys
from collections.abc import Callable, Iterable
from pathlib import Path

from .errors import InputError
from .limits import MAX_LENGTH_MM


def real(name: str, value: object) -> float:
    """``value`` as a finite float, or InputError (strings and booleans are refused)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"{name} must be a finite number, got {value!r}", parameter=name)
    number = float(value)
    if not math.isfinite(number):
        raise InputError(f"{name} must be a finite number, got {value!r}", parameter=name)
    return number


def positive(name: str, value: object) -> float:
    """``value`` as a float, or InputError unless it is a positive finite real number."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not (math.isfinite(value) and value > 0):
        raise InputError(f"{name} must be a positive finite number, got {value!r}", parameter=name)
    return float(value)


def non_negative(name: str, value: object) -> float:
    """``value`` as a float, or InputError unless it is a finite real number >= 0."""
    number = real(name, value)
    if number < 0:
        raise InputError(f"{name} must be >= 0, got {value!r}", parameter=name)
    return number


def length(name: str, value: object, zero: bool = False) -> float:
    """``value`` as a length (mm): positive (>= 0 if ``zero``) and at most MAX_LENGTH_MM, or InputError (the
    bound of the command line's length options, for the library's callers too)."""
    number = non_negative(name, value) if zero else positive(name, value)
    if number > MAX_LENGTH_MM:
        raise InputError(f"{name} must be at most {MAX_LENGTH_MM:g} mm ({MAX_LENGTH_MM.name}), got {value!r}",
                         parameter=name)
    return number


def in_range(name: str, value: object, low: float, high: float) -> float:
    """``value`` as a float, or InputError unless low <= value <= high."""
    number = real(name, value)
    if not low <= number <= high:
        raise InputError(f"{name} must be between {low:g} and {high:g}, got {value!r}", parameter=name)
    return number


def integer(name: str, value: object, minimum: int | None = None) -> int:
    """``value`` as an int, or InputError unless it is an integer (not a bool) >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InputError(f"{name} must be an integer, got {value!r}", parameter=name)
    if minimum is not None and value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}", parameter=name)
    return int(value)


def flag(name: str, value: object) -> bool:
    """``value`` as a bool, or InputError unless it is True or False (a NumPy bool too; not 0, 1 or a string)."""
    numpy = sys.modules.get("numpy")  # a NumPy bool exists only once NumPy is loaded (not loaded here: ~0.1 s)
    if not (isinstance(value, bool) or numpy is not None and isinstance(value, numpy.bool_)):
        raise InputError(f"{name} must be True or False, got {value!r}", parameter=name)
    return bool(value)


def choice(name: str, value: object, options: Iterable[str]) -> str:
    """``value`` if it is one of the strings ``options``, else InputError listing them."""
    options = tuple(options)
    if not (isinstance(value, str) and value in options):
        raise InputError(f"unknown {name} {value!r}; choose one of {', '.join(options)}", parameter=name)
    return value


def function(name: str, value: object) -> Callable | None:
    """``value`` if it is None or callable (a callback), else InputError."""
    if value is not None and not callable(value):
        raise InputError(f"{name} must be a function (or None), got {type(value).__name__}", parameter=name)
    return value


def file_path(name: str, value: object) -> Path:
    """``value`` (a str or path-like object) as a Path, or InputError."""
    if not isinstance(value, (str, os.PathLike)) or isinstance(value, str) and not value.strip():
        raise InputError(f"{name} must be a file path (str or pathlib.Path), got {value!r}", parameter=name)
    return Path(value)
