"""Short reprs for results (a notebook prints a result in a line or two, never its arrays)."""
from __future__ import annotations


def v_text(roughness: float, error: float | None = None) -> str:
    """``V = 0.1495 ± 0.0012`` (dimensionless; the error left out when unknown)."""
    return f"V = {roughness:.4g}" + ("" if error is None else f" ± {error:.2g}")


def shape_text(shape: tuple[int, ...]) -> str:
    """``256 x 256``."""
    return " x ".join(str(n) for n in shape)


def short_repr(obj: object, *parts: str) -> str:
    """``ClassName(part, part, ...)`` from the non-empty parts."""
    return f"{type(obj).__name__}({', '.join(p for p in parts if p)})"
