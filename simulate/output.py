"""Writers for simulation results: strain-map image and ParaView mesh."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.figures import new_figure, save_figure
from roughness.core.files import atomic_write

from .elasticity import strain_tensors, vertex_strain_operator
from .model import Block
from .result import Result

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def save_strain_png(result: Result, path: str | Path | None = None, overwrite: bool = True) -> Figure:
    """Image of lambda3 at receptor depth and its fluctuation (strain, dimensionless); PNG to ``path`` if given.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (no pyplot: the backend is left as it was).
    """
    a = result.grid_axis_mm
    c = result.config
    extent = (a[0], a[-1], a[0], a[-1])
    fig = new_figure(figsize=(10, 4.6), layout="constrained")
    axes = fig.subplots(1, 2)
    panels = ((result.lambda3, f"$\\lambda_3$ at {c.depth_mm} mm depth",
               "max. compressive principal strain $\\lambda_3$ (dimensionless)"),
              (result.fluctuation, "fluctuation: $\\lambda_3$ minus that of the flat texture",
               "strain fluctuation $\\Delta\\lambda_3$ (dimensionless)"))
    for ax, (field, title, label) in zip(axes, panels):
        im = ax.imshow(field, origin="lower", extent=extent, cmap="viridis")
        ax.set(title=title, xlabel="x (mm)", ylabel="y (mm)")
        fig.colorbar(im, ax=ax, shrink=0.85, label=label)
    fig.suptitle(f"FEM ({c.fidelity} fidelity, h = {c.h_contact_mm} mm): V = {result.roughness:.4g} ± "
                 f"{result.roughness_stderr:.2g}   (F = {c.force_n} N, contact {100 * result.contact_fraction:.0f}%)")
    return save_figure(fig, path, 110, overwrite)


def save_vtu(result: Result, block: Block, path: str | Path, overwrite: bool = True) -> None:
    """Deformed mesh with displacement, element strain and lambda3 for ParaView."""
    import meshio

    mesh = block.mesh
    u = result.state.u
    g, dofs, _ = vertex_strain_operator(mesh)
    eps = strain_tensors(g, dofs, u).mean(axis=1)
    lam = np.linalg.eigvalsh(eps)
    voigt = eps.reshape(-1, 9)[:, [0, 4, 8, 5, 2, 1]]
    cell = "tetra" if mesh.order == 1 else "tetra10"
    m = meshio.Mesh(
        mesh.points + u.reshape(-1, 3),
        [(cell, mesh.tets)],
        point_data={"displacement": u.reshape(-1, 3)},
        cell_data={"strain": [voigt], "lambda3": [lam[:, 0]], "region": [mesh.region.astype(np.int32)]},
    )
    atomic_write(path, lambda tmp: meshio.write(tmp, m, file_format="vtu"), overwrite)

