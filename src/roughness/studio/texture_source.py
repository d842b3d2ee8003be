"""Where a page's texture comes from: the bundled example, a named texture or family with its parameters (the
library's texture catalogue, as ``roughness texture make``), or an uploaded heightmap, scan or picture whose missing
units are asked for (``roughness.studio.uploads``). Errors are shown as the command line words them."""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources

from nicegui import events, ui

from roughness.cli.common import error_message
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from .sessions import Session
from .uploads import MAX_UPLOAD_BYTES, Opened, missing_units, open_heightmap, upload_path

EXAMPLE = "standard-1.0mm.png"
EXAMPLE_UNITS = {"pixel_mm": 0.05, "height_mm": 1.0}  # the README's: roughness predict ... --pixel-mm 0.05 --height-mm 1
MAKE_FLAGS = {"params": "--param", "seed": "--seed"}  # roughness texture make's flags, for its messages


def example_path():
    """The bundled example heightmap (the README's examples/standard-1.0mm.png)."""
    return resources.files("roughness.studio") / "example" / EXAMPLE


@dataclass(frozen=True)
class Texture:
    """A texture as opened or made: its heightmap (mm), name, and what loading noted (the CLI's notes)."""

    heightmap: Heightmap
    name: str
    notes: tuple[str, ...] = ()
    recipe: dict | None = None  # a named texture's recipe (roughness texture make's JSON)


def parameter_hint(name: str) -> str:
    """The parameters a texture family takes and their ranges (as ``roughness texture list`` prints them)."""
    from roughness.dataset.families import PARAMETER_LIMITS

    if name == "bumps":
        return "lambda_mm=... [top=cap|flat] [top_diameter_mm=] [height_mm=] [base_diameter_mm=]"
    ranges = PARAMETER_LIMITS.get(name)
    if ranges is None:
        return "no parameters"
    return ", ".join(f"{k} {v[0]:g}..{v[1]:g}" if isinstance(v[0], float) else f"{k} {'|'.join(v)}"
                     for k, v in ranges.items())


def make_named(name: str, params_text: str, seed: int) -> Texture:
    """The named texture or family member (``roughness texture make NAME --param K=V ... --seed S``)."""
    from roughness.dataset.catalogue import make_texture, parse_params

    try:
        hm, recipe = make_texture(name, seed=seed, params=parse_params(params_text.replace(",", " ").split()))
    except InputError as err:
        raise InputError(error_message(err, MAKE_FLAGS), err.parameter) from None
    return Texture(hm, name, (), recipe)


class TextureSource:
    """The controls that open or make a texture; ``on_texture(texture)`` receives each one."""

    def __init__(self, session: Session, on_texture: Callable[[Texture], None], heading: str = "Texture in") -> None:
        from roughness.dataset.catalogue import names

        self.session, self.on_texture = session, on_texture
        self.pending = None  # an uploaded file waiting for the units it does not state
        with ui.card().classes("w-full"):
            ui.label(heading).classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("items-end gap-4"):
                ui.button("Open the bundled example", on_click=self.open_example).mark("open-example")
                self.name = ui.select(names(), value="standard-1.0", label="Named texture or family",
                                      on_change=self._show_hint).classes("w-56").mark("texture-name")
                self.params = ui.input("Parameters (key=value, ...)").classes("w-72").mark("params")
                self.seed = ui.number("Seed", value=0, min=0, precision=0).classes("w-24")
                ui.button("Make", on_click=self.make_named).props('aria-label="Make the named texture"').mark("make")
            self.hint = ui.label(parameter_hint("standard-1.0")).classes("text-sm text-grey-8")
            self.upload = ui.upload(label=f"Heightmap, scan or picture (drop a file here or choose one; up to "
                                          f"{MAX_UPLOAD_BYTES // 2**20} MiB)", auto_upload=True,
                                    max_file_size=MAX_UPLOAD_BYTES, on_upload=self.on_upload).classes("w-full").mark("upload")
            with ui.row().classes("items-end gap-4") as self.units_row:
                self.pixel_mm = ui.number("Pixel size, mm (--pixel-mm)", min=0, format="%.4g").mark("pixel-mm")
                self.height_mm = ui.number("Height of full-scale white, mm (--height-mm)", min=0, format="%.4g").mark("height-mm")
                ui.button("Read with these units", on_click=self.read_pending).mark("read-units")
            self.units_row.set_visibility(False)
            self.error = ui.label("").classes("text-red-10").props('role="alert"').mark("source-error")

    def _show_hint(self) -> None:
        self.hint.set_text(parameter_hint(self.name.value or ""))

    def open_example(self) -> None:
        self._take(lambda: self._opened(open_heightmap(example_path(), **EXAMPLE_UNITS), EXAMPLE))

    def make_named(self) -> None:
        seed = self.seed.value
        self._take(lambda: make_named(self.name.value or "", self.params.value or "", int(seed or 0)))

    async def on_upload(self, event: events.UploadEventArguments) -> None:
        try:
            path = upload_path(self.session, event.file.name, event.file.size())
        except InputError as err:
            self.error.set_text(f"error: {err}")
            return
        await event.file.save(path)
        self.pending = path
        self.pixel_mm.value = self.height_mm.value = None
        self.read_pending(first=True)

    def read_pending(self, first: bool = False) -> None:
        """Read the uploaded file with the units typed in (none the first time: the file's own)."""
        path = self.pending
        if path is None:
            return
        pixel = None if first else self.pixel_mm.value
        height = None if first else self.height_mm.value
        try:
            opened = open_heightmap(path, pixel, height)
        except InputError as err:
            needed = missing_units(err)
            if needed:
                self.units_row.set_visibility(True)
                self.pixel_mm.set_visibility("pixel_mm" in needed or pixel is not None)
                self.height_mm.set_visibility("height_mm" in needed or height is not None)
            self.error.set_text(f"error: {err}")
            return
        self.units_row.set_visibility(False)
        self.pending = None
        self._take(lambda: self._opened(opened, path.name))

    @staticmethod
    def _opened(opened: Opened, name: str) -> Texture:
        return Texture(opened.heightmap, name, tuple(opened.notes()))

    def _take(self, make: Callable[[], Texture]) -> None:
        try:
            texture = make()
        except InputError as err:
            self.error.set_text(f"error: {err}")
            return
        self.error.set_text("")
        self.on_texture(texture)
