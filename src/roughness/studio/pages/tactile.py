"""The Tactile picture page: a picture's flat colours, a palette of textures that feel different, the plate
previewed as relief and as feel map, the tactile-graphics guidelines checked, the plate as STL and 3MF.

Everything comes from the library as ``roughness tactile-image`` uses it: ``roughness.design.colours`` clusters the
colours, ``roughness.design.layout`` says what each becomes, ``roughness.palette`` makes the textures,
``roughness.tactile_image`` the plate, ``roughness.design.guidelines`` checks it (the guidelines it cites), and
the studio's ``downloads`` writes its files (the STL and 3MF checked closed solids). Making the palette and the
plate run as background jobs.
"""
from __future__ import annotations

import io
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np
from nicegui import events, ui

from roughness.core.checks import integer, positive
from roughness.core.errors import InputError
from roughness.design.colours import TOLERANCE, PictureColours, cluster_colours, hex_colour
from roughness.design.guidelines import Check
from roughness.design.layout import Layout, plan_layout
from roughness.design.lines import MAX_STROKE_MM
from roughness.design.palette import Palette
from roughness.design.tactile_image import WIDTH_MM, TactilePlate
from roughness.studio.jobs import Report

from ..downloads import KINDS, write_download
from ..job_panel import JobPanel
from ..pictures import png_url
from ..printer_choice import PrinterChoice
from ..sessions import Session
from ..uploads import MAX_UPLOAD_BYTES, upload_path

PATH = "/tactile"
TITLE = "Tactile picture"
SUMMARY = "a picture's flat colours as textures that feel different, checked against tactile-graphics rules, as a plate"
EXAMPLES = {"shapes": "tactile-shapes.png", "four colours": "tactile-four-colours.png",
            "outlined": "tactile-outlined.png"}
"""The bundled example pictures (examples/design/*.png) by the name their button shows."""
VERIFIERS = {"spectral engine (seconds)": "spectral", "FEM, coarse (minutes)": "coarse",
             "FEM, default (many minutes)": "default"}
"""What verifies the palette's textures: label -> ``verify`` of ``roughness.palette``."""
PALETTE_FOLDER = "palette"
GUIDELINE_SOURCES = ("BANA/CBA Guidelines and Standards for Tactile Graphics (2010): no more than 5 area textures; "
                     "tactilegraphics.org, Keys to readability: areas at least 1/4 inch (6.35 mm) across, 1/8 inch "
                     "between elements; Round Table guidelines for 3D-printed models: raised lines 1.1-3 mm wide. "
                     "Neighbours at least the minimum JND apart on the plate's roughness map is this tool's measure of "
                     "adjacent textures that are clearly different.")


def example_path(name: str):
    """The bundled example picture ``name`` (a key of ``EXAMPLES``)."""
    return resources.files("roughness.studio") / "example" / EXAMPLES[name]


@dataclass(frozen=True)
class Picture:
    """The picture the page works on: its RGB pixels (h, w, 3), its name, its flat colours and their layout."""

    rgb: np.ndarray
    name: str
    colours: PictureColours
    layout: Layout

    def colour_lines(self) -> list[str]:
        """Each flat colour in words: its share of the pixels and what it becomes on the plate."""
        shares = np.bincount(self.colours.labels.ravel(), minlength=len(self.colours.colours)) / self.colours.pixels
        role = {i: "raised line" for i in self.layout.line_colours}
        role.update({i: "left flat (background)" if i == self.layout.background else "left flat"
                     for i in self.layout.flat})
        return [f"{hex_colour(c)}: {100 * shares[i]:.1f}% of the pixels, {role.get(i, 'textured')}"
                for i, c in enumerate(self.colours.colours)]


@dataclass(frozen=True)
class PaletteChoice:
    """How the palette was asked for: its size, least distance (JND), printer profile name (None: digital) and
    verifying engine."""

    k: int
    min_jnd: float
    printer: str | None
    verify: str


@dataclass(frozen=True)
class MadePlate:
    """A plate and what the page shows and serves of it: the guideline checks, the relief and feel-map pictures
    (PNG) and the names of its files in the session folder by kind (``downloads.KINDS``: .npz, STL, 3MF, JSON)."""

    plate: TactilePlate
    checks: tuple[Check, ...]
    relief_png: bytes
    map_png: bytes
    files: dict[str, str]


def read_picture(path: Path, tolerance: float, width_mm: float) -> Picture:
    """The picture in ``path`` (``tactile-image``'s reader and checks), clustered within ``tolerance`` (Delta E) and
    laid out as ``roughness.tactile_image`` lays it out on a plate ``width_mm`` wide (mm)."""
    from roughness.design.tactile_image import read_image

    return cluster(read_image(path), path.name, tolerance, width_mm)


