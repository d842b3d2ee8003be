"""The printer a page answers for (``--printer NAME``): a select of the shipped profiles
(``roughness.surface.printing.PROFILES``) and "none", the digital design, by default."""
from __future__ import annotations

from nicegui import ui

from roughness.surface.printing import PROFILES, PrintProfile

NO_PRINTER = "none (the digital design)"
LABEL = "Printer profile (--printer)"


class PrinterChoice:
    """The select, and the chosen profile's name (``name``) or profile (``profile``); None: the digital design."""

    def __init__(self) -> None:
        self.select = ui.select([NO_PRINTER, *PROFILES], value=NO_PRINTER, label=LABEL).classes("w-64")

    @property
    def name(self) -> str | None:
        return None if self.select.value == NO_PRINTER else self.select.value

    @property
    def profile(self) -> PrintProfile | None:
        return None if self.name is None else PROFILES[self.name]
