"""How a texture feels, shown: V with its uncertainty and the engine (the CLI's own line), the heightmap, its
shaded 3D relief, and its place on the standard scale as a picture and in words."""
from __future__ import annotations

from dataclasses import dataclass

from nicegui import ui

from roughness.prediction import Prediction
from roughness.surface.heightmap import Heightmap

from .pictures import heightmap_url, relief_points, scale_url, shaded_url


def placement_text(p: Prediction) -> str:
    """The place on the standard scale in words (what the scale picture shows)."""
    where = p.placement
    if where.below_scale:
        return f"Below the standard scale: V {p.roughness:.4f} is under its floor {where.floor:.4f}."
    steps = round(where.jnd_from_nearest, 1)
    side = (f"{abs(steps):.1f} JND {'rougher' if steps > 0 else 'smoother'} than" if steps else
            "0.0 JND from (as rough as)")
    off = "" if where.on_scale else " (extrapolated beyond the scale's ends)"
    return (f"On the standard scale{off}: feels like bumps {where.equivalent_lambda_mm:.3f} mm apart, "
            f"{side} {where.nearest_standard}.")


class FeelView:
    """The results card of a texture page."""

    def __init__(self, heading: str = "How it feels", mark: str = "") -> None:
        """``mark``: a prefix of the markers of its texts (tests find them by it)."""
        with ui.card().classes("w-full"):
            ui.label(heading).classes("text-lg").props('role="heading" aria-level="2"')
            self.answer = ui.label("Open or make a texture.").props('role="status" aria-live="polite"').mark(f"{mark}answer")
            self.placement = ui.label("").mark(f"{mark}placement")
            self.notes = ui.label("").classes("text-sm text-grey-8")
            with ui.row().classes("gap-4 items-start"):
                self.heightmap = ui.image().classes("w-64 h-64").props('alt="no texture yet" fit="contain"')
                self.scene = ui.scene(width=320, height=256, grid=False).props('role="img" aria-label="3D relief: '
                                                                               'no texture yet"')
                with self.scene:
                    self.relief = None
                self.scale = ui.image().classes("w-96").props('alt="standard scale: no texture yet" fit="contain"')

    def show_texture(self, name: str, hm: Heightmap, notes: tuple[str, ...] = (),
                     drawn: TexturePictures | None = None) -> None:
        """The pictures of the heightmap ``hm`` (``drawn``: already drawn, e.g. in a worker thread)."""
        ny, nx = hm.shape
        size = f"{nx * hm.pixel_mm:.3g} x {ny * hm.pixel_mm:.3g} mm"
        relief = float(hm.heights.max() - hm.heights.min())
        drawn = drawn or TexturePictures.draw(hm)
        self.heightmap.set_source(drawn.heightmap)
        self.heightmap.props(f'alt="Heightmap of {name}, {size}, relief {relief:.3f} mm: dark is low, light is high"')
        points, shaded = drawn.points, drawn.shaded
        if self.relief is None:
            with self.scene:
                self.relief = self.scene.texture(shaded, points)
        else:
            self.relief.set_url(shaded)
            self.relief.set_coordinates(points)
        width = nx * hm.pixel_mm
        self.scene.move_camera(x=width / 2, y=-1.05 * width, z=0.75 * width, look_at_x=width / 2, look_at_y=-width / 2,
                               duration=0)
        self.scene.props(f'aria-label="Shaded 3D relief of {name}, {size}, relief {relief:.3f} mm (drag to orbit)"')
        self.notes.set_text(" ".join(f"Note: {n}" for n in notes))

    def show_prediction(self, p: Prediction) -> None:
        """V, its uncertainty and engine (as `roughness predict` prints it), and the scale picture."""
        self.show_answer(p)
        self.show_scale(p)

    def show_answer(self, p: Prediction) -> None:
        """The answer in words: V, its uncertainty, the engine, the place on the scale."""
        from roughness.cli.predict import prediction_line

        self.answer.set_text(prediction_line(p))
        self.placement.set_text(placement_text(p))

    def show_scale(self, p: Prediction, drawn: str | None = None) -> None:
        """The standard scale picture of ``p`` (``drawn``: its ``scale_picture``, already drawn)."""
        self.scale.set_source(drawn or scale_picture(p))
        self.scale.props(f'alt="Standard scale picture. {placement_text(p)}"')


def scale_picture(p: Prediction) -> str:
    """The standard scale picture (a data URL) of the prediction ``p``, on the scale of its fidelity."""
    from roughness.perceptual_scale import load_scale

    return scale_url(load_scale(p.fidelity), p.roughness, p.placement)


@dataclass(frozen=True)
class TexturePictures:
    """The pictures of a heightmap (data URLs) and the points of its 3D relief, drawn apart from showing them."""

    heightmap: str
    shaded: str
    points: list

    @classmethod
    def draw(cls, hm: Heightmap) -> TexturePictures:
        return cls(heightmap_url(hm), shaded_url(hm), relief_points(hm))