def cluster(rgb: np.ndarray, name: str, tolerance: float, width_mm: float) -> Picture:
    """``rgb``'s flat colours within ``tolerance`` (Delta E) and their layout (lines, flat background, textured) as
    ``roughness.tactile_image``'s defaults make it."""
    found = cluster_colours(rgb, tolerance, source=name)
    return Picture(rgb, name, found, plan_layout(found, width_mm / rgb.shape[1], MAX_STROKE_MM))


def make_palette(report: Report, choice: PaletteChoice) -> Palette:
    """The job: ``roughness.palette`` of ``choice`` (a family palette of standard-1.0 scaled by height)."""
    import roughness

    as_printed = "" if choice.printer is None else f", as printed by {choice.printer}"
    report(None, f"making {choice.k} textures {choice.min_jnd:g} JND apart{as_printed}, verified by {choice.verify}")
    return roughness.palette(choice.k, min_jnd=choice.min_jnd, verify=choice.verify, printer=choice.printer)


def make_plate(report: Report, rgb: np.ndarray, palette_folder: str, choice: PaletteChoice, width_mm: float,
               tolerance: float, session: Session, stem: str) -> MadePlate:
    """The job: the plate of ``rgb`` with the palette in ``palette_folder`` (``roughness.tactile_image``), its
    guideline checks and pictures; its files written under the new ``stem`` in the session's folder by
    ``downloads.write_download`` (the plate checked a closed solid first), so nothing made before is replaced."""
    import roughness
    from roughness.design.guidelines import check_plate
    from roughness.design.tactile_image import figures

    report(0.0, "composing the plate and mapping its roughness (surrogate)")
    plate = roughness.tactile_image(rgb, palette_folder, size_mm=width_mm, colour_tolerance=tolerance,
                                    min_jnd=choice.min_jnd, verify=choice.verify, printer=choice.printer)
    report(0.5, "checking the tactile-graphics guidelines")
    checks = tuple(check_plate(plate, choice.min_jnd))
    report(0.6, "drawing the relief and the feel map")
    drawn = figures(plate)
    relief, feel = (_png(drawn[name]) for name in ("relief.png", "roughness_map.png"))
    summary = {**plate.summary(), "guidelines": [c.as_dict() for c in checks],
               "printer": choice.printer, "verifier": choice.verify}
    files = {}
    for i, kind in enumerate(KINDS):
        report(0.7 + 0.3 * i / len(KINDS), f"writing {KINDS[kind]}")
        files[kind] = write_download(session, stem, kind, plate.heightmap, summary).name
    return MadePlate(plate, checks, relief, feel, files)


def _png(figure) -> bytes:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=80)
    return buffer.getvalue()


def palette_lines(palette: Palette, choice: PaletteChoice) -> list[str]:
    """The palette in words: each member's verified V (± its standard error) and wavelength, the closest pair."""
    engine = "spectral engine" if choice.verify == "spectral" else f"FEM, {choice.verify}"
    printed = "" if choice.printer is None else f" as printed by {choice.printer}"
    lines = [f"{m.name}: V = {m.fem.roughness:.4f} ± {m.fem.roughness_stderr:.4f}{printed} ({engine}), equivalent "
             f"wavelength {m.fem.equivalent_lambda_mm:.3f} mm" for m in palette.members]
    verdict = "every pair at least that far apart" if palette.verified else "NOT every pair that far apart"
    lines.append(f"closest pair {palette.closest_jnd:.2f} JND apart (asked: at least {palette.min_jnd:g} JND): {verdict}")
    return lines + [f"note: {n}" for n in palette.notes]


def region_lines(plate: TactilePlate) -> list[str]:
    """Each region of the plate in words: its texture and how rough it feels on the plate."""
    lines = []
    for r in plate.regions:
        on_plate = (f"V {r.plate_roughness:.4f} on the plate, lambda {r.plate_lambda_mm:.3f} mm, median over "
                    f"{r.footprints} footprints (surrogate: no uncertainty of its own)"
                    if r.plate_roughness is not None and r.plate_lambda_mm is not None else
                    f"V {r.plate_roughness:.4f} on the plate (below the standard scale)"
                    if r.plate_roughness is not None else "no 10 mm footprint fits inside it: not measured")
        lines.append(f"{hex_colour(r.colour)} -> {r.texture}: {on_plate}")
    return lines


