"""The Texture page: open or make a texture; its V, live under height and lateral-scale sliders (the surrogate),
verified by the spectral engine or the FEM in the background; tune it to a target; compare textures; download."""
from __future__ import annotations

import dataclasses
import time

from nicegui import run, ui

import roughness
from roughness.core.errors import InputError
from roughness.design.palette import variant
from roughness.design.tune import FACTOR_RANGE
from roughness.prediction import Prediction
from roughness.surface.heightmap import Heightmap

from ..compare_panel import ComparePanel
from ..downloads import DownloadPanel
from ..feel_view import FeelView, TexturePictures, scale_picture
from ..job_panel import JobPanel
from ..jobs import cli_flags
from ..sessions import Session
from ..texture_source import Texture, TextureSource
from ..work import VERIFY_ENGINES, tune, verify

PATH = "/texture"
TITLE = "Texture"
SUMMARY = "open or make a texture, see how rough it feels, tune it, compare it, download it"
LIVE_SECONDS = 0.05  # the sliders' answers are recomputed at most this often while they move
PICTURES_REST_S = 0.6  # the pictures of a live answer are drawn once the sliders rest this long
TUNE_VERIFIERS = ("spectral", "coarse", "default")  # roughness.design.evaluation.VERIFIERS, fastest first


class TexturePage:
    """The page's controls and results for one session."""

    def __init__(self, session: Session) -> None:
        self.texture: Texture | None = None
        self.prediction: Prediction | None = None
        self.verified: Prediction | None = None
        self.stale = False  # the sliders moved since the last answer
        self.pictures_due = False  # the answer is new, its pictures not yet drawn (drawn once the sliders rest)
        self.rested_from = 0.0  # when the sliders' last answer was shown (time.monotonic)
        self.busy = False  # a live answer or its pictures are being made
        TextureSource(session, self.set_texture)
        self.view = FeelView()
        self._sliders()
        self._verify()
        self._tune()
        ComparePanel(self.shown)
        DownloadPanel(session, self.downloadable)
        ui.timer(LIVE_SECONDS, self._live)

    # the texture and its live answer ---------------------------------------------------------------------------

    def _sliders(self) -> None:
        with ui.card().classes("w-full"):
            ui.label("Height and lateral scale (live, surrogate)").classes("text-lg").props('role="heading" '
                                                                                            'aria-level="2"')
            low, high = FACTOR_RANGE["height"]
            ui.label("Height factor (heights above their lowest point times this)")
            self.height = ui.slider(min=low, max=high, step=0.01, value=1.0, on_change=self._moved).props(
                'label aria-label="Height factor"').mark("height-slider")
            low, high = FACTOR_RANGE["lateral"]
            ui.label("Lateral scale (the texture stretched by this)")
            self.lateral = ui.slider(min=low, max=high, step=0.01, value=1.0, on_change=self._moved).props(
                'label aria-label="Lateral scale"').mark("lateral-slider")
            self.factors = ui.label("height x 1.00, lateral x 1.00")

    def set_texture(self, texture: Texture) -> None:
        self.texture = texture
        self.height.value = self.lateral.value = 1.0
        self.stale = False
        self.verified = None
        self.verify_result.set_text("")
        self._answer("auto")  # as `roughness predict` answers (its default engine)

    def current(self) -> Heightmap:
        """The texture as the sliders scale it (``roughness.design.palette.variant``)."""
        return variant(self.texture.heightmap, float(self.height.value), float(self.lateral.value))

    def current_name(self) -> str:
        h, lat = float(self.height.value), float(self.lateral.value)
        return self.texture.name if (h, lat) == (1.0, 1.0) else f"{self.texture.name} (height x {h:.2f}, lateral x {lat:.2f})"

    def _moved(self) -> None:
        self.stale = self.texture is not None
        self.factors.set_text(f"height x {float(self.height.value):.2f}, lateral x {float(self.lateral.value):.2f}")

    async def _live(self) -> None:
        """While the sliders move, the answer in words (the surrogate, in a worker thread, so the page stays
        responsive); its pictures (tenths of a second to draw) once the sliders have rested ``PICTURES_REST_S``."""
        if self.busy or self.texture is None:
            return
        self.busy = True
        try:
            if self.stale:
                self.stale = False
                hm, name = self.current(), self.current_name()
                p = await run.io_bound(self._predict, name, hm, "surrogate")
                if p is not None:
                    self.view.show_answer(p)
                    self.pictures_due, self.rested_from = True, time.monotonic()
            elif self.pictures_due and time.monotonic() - self.rested_from >= PICTURES_REST_S:
                self.pictures_due = False
                hm, name, p = self.current(), self.current_name(), self.prediction
                drawn, scale = await run.io_bound(lambda: (TexturePictures.draw(hm), scale_picture(p)))
                self.view.show_texture(name, hm, self.texture.notes, drawn)
                self.view.show_scale(p, scale)
        finally:
            self.busy = False

    def _predict(self, name: str, hm: Heightmap, engine: str) -> Prediction | None:
        """V of the texture (``roughness.predict``); None with the error shown."""
        try:
            [p] = roughness.predict({name: hm}, engine=engine, units_ok=True)  # units checked as it was read
        except InputError as err:
            self.view.answer.set_text(f"error: {err}")
            return None
        self.prediction = p
        return p

    def _answer(self, engine: str) -> None:
        """The answer and all its pictures at once (a texture just opened)."""
        hm, name = self.current(), self.current_name()
        p = self._predict(name, hm, engine)
        if p is not None:
            self.view.show_texture(name, hm, self.texture.notes)
            self.view.show_prediction(p)

    # verify ------------------------------------------------------------------------------------------------------

    def _verify(self) -> None:
        with ui.card().classes("w-full"):
            ui.label("Verify").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("items-end gap-4"):
                self.verify_engine = ui.select(list(VERIFY_ENGINES), value="spectral", label="Engine").classes("w-48").mark("verify-engine")
                ui.button("Verify", on_click=self.start_verify).props('aria-label="Verify the current texture"').mark("verify")
            self.verify_job = JobPanel("verify")
            self.verify_result = ui.label("").props('role="status" aria-live="polite"').mark("verify-result")

    def start_verify(self) -> None:
        if self.texture is None:
            self.verify_result.set_text("Open or make a texture first.")
            return
        self.verify_job.start(f"verify ({self.verify_engine.value})", verify, self.current_name(), self.current(),
                              self.verify_engine.value, on_done=self._verified, flags=cli_flags("predict"))

    def _verified(self, p: Prediction) -> None:
        from roughness.cli.predict import prediction_line

        self.verified = p
        self.verify_result.set_text("Verified: " + prediction_line(p))

    # tune --------------------------------------------------------------------------------------------------------

    def _tune(self) -> None:
        with ui.card().classes("w-full"):
            ui.label("Tune to a target").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("items-end gap-4"):
                self.tune_kind = ui.select({"lambda": "equivalent lambda (mm)", "jnd": "JND from this texture"},
                                           value="lambda", label="Target").classes("w-56").mark("tune-kind")
                self.tune_value = ui.number("Target value", value=1.0, format="%.4g").classes("w-32").mark("tune-value")
                self.tune_by = ui.select(["height", "lateral"], value="height", label="Knob").classes("w-32").mark("tune-by")
                self.tune_verifier = ui.select(list(TUNE_VERIFIERS), value="spectral",
                                               label="Verified by").classes("w-32")
                ui.button("Tune", on_click=self.start_tune).props('aria-label="Tune the current texture"').mark("tune")
            self.tune_job = JobPanel("tune")
            self.tune_result = ui.label("").props('role="status" aria-live="polite"').mark("tune-result")

    def start_tune(self) -> None:
        if self.texture is None:
            self.tune_result.set_text("Open or make a texture first.")
            return
        value = self.tune_value.value
        lam, jnd = (value, None) if self.tune_kind.value == "lambda" else (None, value)
        self.tune_job.start("tune", tune, self.current(), self.tune_by.value, lam, jnd, self.tune_verifier.value,
                            on_done=self._tuned, flags=cli_flags("tune"))

    def _tuned(self, result) -> None:
        self.tune_result.set_text(f"Tuned: {result!r}. The tuned texture is now the page's texture.")
        name = f"{self.texture.name} tuned ({result.by} x {result.factor:.3f})"
        self.set_texture(dataclasses.replace(self.texture, heightmap=result.heightmap, name=name))

    def shown(self) -> tuple[str, Heightmap] | None:
        """The texture as the page shows it (name, heightmap), or None."""
        return None if self.texture is None else (self.current_name(), self.current())

    def downloadable(self) -> tuple[Heightmap, dict] | None:
        """The texture as shown and its JSON report: the texture, the sliders, the answer (as `roughness predict
        --json` gives it), any verification."""
        if self.texture is None or self.prediction is None:
            return None
        return self.current(), {"texture": self.texture.name, "recipe": self.texture.recipe,
                                "height_factor": float(self.height.value),
                                "lateral_factor": float(self.lateral.value), "prediction": self.prediction.as_dict(),
                                "notes": list(self.texture.notes),
                                "verified": None if self.verified is None else self.verified.as_dict()}


def build(session: Session) -> None:
    TexturePage(session)
