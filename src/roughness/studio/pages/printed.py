"""The Printed page: a texture as designed and as a chosen printer makes it (``roughness.surface.printing``), side
by side, each with its V, and how far apart they feel (as `roughness predict --printer` reports it)."""
from __future__ import annotations

from nicegui import ui

import roughness
from roughness.cli.printer import PrintDifference
from roughness.core.errors import InputError
from roughness.surface.printing import PROFILES, printed

from ..feel_view import FeelView
from ..sessions import Session
from ..texture_source import Texture, TextureSource

PATH = "/printed"
TITLE = "Printed"
SUMMARY = "choose a printer: the digital and the printed surface and how each feels"


class PrintedPage:
    def __init__(self, session: Session) -> None:
        self.texture: Texture | None = None
        TextureSource(session, self.set_texture)
        with ui.card().classes("w-full"):
            ui.label("Printer").classes("text-lg").props('role="heading" aria-level="2"')
            self.printer = ui.select(list(PROFILES), value=next(iter(PROFILES)), label="Printer profile",
                                     on_change=self.update).classes("w-56").mark("printer")
            self.profile = ui.label(PROFILES[self.printer.value].describe())
            self.difference = ui.label("").props('role="status" aria-live="polite"').mark("difference")
            self.steps = ui.label("").classes("text-sm text-grey-8").mark("print-steps")
        with ui.row().classes("w-full no-wrap gap-4 items-start"):
            with ui.column().classes("w-1/2"):
                self.digital = FeelView("Digital (as designed)", mark="digital-")
            with ui.column().classes("w-1/2"):
                self.printed = FeelView("Printed (as the printer makes it)", mark="printed-")

    def set_texture(self, texture: Texture) -> None:
        self.texture = texture
        self.update()

    def update(self) -> None:
        """Print the texture with the chosen profile and answer for both surfaces."""
        profile = PROFILES[self.printer.value]
        self.profile.set_text(profile.describe())
        if self.texture is None:
            return
        name, hm = self.texture.name, self.texture.heightmap
        try:
            made = printed(hm, profile)
            digital, as_printed = roughness.predict({name: hm, f"{name} as printed": made.heightmap}, units_ok=True)
        except InputError as err:
            self.difference.set_text(f"error: {err}")
            return
        diff = PrintDifference(digital.roughness, as_printed.roughness, digital.placement.equivalent_lambda_mm,
                               as_printed.placement.equivalent_lambda_mm)
        self.difference.set_text(f"printer {profile.describe()}: {diff.describe()}")
        self.steps.set_text(" ".join([*(f"Print: {step}." for step in made.steps),
                                      *(f"Note: {note}." for note in made.notes)]))
        for view, surface, p, notes in ((self.digital, hm, digital, self.texture.notes),
                                        (self.printed, made.heightmap, as_printed, ())):
            view.show_texture(p.source, surface, notes)
            view.show_prediction(p)


def build(session: Session) -> None:
    PrintedPage(session)
