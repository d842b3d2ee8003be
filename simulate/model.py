"""The FEM roughness model: a prepared skin block and the texture -> V pipeline."""
from __future__ import annotations

import math
import time
from collections import OrderedDict
from dataclasses import dataclass, field, replace

import numpy as np

from roughness.core.errors import SimulationError

from . import mesh as meshing
from .config import SimConfig
from .contact import ContactError, ContactProblem, ContactState, solve_contact
from .elasticity import rigid_body_modes, stiffness
from .face import ContactFace
from .heightmap import Heightmap
from .linsolve import ConstrainedSystem, SolverError
from .strain import StrainSampler
from .variation import PairSampling, variation


@dataclass
class Result:
    """Roughness of one texture and how it was obtained (mm, N, s)."""

    roughness: float
    roughness_stderr: float
    contact_fraction: float
    indentation_mm: float
    converged: bool
    iterations: int
    unresolved_nodes: int
    cycled: bool
    nodes: int
    dofs: int
    seconds: float
    stage_seconds: dict[str, float]
    fluctuation: np.ndarray
    lambda3: np.ndarray
    grid_axis_mm: np.ndarray
    contact_history: list[int]
    warnings: list[str]
    config: SimConfig
    state: ContactState | None = field(default=None, repr=False)

    def summary(self) -> dict:
        """JSON-ready scalars."""
        keys = ("roughness", "roughness_stderr", "contact_fraction", "indentation_mm", "converged",
                "iterations", "unresolved_nodes", "cycled", "nodes", "dofs", "seconds")
        out = {k: getattr(self, k) for k in keys}
        out.update(stage_seconds={k: round(v, 4) for k, v in self.stage_seconds.items()},
                   contact_history=self.contact_history, warnings=self.warnings,
                   fidelity=self.config.fidelity, h_contact_mm=self.config.h_contact_mm,
                   force_n=self.config.force_n, poisson=self.config.poisson, contact=self.config.contact,
                   element=self.config.element, bone=self.config.bone)
        return out


class Block:
    """Texture-independent parts of one configuration, built once and reused.

    Mesh (cached on disk), stiffness, AMG-preconditioned constrained system, strain
    sampler, disk-pair sampling and the untextured (flat) base field per force.
    """

    def __init__(self, config: SimConfig, cache: bool = True) -> None:
        self.config = config
        self.seconds: dict[str, float] = {}
        t = time.perf_counter()
        self.mesh = meshing.build(config.mesh_spec(), cache=cache)
        self.seconds["mesh"] = time.perf_counter() - t
        t = time.perf_counter()
        bone = self.mesh.region == meshing.BONE
        young = np.where(bone, config.bone_young_mpa, config.young_mpa)
        poisson = np.where(bone, config.bone_poisson, config.poisson)
        k = stiffness(self.mesh, young, poisson)
        self.seconds["assembly"] = time.perf_counter() - t
        bottom = self.mesh.bottom
        self.problem = ContactProblem(
            system=ConstrainedSystem(k, rigid_body_modes(self.mesh.points)),
            bottom=bottom,
            bottom_xy=self.mesh.points[bottom, :2],
            top=self.mesh.top,
            n_dofs=3 * len(self.mesh.points),
            face=ContactFace(self.mesh, bottom),
        )
        self.area = self.problem.face.area
        t = time.perf_counter()
        self.sampler = StrainSampler(self.mesh, config.depth_mm, config.window_mm, config.grid_mm)
        self.seconds["sampler"] = time.perf_counter() - t
        self._base: dict[tuple[float, str], tuple[np.ndarray, float, tuple]] = {}
        self.runs = 0

    def base(self, force_n: float, contact: str) -> tuple[np.ndarray, float, tuple]:
        """lambda3 of the untextured block, its indentation and warm-start solutions."""
        key = (force_n, contact)
        if key not in self._base:
            state, warm = solve_contact(self.problem, _flat, force_n, contact == "frictionless",
                                        max_rounds=self.config.max_rounds)
            self._base[key] = (self.sampler.max_compression(state.u), state.indentation_mm, warm)
        return self._base[key]


