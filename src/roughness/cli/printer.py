"""``--printer NAME|FILE`` of predict, tune and palette: answer for the printed plate, and say how far it is
from the digital texture (roughness.surface.printing)."""
from __future__ import annotations

import argparse
from dataclasses import dataclass


def add_printer_arg(p: argparse.ArgumentParser, what: str) -> None:
    from roughness.surface.printing import CONFIG_NAME, PRINTER_ENV, PROFILES

    p.add_argument("--printer", metavar="NAME|FILE|none", action=_PrinterAction,
                   help=f"answer for the plate as this printer would print it: a profile ({', '.join(PROFILES)}) or "
                        f"a JSON profile file (see docs/how-to/printing.md); {what}. Default: ${PRINTER_ENV}, else "
                        f"printer = \"...\" in ./{CONFIG_NAME}, else in ~/.config/roughness/config.toml; "
                        "none: the digital texture")


class _PrinterAction(argparse.Action):
    """--printer NAME|FILE, or ``none``: stored as ``printer`` None and ``printer_off`` True (so that a command's
    ``if args.printer`` sees no printer, and ``printer_of`` skips the project's default)."""

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        off = str(values).strip().lower() == "none"
        setattr(namespace, self.dest, None if off else values)
        namespace.printer_off = off


def printer_of(args: argparse.Namespace):
    """The ``PrintProfile`` of --printer, else of the project's default (``choose_printer``: $ROUGHNESS_PRINTER,
    ./roughness.toml, the user's config file), or None (--printer none, or no default). A default profile says
    where it came from (``chosen_by``, shown by ``describe()``). InputError naming --printer if unknown or
    invalid."""
    from roughness.surface.printing import choose_printer, chosen_profile

    if getattr(args, "printer_off", False):
        return None
    return chosen_profile(choose_printer(getattr(args, "printer", None)))


@dataclass(frozen=True)
class PrintDifference:
    """V of a texture as designed and as printed, each placed on the standard scale (lambda in mm)."""

    digital_roughness: float
    printed_roughness: float
    digital_lambda_mm: float | None  # None: below the scale's floor
    printed_lambda_mm: float | None

    @property
    def jnd(self) -> float | None:
        """Signed JNDs of equivalent wavelength, printed against digital (None if either is below the scale)."""
        from roughness.perceptual_scale import jnd

        if self.digital_lambda_mm is None or self.printed_lambda_mm is None:
            return None
        return jnd(self.printed_lambda_mm, self.digital_lambda_mm)

    @property
    def relative_change(self) -> float | None:
        """(V printed - V digital) / V digital (None for a flat digital texture)."""
        if self.digital_roughness == 0:
            return None
        return self.printed_roughness / self.digital_roughness - 1

    def as_dict(self) -> dict:
        return {"digital_roughness": self.digital_roughness, "printed_roughness": self.printed_roughness,
                "digital_lambda_mm": self.digital_lambda_mm, "printed_lambda_mm": self.printed_lambda_mm,
                "difference_jnd": self.jnd, "relative_change": self.relative_change}

    def describe(self) -> str:
        change = "" if self.relative_change is None else f"{100 * self.relative_change:+.1f}%, "
        jnd = (f"{self.jnd:+.2f} JND" if self.jnd is not None else
               "JND undefined: below the standard scale's floor")
        return f"V digital {self.digital_roughness:.4f}, printed {self.printed_roughness:.4f} ({change}{jnd})"


def difference(digital_roughness: float, printed_roughness: float, scale) -> PrintDifference:
    """The difference of two V on one standard scale (``StandardScale``)."""
    d, p = scale.place(digital_roughness), scale.place(printed_roughness)
    return PrintDifference(digital_roughness, printed_roughness, d.equivalent_lambda_mm, p.equivalent_lambda_mm)


class PrintPairs:
    """The usable (name, heightmap) of an ``InputReader``, each followed by its print (``printed``), named alike.

    A heightmap that cannot be printed at its resolution is recorded in the reader's ``errors`` and skipped.
    ``prints`` holds the ``PrintResult`` of each pair yielded, for the caller to take in order.
    """

    def __init__(self, reader, profile, tile: bool) -> None:
        from collections import deque

        self.reader, self.profile, self.tile = reader, profile, tile
        self.prints: deque = deque()

    def named(self):
        """(name, heightmap) of each usable input, then (name, its print)."""
        from roughness.core.errors import InputError
        from roughness.surface.printing import printed

        for name, hm in self.reader.named():
            try:
                result = printed(hm, self.profile, self.tile)
            except InputError as err:
                self.reader.errors.append((name, InputError(f"{name}: {err}", err.parameter)))
                continue
            self.prints.append(result)
            yield name, hm
            yield name, result.heightmap


class PrintReport:
    """--printer in the design commands: what printing does to the input, and each result's digital V against its
    printed V (the verifier's, on its standard scale)."""

    def __init__(self, evaluator, result) -> None:
        self.evaluator, self.result = evaluator, result  # result: the input's PrintResult
        self.differences: list[tuple[str, PrintDifference]] = []

    def verify(self, heightmap, printed_roughness: float, tile: bool, name: str = "result") -> PrintDifference:
        """Verify the digital ``heightmap`` (its printed V is known) and record the difference under ``name``."""
        digital = self.evaluator.verify(heightmap, tile=tile, digital=True)
        diff = difference(digital.roughness, printed_roughness, self.evaluator.scale)
        self.differences.append((name, diff))
        return diff

    def as_dict(self) -> dict:
        return {**self.result.as_dict(), "verifier": self.evaluator.verifier,
                "differences": {name: diff.as_dict() for name, diff in self.differences}}

    def lines(self) -> list[str]:
        profile = self.result.profile
        return [f"judged as printed by {profile.describe()}; the files saved are the digital designs",
                *(f"{name}: {diff.describe()} ({self.evaluator.verifier})" for name, diff in self.differences),
                *(f"print: {step}" for step in self.result.steps), *(f"print note: {n}" for n in self.result.notes)]


def print_report(evaluator, heightmap, tile: bool) -> PrintReport | None:
    """A ``PrintReport`` if the evaluator has a printer (its print of ``heightmap`` made now, so that a map too
    coarse for the printer is refused before any work), else None."""
    from roughness.surface.printing import printed

    if evaluator.printer is None:
        return None
    return PrintReport(evaluator, printed(heightmap, evaluator.printer, tile))


def merged(reports: list[PrintReport | None]) -> PrintReport | None:
    """One report for several inputs printed alike: the first's, with every input's notes (each once)."""
    from dataclasses import replace

    if not reports or reports[0] is None:
        return None
    notes = tuple(dict.fromkeys(note for r in reports for note in r.result.notes))
    return PrintReport(reports[0].evaluator, replace(reports[0].result, notes=notes))