class TactilePage:
    """The page's controls and results for one session."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.picture: Picture | None = None
        self.palette: tuple[Palette, PaletteChoice] | None = None
        self.made = 0  # plates asked for: each one's files get new names (no stale picture, nothing replaced)
        self._picture_card()
        self._palette_card()
        self._plate_card()

    def _picture_card(self) -> None:
        with ui.card().classes("w-full"):
            ui.label("1. The picture").classes("text-lg").props('role="heading" aria-level="2"')
            ui.label("A picture with a few flat colours (a map, a diagram); each colour becomes a region.")
            with ui.row().classes("items-end gap-2"):
                for name in EXAMPLES:
                    ui.button(f"Open example: {name}", on_click=lambda n=name: self.open_example(n))
                ui.upload(label=f"Picture (.png, .jpg, ...; up to {MAX_UPLOAD_BYTES // 2**20} MiB)", auto_upload=True,
                          max_file_size=MAX_UPLOAD_BYTES, on_upload=self.on_upload).props('accept="image/*"')
            with ui.row().classes("items-end gap-4"):
                self.tolerance = ui.number("Colour tolerance, CIELAB Delta E (--colour-tolerance)", value=TOLERANCE,
                                           min=0.1, max=300, step=1, format="%.3g").classes("w-72")
                self.width = ui.number("Plate width, mm (--size-mm)", value=WIDTH_MM, min=10, max=400, step=5,
                                       format="%.4g").classes("w-56")
                ui.button("Cluster the colours again", on_click=self.recluster)
            self.error = ui.label("").classes("text-red-10").props('role="alert"')
            self.colours_text = ui.label("Open a picture.").props('role="status" aria-live="polite"')
            with ui.row().classes("items-start gap-4"):
                self.clustered = ui.image().classes("w-64").props('alt=""')
                self.colour_list = ui.column().classes("gap-0")

    def _palette_card(self) -> None:
        with ui.card().classes("w-full"):
            ui.label("2. The palette").classes("text-lg").props('role="heading" aria-level="2"')
            ui.label("Textures that feel different: standard-1.0 scaled in height, each pair at least the minimum "
                     "JND apart, verified by a physics engine.")
            with ui.row().classes("items-end gap-4"):
                self.k = ui.number("Textures, k (--k)", value=2, min=2, max=12, step=1, format="%d").classes("w-40")
                self.min_jnd = ui.number("Minimum distance, JND (--min-jnd)", value=2.0, min=0.1, max=20, step=0.5,
                                         format="%.3g").classes("w-64")
                self.printer = PrinterChoice()
                self.verify = ui.select(list(VERIFIERS), value=next(iter(VERIFIERS)),
                                        label="Verified by (--verify)").classes("w-64")
                self.palette_button = ui.button("Make the palette", on_click=self.start_palette)
            self.palette_job = JobPanel("making the palette")
            self.palette_text = ui.column().classes("gap-0").props('role="status" aria-live="polite"')

    def _plate_card(self) -> None:
        with ui.card().classes("w-full"):
            ui.label("3. The plate").classes("text-lg").props('role="heading" aria-level="2"')
            self.plate_button = ui.button("Make the plate", on_click=self.start_plate)
            self.plate_job = JobPanel("making the plate")
            self.plate_text = ui.column().classes("gap-0").props('role="status" aria-live="polite"')
            with ui.row().classes("items-start gap-4"):
                self.relief = ui.image().classes("w-96").props('alt=""')
                self.feel = ui.image().classes("w-96").props('alt=""')
            ui.label("Tactile-graphics guidelines").classes("text-base font-bold").props('role="heading" aria-level="3"')
            self.checks = ui.column().classes("gap-0")
            ui.label(f"Sources: {GUIDELINE_SOURCES}").classes("text-sm")
            self.downloads = ui.row().classes("gap-4")

    # the picture

    def open_example(self, name: str) -> None:
        with resources.as_file(example_path(name)) as path:
            self._read(lambda: read_picture(path, self._tolerance(), self._width()))

    async def on_upload(self, event: events.UploadEventArguments) -> None:
        try:
            path = upload_path(self.session, event.file.name, event.file.size())
        except InputError as err:
            self.show_error(f"error: {err}")
            return
        await event.file.save(path)
        self._read(lambda: read_picture(path, self._tolerance(), self._width()))

    def recluster(self) -> None:
        if self.picture is None:
            self.show_error("error: open a picture first")
            return
        picture = self.picture
        self._read(lambda: cluster(picture.rgb, picture.name, self._tolerance(), self._width()))

    def _tolerance(self) -> float:
        return _number(self.tolerance.value, "--colour-tolerance")

    def _width(self) -> float:
        return _number(self.width.value, "--size-mm")

    def _read(self, read) -> None:
        try:
            picture = read()
        except InputError as err:
            self.show_error(f"error: {err}")
            return
        self.error.set_text("")
        self.picture = picture
        found, h, w = picture.colours, *picture.rgb.shape[:2]
        textured = len(picture.layout.textured)
        self.colours_text.set_text(f"{picture.name}: {w} x {h} pixels; {found.describe()}; {textured} to texture")
        self.clustered.set_source(png_url(_image(found.clustered())))
        self.clustered.props(f'alt="{picture.name} in its {len(found.colours)} flat colours"')
        self.colour_list.clear()
        with self.colour_list:
            for line in picture.colour_lines():
                ui.label(line)
        self.k.set_value(max(2, textured))

    def show_error(self, text: str) -> None:
        self.error.set_text(text)

    # the palette

    def start_palette(self) -> None:
        try:
            choice = PaletteChoice(_count(self.k.value, "--k"), _number(self.min_jnd.value, "--min-jnd"),
                                   self.printer.name,
                                   VERIFIERS[self.verify.value])
        except InputError as err:
            self.show_error(f"error: {err}")
            return
        self.error.set_text("")
        self.palette_job.start("palette", make_palette, choice, on_done=lambda palette: self.palette_made(palette,
                                                                                                           choice))

    def palette_made(self, palette: Palette, choice: PaletteChoice) -> None:
        from roughness.design.palette import save_palette

        save_palette(palette, self.session.path(PALETTE_FOLDER), overwrite=True)
        self.palette = palette, choice
        self.palette_text.clear()
        with self.palette_text:
            for line in palette_lines(palette, choice):
                ui.label(line)

    # the plate

    def start_plate(self) -> None:
        if self.picture is None or self.palette is None:
            self.show_error("error: " + ("open a picture first" if self.picture is None else "make a palette first"))
            return
        try:
            width, tolerance = self._width(), self._tolerance()
        except InputError as err:
            self.show_error(f"error: {err}")
            return
        self.error.set_text("")
        self.made += 1
        self.plate_job.start("plate", make_plate, self.picture.rgb, str(self.session.path(PALETTE_FOLDER)),
                             self.palette[1], width, tolerance, Session(self.session.id, self.session.folder),
                             f"plate-{self.made}", on_done=self.plate_made)

    def plate_made(self, made: MadePlate) -> None:
        names = {}
        for kind, data in (("relief", made.relief_png), ("feel", made.map_png)):
            names[kind] = f"plate-{self.made}-{kind}.png"
            self.session.path(names[kind]).write_bytes(data)
        plate = made.plate
        width, height = plate.heightmap.size_mm
        summary = (f"plate {width:.1f} x {height:.1f} mm, relief {np.ptp(plate.heightmap.heights):.2f} mm, "
                   f"{plate.heightmap.pixel_mm:g} mm pixels")
        self.plate_text.clear()
        with self.plate_text:
            for line in [summary, *region_lines(plate), *(f"note: {n}" for n in plate.notes)]:
                ui.label(line)
        self.relief.set_source(self.session.download_url(names["relief"]))
        self.relief.props(f'alt="Relief of the plate, {width:.0f} by {height:.0f} mm: dark is low, light is high"')
        self.feel.set_source(self.session.download_url(names["feel"]))
        self.feel.props('alt="Feel map of the plate: the predicted roughness V at each footprint centre, dark smooth, '
                        'light rough; the regions are listed as text"')
        self.checks.clear()
        with self.checks:
            for check in made.checks:
                ui.label(check.describe()).classes("text-green-10" if check.passed else "text-red-10")
        self.downloads.clear()
        with self.downloads:
            for kind, name in made.files.items():
                size = self.session.path(name).stat().st_size
                ui.link(f"Download the {KINDS[kind]}: {name} ({size:,} bytes)",
                        self.session.download_url(name)).props(f'download="{name}"').classes("text-primary")


def _number(value: object, flag: str) -> float:
    """A positive number typed into a field, or InputError naming its command-line flag."""
    if value is None:
        raise InputError(f"{flag}: give a number")
    return positive(flag, value)


def _count(value: object, flag: str) -> int:
    """A whole number (at least 2) typed into a field, or InputError naming its flag."""
    number = _number(value, flag)
    return integer(flag, int(number) if number.is_integer() else number, minimum=2)


def _image(rgb: np.ndarray):
    from PIL import Image

    image = Image.fromarray(rgb)
    if max(image.size) < 256:  # a small picture shown enlarged with its pixels kept sharp
        factor = 256 // max(image.size)
        image = image.resize((image.width * factor, image.height * factor), Image.NEAREST)
    return image


def build(session: Session) -> None:
    TactilePage(session)