def _flat(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.zeros_like(x)


def texture_surface(heightmap: Heightmap, centre_mm: tuple[float, float], z0: float, periodic: bool):
    """Texture height (mm) relative to the undeformed skin face, in block coordinates."""
    cx, cy = centre_mm

    def surface(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return heightmap.sample(cx + x, cy + y, periodic=periodic) - z0

    return surface


class Simulator:
    """Runs the FEM model for many textures, preparing each configuration once."""

    def __init__(self, config: SimConfig | None = None, cache: bool = True, max_blocks: int = 4) -> None:
        self.config = config or SimConfig()
        self.cache = cache
        self.max_blocks = max_blocks
        self._blocks: OrderedDict[tuple, Block] = OrderedDict()

    def block(self, config: SimConfig) -> Block:
        """The prepared block for a resolved configuration (what the mesh and matrices depend on)."""
        key = (config.mesh_spec(), config.young_mpa, config.poisson, config.bone_young_mpa,
               config.bone_poisson, config.depth_mm, config.window_mm, config.grid_mm)
        if key not in self._blocks:
            self._blocks[key] = Block(config, cache=self.cache)
            while len(self._blocks) > self.max_blocks:
                self._blocks.popitem(last=False)
        self._blocks.move_to_end(key)
        return self._blocks[key]

    def run(self, heightmap: Heightmap, centre_mm: tuple[float, float] | None = None,
            tile: bool = False, **overrides) -> Result:
        """Roughness V of ``heightmap`` under the skin footprint centred at ``centre_mm``."""
        t_start = time.perf_counter()
        config = replace(self.config, **overrides).resolved(heightmap)
        centre = centre_mm or heightmap.centre_mm
        heightmap.require_footprint(config.width_mm, centre, tile)
        block = self.block(config)
        stages = dict(block.seconds) if block.runs == 0 else {}
        block.runs += 1
        t = time.perf_counter()
        base, flat_indentation, warm = block.base(config.force_n, config.contact)
        stages["base_field"] = time.perf_counter() - t
        z0 = heightmap.max_in_footprint(config.width_mm, centre, periodic=tile)
        surface = texture_surface(heightmap, centre, z0, tile)
        # Initial contact set: what the flat block's indentation at this force would touch.
        initial = surface(*block.problem.bottom_xy.T) >= -flat_indentation
        t = time.perf_counter()
        setups = block.problem.system.stats.setups
        try:
            state, _ = solve_contact(block.problem, surface, config.force_n, config.contact == "frictionless",
                                     max_rounds=config.max_rounds, initial=initial, warm=warm)
        except (ContactError, SolverError) as err:
            raise SimulationError(str(err)) from err
        stages["contact"] = time.perf_counter() - t
        t = time.perf_counter()
        lam3 = block.sampler.max_compression(state.u)
        stages["strain"] = time.perf_counter() - t
        t = time.perf_counter()
        fluct = lam3 - base
        pairs = PairSampling(config.window_mm, config.pair_distance_mm, config.disk_radius_mm,
                             config.pairs, config.seed)
        v, se = variation(fluct, block.sampler.axis, pairs)
        stages["variation"] = time.perf_counter() - t
        if not (np.all(np.isfinite(fluct)) and math.isfinite(v)):
            raise SimulationError("the strain field is not finite")
        contact_fraction = float(block.area[state.in_contact].sum() / block.area.sum())
        return Result(
            roughness=v,
            roughness_stderr=se,
            contact_fraction=contact_fraction,
            indentation_mm=state.indentation_mm,
            converged=state.converged,
            iterations=state.rounds,
            unresolved_nodes=state.unresolved,
            cycled=state.cycled,
            nodes=len(block.mesh.points),
            dofs=3 * len(block.mesh.points),
            seconds=time.perf_counter() - t_start,
            stage_seconds={**stages, "amg_setups": block.problem.system.stats.setups - setups},
            fluctuation=fluct,
            lambda3=lam3,
            grid_axis_mm=block.sampler.axis,
            contact_history=state.contact_history,
            warnings=_regime_warnings(config, state),
            config=config,
            state=state,
        )


def _regime_warnings(config: SimConfig, state: ContactState) -> list[str]:
    out = []
    if state.indentation_mm > config.tissue_mm:
        out.append(f"indentation {state.indentation_mm:.2f} mm exceeds the {config.tissue_mm} mm tissue: "
                   "linear small-strain elasticity far past its range (as in the paper's model)")
    if not state.converged:
        out.append(f"contact did not settle in {state.rounds} rounds: {state.unresolved} nodes still violate "
                   f"(max penetration {state.max_penetration_mm:.2e} mm, max tension {state.max_tension_mpa:.2e} MPa)")
    if state.cycled:
        out.append("the contact set revisited an earlier state (cycling) before settling")
    return out


_DEFAULT = Simulator()


def roughness(heightmap: Heightmap, centre_mm: tuple[float, float] | None = None, tile: bool = False,
              simulator: Simulator | None = None, **config) -> Result:
    """FEM roughness of a heightmap; keyword arguments override ``SimConfig`` fields."""
    return (simulator or _DEFAULT).run(heightmap, centre_mm, tile, **config)
