"""Pictures the pages show, as data URLs of PNG images (no file, nothing fetched from elsewhere): the heightmap in
grey, its shaded relief, the points of its 3D relief, and its place on the standard scale."""
from __future__ import annotations

import base64
import io

import numpy as np
from PIL import Image

from roughness.core.figures import new_figure
from roughness.perceptual_scale import Placement, StandardScale
from roughness.surface.heightmap import Heightmap

RELIEF_POINTS = 64  # points a side of the 3D relief (the heightmap sampled on this grid)


def png_url(image: Image.Image) -> str:
    """``image`` as a ``data:image/png`` URL."""
    buffer = io.BytesIO()
    image.save(buffer, format="PNG")
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def _grey(values: np.ndarray, side_px: int) -> str:
    span = float(values.max() - values.min())
    grey = np.zeros(values.shape, np.uint8) if span == 0 else np.rint((values - values.min()) / span * 255)
    image = Image.fromarray(grey.astype(np.uint8))
    image.thumbnail((side_px, side_px))
    return png_url(image)


def heightmap_url(hm: Heightmap, side_px: int = 320) -> str:
    """The heightmap in grey (black: lowest, white: highest), at most ``side_px`` pixels a side."""
    return _grey(np.asarray(hm.heights, dtype=float), side_px)


def shaded_url(hm: Heightmap, side_px: int = 320) -> str:
    """The heightmap lit from the upper left (matplotlib's hill shading, true to scale in mm)."""
    from matplotlib.colors import LightSource

    shade = LightSource(azdeg=315, altdeg=45).hillshade(np.asarray(hm.heights, float), dx=hm.pixel_mm, dy=hm.pixel_mm)
    return _grey(shade, side_px)


def relief_points(hm: Heightmap, points: int = RELIEF_POINTS) -> list[list[list[float]]]:
    """The heightmap sampled on a ``points`` x ``points`` grid as [x, y, z] in mm (rows of points), heights above
    their minimum: the vertices of the 3D relief."""
    ny, nx = hm.shape
    rows = np.linspace(0, ny - 1, min(points, ny)).round().astype(int)
    cols = np.linspace(0, nx - 1, min(points, nx)).round().astype(int)
    z = np.asarray(hm.heights, float)[np.ix_(rows, cols)]
    z = z - z.min()
    x, y = (cols + 0.5) * hm.pixel_mm, (rows + 0.5) * hm.pixel_mm
    return [[[float(x[i]), float(-y[j]), float(z[j, i])] for i in range(len(cols))] for j in range(len(rows))]


def scale_url(scale: StandardScale, roughness: float, placement: Placement) -> str:
    """The standard scale as a picture: its reference textures' V over their wavelength (log-log), the texture's
    V as a line and its equivalent wavelength as a point, with the JND to the nearest reference."""
    fig = new_figure(figsize=(5.2, 3.2), dpi=100, layout="constrained")
    ax = fig.add_subplot()
    ax.loglog(scale.lambdas_mm, scale.roughness, "o-", color="0.35", label="standard textures")
    ax.axhline(scale.floor, color="0.6", ls=":", label="floor of the scale")
    ax.axhline(roughness, color="tab:red", lw=1, label=f"this texture: V = {roughness:.4f}")
    if placement.equivalent_lambda_mm is not None:
        ax.plot([placement.equivalent_lambda_mm], [roughness], "D", color="tab:red", ms=8)
        ax.annotate(f"λ {placement.equivalent_lambda_mm:.3f} mm\n{round(placement.jnd_from_nearest, 1) + 0.0:+.1f} JND from "
                    f"{placement.nearest_standard}", (placement.equivalent_lambda_mm, roughness),
                    textcoords="offset points", xytext=(8, -28), fontsize=8)
    ax.set(xlabel="wavelength λ of the standard bumps (mm)", ylabel=f"V ({scale.fidelity} FEM)",
           title=f"The standard scale ({len(scale.lambdas_mm)} references)")
    ax.legend(fontsize=7, loc="upper left")
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")
