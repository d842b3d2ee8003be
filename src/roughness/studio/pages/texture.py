"""The Texture page: open a heightmap, scan or picture, or make a named texture; its V, live under the height and
lateral-scale sliders (the surrogate), verified by the spectral engine or the FEM in the background."""
from __future__ import annotations

from dataclasses import dataclass
from importlib import resources

from nicegui import events, ui

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from ..pictures import heightmap_url
from ..sessions import Session
from ..uploads import MAX_UPLOAD_BYTES, missing_units, open_heightmap, store

PATH = "/texture"
TITLE = "Texture"
SUMMARY = "open or make a texture, see how rough it feels, tune it, compare it, download it"
EXAMPLE = "standard-1.0mm.png"
EXAMPLE_UNITS = {"pixel_mm": 0.05, "height_mm": 1.0}  # the README's: roughness predict ... --pixel-mm 0.05 --height-mm 1


def example_path():
    """The bundled example heightmap (the README's examples/standard-1.0mm.png)."""
    return resources.files("roughness.studio") / "example" / EXAMPLE


@dataclass
class Texture:
    """The texture the page works on: the heightmap as opened or made, its name, and what loading noted."""

    base: Heightmap
    name: str
    notes: tuple[str, ...] = ()


class TexturePage:
    """The page's controls and results for one session."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.texture: Texture | None = None
        self.pending_upload = None  # an uploaded file that waits for the units it does not state
        with ui.card().classes("w-full"):
            ui.label("Texture in").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("items-end gap-4"):
                ui.button("Open the bundled example", on_click=self.open_example)
                self.upload = ui.upload(label=f"Heightmap, scan or picture (up to {MAX_UPLOAD_BYTES // 2**20} MiB)",
                                        auto_upload=True, max_file_size=MAX_UPLOAD_BYTES,
                                        on_upload=self.on_upload).props('accept="*"')
            with ui.row().classes("items-end gap-4") as self.units_row:
                self.pixel_mm = ui.number("Pixel size, mm (--pixel-mm)", min=0, format="%.4g")
                self.height_mm = ui.number("Height of full-scale white, mm (--height-mm)", min=0, format="%.4g")
                ui.button("Read with these units", on_click=self.read_pending)
            self.units_row.set_visibility(False)
            self.error = ui.label("").classes("text-red-10").props('role="alert"')
        with ui.card().classes("w-full"):
            ui.label("How it feels").classes("text-lg").props('role="heading" aria-level="2"')
            self.answer = ui.label("Open or make a texture.").props('role="status" aria-live="polite"')
            self.picture = ui.image().classes("w-64").props('alt=""')

    def open_example(self) -> None:
        self._open(lambda: open_heightmap(example_path(), **EXAMPLE_UNITS), EXAMPLE)

    async def on_upload(self, event: events.UploadEventArguments) -> None:
        data = await event.file.read()
        try:
            path = store(self.session, event.file.name, data)
        except InputError as err:
            self.show_error(f"error: {err}")
            return
        self.pending_upload = path
        self.read_pending(first=True)

    def read_pending(self, first: bool = False) -> None:
        """Read the uploaded file, with the units typed in (none the first time)."""
        path = self.pending_upload
        if path is None:
            return
        pixel = None if first else self.pixel_mm.value
        height = None if first else self.height_mm.value
        try:
            opened = open_heightmap(path, pixel, height)
        except InputError as err:
            needed = missing_units(err)
            self.units_row.set_visibility(bool(needed) or self.units_row.visible)
            self.pixel_mm.set_visibility("pixel_mm" in needed or self.pixel_mm.value is not None)
            self.height_mm.set_visibility("height_mm" in needed or self.height_mm.value is not None)
            self.show_error(f"error: {err}")
            return
        self.units_row.set_visibility(False)
        self.pending_upload = None
        self.set_texture(Texture(opened.heightmap, path.name, tuple(opened.notes())))

    def _open(self, make, name: str) -> None:
        try:
            opened = make()
        except InputError as err:
            self.show_error(f"error: {err}")
            return
        self.set_texture(Texture(opened.heightmap, name, tuple(opened.notes())))

    def show_error(self, text: str) -> None:
        self.error.set_text(text)

    def set_texture(self, texture: Texture) -> None:
        import roughness
        from roughness.cli.predict import prediction_line

        self.error.set_text("")
        self.texture = texture
        try:
            [p] = roughness.predict({texture.name: texture.base}, units_ok=True)  # units checked as it was read
        except InputError as err:
            self.show_error(f"error: {err}")
            return
        self.answer.set_text(prediction_line(p))
        self.picture.set_source(heightmap_url(texture.base))
        self.picture.props(f'alt="Heightmap of {texture.name}: dark is low, light is high"')


def build(session: Session) -> None:
    TexturePage(session)
