"""Number checks that name the parameter in their error (the CLI maps names to flags)."""
from __future__ import annotations

import math
import numbers

from .errors import InputError


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
