"""Plan a textured mesh for a printer: the edge length the printer calls for, and what the refined mesh will cost
(triangles, STL bytes, time) before any refinement starts.

Edge length from a printer (``printer_edge``). A triangle edge is a sample of the texture on the surface; edges
finer than what the printer reproduces laterally only add triangles the slicer and printer throw away:

- FDM: the bead is ``line_width_mm`` wide and nothing narrower than one line is printed
  (``roughness.surface.printing``, step 3); samples at half the line width (the Nyquist step of the narrowest
  printable feature) catch every feature the bead can make;
- SLA/MSLA: heights are held over each LCD pixel (``pixel_mm``), so one sample per printer pixel is all the
  printer can use.

The edge is never finer than sqrt(2) times the texture's pixel on the surface (today's default: the right triangles
of longest-edge bisection then have legs of about one texture pixel), since below that there is no more texture to
sample.

Cost (``mesh_plan``): triangles from ``remesh.predicted_triangles`` (measured on a sample of the faces), bytes from
``meshes.stl_bytes``, time from the rates measured in benchmarks/results/object_texture.md (a 60 mm ball refined
to 13,107,200 triangles: refine to displace and closed checks 113.1 s, self-intersection check 93.5 s, binary STL
6.9 s, on 2 cores shared with other jobs, so a quiet machine is faster), memory from the peak measured on a CAD
cube (``PEAK_BYTES_PER_TRIANGLE``).

Budget (``require_within``): a plan above MAX_MESH_TRIANGLES is refused before anything is refined, with
its cost and what fits: the edge at which the estimate falls within the limit (found by estimating again, since the
count jumps with the number of halvings) and the area that fits at the asked edge (triangles grow with the area).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roughness.core.errors import InputError
from roughness.core.limits import MAX_MESH_TRIANGLES, Limit

from .meshes import stl_bytes
from .remesh import predicted_triangles

_BENCH_TRIANGLES = 13_107_200  # benchmarks/results/object_texture.md
REFINE_SECONDS_PER_TRIANGLE = (63.5 + 11.9 + 1.9 + 18.6 + 17.2) / _BENCH_TRIANGLES
"""Refine, normals, heights, concave radius, displace and closed checks (s per output triangle)."""
CHECK_SECONDS_PER_TRIANGLE = 93.5 / _BENCH_TRIANGLES
"""The self-intersection check (s per output triangle)."""
WRITE_SECONDS_PER_TRIANGLE = 6.9 / _BENCH_TRIANGLES
"""Writing a binary STL (s per triangle)."""
PEAK_BYTES_PER_TRIANGLE = 371
"""Peak memory of ``object texture`` per output triangle (bytes): 4.56 GB (maximum resident set) texturing the
40 mm octant cube of tests/test_mesh_solid.py whole with standard-1.0 at the default edge, 12,589,056 triangles
(self-intersection check and STL included)."""
BUDGET_MARGIN = 0.9
"""The fitting edge and area are chosen for this fraction of the limit (the estimate is a sample's)."""
FIT_STEP = 1.1
"""Each try at a fitting edge is this much coarser than the last."""
SLICER_TRIANGLES = 5_000_000
"""Above this a slicer struggles: a 250 MB binary STL. PrusaSlicer and Cura keep every triangle in memory several
times over (mesh, slices, preview) and their load and slice times grow with it; meshes of a few million triangles
load in seconds to a minute, beyond about five million loading and slicing take minutes and several GB of memory,
and some online services and firmwares' file systems cap uploads at a few hundred MB. A rule of thumb, not a
measured limit: the warning says so."""


@dataclass(frozen=True)
class EdgeChoice:
    """The longest textured edge (mm) for a printer and why: ``printer_mm`` the finest step the printer reproduces
    (half an FDM line, one SLA pixel), ``texture_mm`` sqrt(2) x the texture's pixel on the surface."""

    edge_mm: float
    printer_mm: float
    texture_mm: float
    printer: str  # the profile's name
    printer_step: str  # what printer_mm is, in words

    def note(self) -> str:
        """The rule, in one line."""
        bound = ("the printer's" if self.edge_mm == self.printer_mm else
                 "the texture's (the printer reproduces finer steps than the texture holds)")
        return (f"edge length {self.edge_mm:.4g} mm from the printer {self.printer}: the larger of {self.printer_step} "
                f"({self.printer_mm:.4g} mm, the finest step it prints) and sqrt(2) x the texture's pixel on the "
                f"surface ({self.texture_mm:.4g} mm, the finest the texture holds); {bound} bound applies "
                "(--edge-mm sets it)")


def printer_edge(profile, texture_pixel_mm: float) -> EdgeChoice:
    """The ``EdgeChoice`` for ``profile`` (a ``PrintProfile``) and a texture of ``texture_pixel_mm`` (mm, on the
    surface) (module docstring)."""
    if profile.kind == "fdm":
        step, words = profile.line_width_mm / 2, f"half its {profile.line_width_mm:g} mm line width"
    else:
        step, words = profile.pixel_mm, f"its {1e3 * profile.pixel_mm:g} um pixel"
    texture = math.sqrt(2) * texture_pixel_mm
    return EdgeChoice(max(step, texture), step, texture, profile.name, words)


def chosen_edge(edge_mm: float | None, profile, texture_pixel_mm: float) -> tuple[float, str | None]:
    """The longest textured edge (mm) and the note of its rule: ``edge_mm`` if given (no note), else the printer's
    (``printer_edge``; ``profile`` a ``PrintProfile`` or None), else sqrt(2) x the texture's pixel on the surface
    (``texture_pixel_mm``, mm; no note)."""
    if edge_mm is not None:
        return edge_mm, None
    if profile is not None:
        choice = printer_edge(profile, texture_pixel_mm)
        return choice.edge_mm, choice.note()
    return math.sqrt(2) * texture_pixel_mm, None


@dataclass(frozen=True)
class MeshPlan:
    """What refining to ``edge_mm`` (mm) will make: about ``triangles`` (measured on a sample), an STL of ``stl_bytes``, in
    about ``seconds`` (texturing, checks and writing, at the benchmark's rates) using about ``memory_bytes`` at the
    peak; of the triangles, ``untextured_triangles`` are the faces left as they are, the rest refine
    ``textured_area_mm2``."""

    edge_mm: float
    triangles: int
    stl_bytes: int
    seconds: float
    memory_bytes: int
    textured_area_mm2: float
    untextured_triangles: int

    @property
    def too_large(self) -> bool:
        """More triangles than a slicer handles comfortably (``SLICER_TRIANGLES``)."""
        return self.triangles > SLICER_TRIANGLES

    def line(self) -> str:
        """The plan in one line; the time is an estimate, and said to be one."""
        return (f"expected: about {self.triangles:,} triangles (refined on a sample of the faces), a binary STL of about "
                f"{_mb(self.stl_bytes)} MB, about {_duration(self.seconds)} (estimated from "
                "benchmarks/results/object_texture.md; a busy or slower machine takes longer)")

    def warning(self) -> str | None:
        """A warning if the file would be more than a slicer handles comfortably, else None."""
        if not self.too_large:
            return None
        return (f"the textured mesh would have about {self.triangles:,} triangles ({_mb(self.stl_bytes)} MB), "
                f"above the ~{SLICER_TRIANGLES / 1e6:g} M triangles ({_mb(stl_bytes(SLICER_TRIANGLES))} MB) "
                "slicers handle comfortably (a rule of thumb: loading and slicing take minutes and GB of memory); "
                "a larger --edge-mm, a smaller --region or a --printer profile to set the edge avoids it")

    def as_dict(self) -> dict:
        return {"edge_mm": self.edge_mm, "triangles": self.triangles, "stl_bytes": self.stl_bytes,
                "seconds": self.seconds, "memory_bytes": self.memory_bytes,
                "too_large_for_slicers": self.too_large, "slicer_triangles": SLICER_TRIANGLES}

    def cost(self) -> str:
        """Triangles, memory and time, in words."""
        return (f"about {self.triangles:,} triangles, {_gb(self.memory_bytes)} GB of memory and "
                f"{_duration(self.seconds)}")


def mesh_plan(vertices: np.ndarray, faces: np.ndarray, selected: np.ndarray, edge_mm: float,
              check_intersections: bool = True) -> MeshPlan:
    """The ``MeshPlan`` of refining the ``selected`` faces (bool per face) of a mesh (mm) to edges of ``edge_mm``
    (mm)."""
    triangles = int(math.ceil(predicted_triangles(vertices, faces, selected, edge_mm)))
    rate = REFINE_SECONDS_PER_TRIANGLE + WRITE_SECONDS_PER_TRIANGLE
    if check_intersections:
        rate += CHECK_SECONDS_PER_TRIANGLE
    tri = vertices[faces[selected]]
    area = float(0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum())
    return MeshPlan(edge_mm, triangles, stl_bytes(triangles), triangles * rate, triangles * PEAK_BYTES_PER_TRIANGLE,
                    area, int((~selected).sum()))


def require_within(plan: MeshPlan, vertices: np.ndarray, faces: np.ndarray, selected: np.ndarray,
                   check_intersections: bool = True, limit: Limit = MAX_MESH_TRIANGLES) -> None:
    """InputError (naming --edge-mm) if ``plan`` (of the ``selected`` faces of the mesh) makes more than ``limit``
    triangles: its cost, the coarsest edge whose estimate fits (tried from the edge that scaling by the square
    root of the excess gives, FIT_STEP coarser each try), and the textured area that fits at the plan's edge."""
    if plan.triangles <= limit:
        return
    room = BUDGET_MARGIN * limit - plan.untextured_triangles
    if room <= 0:
        raise InputError(f"the mesh's {plan.untextured_triangles:,} untextured faces alone come near the limit of "
                         f"{limit:,} triangles ({limit.name})",
                         parameter="mesh")
    textured = plan.triangles - plan.untextured_triangles
    edge = _up(plan.edge_mm * math.sqrt(textured / room))
    for _ in range(40):
        fit = mesh_plan(vertices, faces, selected, edge, check_intersections)
        if fit.triangles <= BUDGET_MARGIN * limit:
            break
        edge = _up(edge * FIT_STEP)
    area = plan.textured_area_mm2 * room / textured
    raise InputError(f"edges of {plan.edge_mm:.4g} mm would make {plan.cost()}, above the limit of {limit:,} "
                     f"triangles ({limit.name}); what fits: --edge-mm {edge:g} ({fit.cost()}), or at this "
                     f"edge a --region of at most {area:,.0f} mm^2 of the {plan.textured_area_mm2:,.0f} mm^2 asked",
                     parameter="edge_mm")


def _up(value: float) -> float:
    """``value`` rounded up to two significant digits."""
    digits = 1 - math.floor(math.log10(value))
    return float(f"{math.ceil(value * 10**digits) / 10**digits:.{max(digits, 0)}f}")


def _gb(size: int) -> str:
    """``size`` (bytes) in GB: one decimal under 10 GB, whole GB above."""
    return f"{size / 1e9:.1f}" if size < 10e9 else f"{size / 1e9:,.0f}"


def _duration(seconds: float) -> str:
    """``seconds`` in words: seconds under two minutes, then minutes, then hours."""
    if seconds < 120:
        return f"{max(seconds, 1):.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def _mb(size: int) -> str:
    """``size`` (bytes) in MB: one decimal under 10 MB, whole MB above."""
    return f"{size / 1e6:.1f}" if size < 10e6 else f"{size / 1e6:,.0f}"
