"""Simulation parameters (mm, N, MPa) and fidelity levels."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from dataclasses import fields as dataclass_fields

from roughness.core.checks import in_range, integer, positive, real
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap

from .curved import AXES, TEXTURE_ALONG, BaseShape, require_restable
from .discretization import LADDER_MM
from .mesh import MeshSpec

# Contact-face spacing (mm) per fidelity; ``auto`` picks from this ladder; ``converged`` refines
# (simulate/converged.py) until V's estimated discretization error is below ``tolerance``.
FIDELITY_SPACING_MM = {"coarse": 0.3, "default": 0.2, "fine": 0.14}
FIDELITIES = ("coarse", "default", "fine", "auto", "converged")
CONTACT_MODES = ("stick", "frictionless")
BONE_MODELS = ("rigid", "elastic")
ELEMENTS = ("p1", "p2")
CURVED_BASES = ("cylinder", "sphere")
CHOICES = {"fidelity": FIDELITIES, "contact": CONTACT_MODES, "bone": BONE_MODELS, "element": ELEMENTS,
           "base": CURVED_BASES, "curvature_axis": AXES, "texture_along": TEXTURE_ALONG}

# Where linear small-strain elasticity stops meaning anything (both engines refuse): the skin is pushed
# further than this many tissue thicknesses (the paper's own regime reaches about 2 at 10 N on 1 mm bumps).
MAX_INDENTATION_TISSUES = 4.0
DEEP_INDENTATION_TISSUES = 2.0  # beyond this an indentation is unusual (a note on stderr)

# SimConfig fields that do not shape the prepared skin block, so a Simulator reuses one block
# for all of them: the load and contact law (force_n, contact, max_rounds: the contact solve per
# texture) and the disk-pair sampling of V (pairs, pair_distance_mm, disk_radius_mm, seed), and the
# base shape under the texture (curvature_mm, base, curvature_axis, texture_along: the block keeps
# one untextured base field per shape). Every other field enters BlockSpec (fidelity through the
# h_contact_mm it resolves to).
CURVED_FIELDS = ("curvature_mm", "base", "curvature_axis", "texture_along")
RUN_FIELDS = frozenset({"force_n", "contact", "max_rounds", "pairs", "pair_distance_mm", "disk_radius_mm", "seed",
                        "tolerance", *CURVED_FIELDS})


@dataclass(frozen=True)
class BlockSpec:
    """Exactly what the prepared skin block (mesh, stiffness, strain sampler) depends on; its cache key."""

    mesh: MeshSpec
    young_mpa: float
    poisson: float
    bone_young_mpa: float
    bone_poisson: float
    depth_mm: float
    window_mm: float
    grid_mm: float


@dataclass(frozen=True)
class SimConfig:
    """Everything that defines one FEM roughness evaluation except the texture.

    Curved base (``roughness.simulate.curved``): ``curvature_mm`` is the signed radius (mm; > 0
    convex toward the finger, < 0 concave; None: flat) of a ``base`` cylinder (straight along
    ``curvature_axis``) or sphere; ``texture_along`` lays the heights off along the base normal or z.
    """

    young_mpa: float = 0.042
    poisson: float = 0.45
    tissue_mm: float = 2.5
    width_mm: float = 10.0
    bone: str = "rigid"
    bone_young_mpa: float = 18000.0
    bone_poisson: float = 0.3
    bone_mm: float = 2.5
    force_n: float = 10.0
    contact: str = "stick"
    fidelity: str = "default"
    tolerance: float = 0.03  # converged: target relative discretization error of V
    element: str = "p1"
    h_contact_mm: float | None = None
    depth_mm: float = 0.75
    window_mm: float = 8.0
    grid_mm: float = 0.05
    pairs: int = 8000
    pair_distance_mm: float = 0.8
    disk_radius_mm: float = 0.8
    seed: int = 0
    max_rounds: int = 30
    curvature_mm: float | None = None
    base: str = "cylinder"
    curvature_axis: str = "x"
    texture_along: str = "normal"

    def __post_init__(self) -> None:
        for name, options in CHOICES.items():
            if getattr(self, name) not in options:
                raise InputError(f"{name} must be one of {', '.join(options)}; got {getattr(self, name)!r}",
                                 parameter=name)
        for name in ("young_mpa", "tissue_mm", "width_mm", "bone_young_mpa", "bone_mm", "force_n",
                     "depth_mm", "window_mm", "grid_mm", "pair_distance_mm", "disk_radius_mm"):
            positive(name, getattr(self, name))
        for name in ("poisson", "bone_poisson"):
            if not -1.0 < real(name, getattr(self, name)) < 0.5:
                raise InputError(f"{name} must lie in (-1, 0.5), got {getattr(self, name)}", parameter=name)
        if self.h_contact_mm is not None:
            positive("h_contact_mm", self.h_contact_mm)
        positive("tolerance", self.tolerance)
        in_range("tolerance", self.tolerance, 0.0, 1.0)
        if self.depth_mm >= self.tissue_mm:
            raise InputError(f"receptor depth {self.depth_mm} mm must be inside the {self.tissue_mm} mm tissue",
                             parameter="depth_mm")
        if self.window_mm > self.width_mm:
            raise InputError(f"sampling window {self.window_mm} mm exceeds the {self.width_mm} mm footprint",
                             parameter="window_mm")
        if self.window_mm / 2 <= self.pair_distance_mm / 2 + self.disk_radius_mm:
            raise InputError("disk pairs (d/2 + r) do not fit in the sampling window", parameter="pair_distance_mm")
        integer("pairs", self.pairs, minimum=2)
        integer("max_rounds", self.max_rounds, minimum=1)
        integer("seed", self.seed, minimum=0)
        if self.curvature_mm is not None:
            if real("curvature_mm", self.curvature_mm) == 0:
                raise InputError("curvature_mm is a signed radius (> 0 convex, < 0 concave); 0 is not a radius "
                                 "(leave it unset for a flat base)", parameter="curvature_mm")
            if abs(self.curvature_mm) < self.depth_mm:
                raise InputError(
                    f"a base of radius {abs(self.curvature_mm):g} mm is far below the {self.width_mm:g} mm skin "
                    f"footprint's scale: at the {self.depth_mm:g} mm depth where the model reads the skin's strain it "
                    f"is an edge, not a curved surface; |curvature_mm| must be at least {self.depth_mm:g} mm "
                    "(the receptor depth)", parameter="curvature_mm")
            require_restable(self.base_shape(), self.width_mm)

    def updated(self, **fields: object) -> SimConfig:
        """This configuration with ``fields`` replaced, checked; InputError naming an unknown field."""
        known = {f.name for f in dataclass_fields(self)}
        unknown = [name for name in fields if name not in known]
        if unknown:
            raise InputError(f"{unknown[0]!r} is not a simulation parameter; SimConfig's fields are "
                             f"{', '.join(sorted(known))}", parameter=unknown[0])
        return replace(self, **fields)

    def base_shape(self) -> BaseShape:
        """The untextured base under the texture (flat unless ``curvature_mm`` is set)."""
        if self.curvature_mm is None:
            return BaseShape()
        return BaseShape(self.base, float(self.curvature_mm), self.curvature_axis)

    def spacing_mm(self, heightmap: Heightmap | None = None) -> float:
        """Contact-face spacing for this fidelity (``auto`` needs the heightmap; ``converged``
        starts at the coarsest rung of its ladder)."""
        if self.h_contact_mm is not None:
            return self.h_contact_mm
        if self.fidelity == "converged":
            return LADDER_MM[0]
        if self.fidelity != "auto":
            return FIDELITY_SPACING_MM[self.fidelity]
        feature = heightmap.feature_size_mm() if heightmap is not None else math.inf
        ladder = sorted(FIDELITY_SPACING_MM.values(), reverse=True)
        return next((h for h in ladder if h <= feature / 4), ladder[-1])

    def resolved(self, heightmap: Heightmap | None = None) -> SimConfig:
        """The same configuration with the mesh spacing fixed (for caching and records)."""
        return replace(self, h_contact_mm=self.spacing_mm(heightmap))

    def mesh_spec(self) -> MeshSpec:
        if self.h_contact_mm is None:
            raise ValueError("resolve the configuration first")
        h = self.h_contact_mm
        return MeshSpec(
            width_mm=self.width_mm,
            tissue_mm=self.tissue_mm,
            bone_mm=self.bone_mm if self.bone == "elastic" else 0.0,
            h_contact_mm=h,
            fine_depth_mm=min(self.depth_mm + max(0.25, 2 * h), self.tissue_mm),
            h_max_mm=max(h, min(1.0, self.tissue_mm / 2)),
            order=2 if self.element == "p2" else 1,
        )

    def block_spec(self) -> BlockSpec:
        """The fields of this (resolved) configuration the prepared block depends on."""
        return BlockSpec(mesh=self.mesh_spec(), young_mpa=self.young_mpa, poisson=self.poisson,
                         bone_young_mpa=self.bone_young_mpa, bone_poisson=self.bone_poisson,
                         depth_mm=self.depth_mm, window_mm=self.window_mm, grid_mm=self.grid_mm)

    def as_dict(self) -> dict:
        """The fields as a dict, leaving out what does not apply (so records of configurations that existed
        before those fields read as they did: datasets, caches, model metadata): ``tolerance`` unless the
        fidelity is ``converged``, the one whose results depend on it; the curved-base fields
        (``CURVED_FIELDS``) for a flat base."""
        out = asdict(self)
        if self.fidelity != "converged":
            del out["tolerance"]
        if self.curvature_mm is None:
            for name in CURVED_FIELDS:
                del out[name]
        return out

    def identity(self) -> str:
        """What FEM results with this configuration depend on, as the result cache and provenance records name
        it: ``fem-`` and a digest of ``as_dict()`` (the spectral engine's: ``spectral.engine.identity``)."""
        from roughness.core.hashing import digest

        return "fem-" + digest(self.as_dict())

