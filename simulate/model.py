"""The FEM roughness model: a prepared skin block and the texture -> V pipeline."""
from __future__ import annotations

import math
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from roughness.core.checks import flag, function, integer
from roughness.core.errors import InputError, SimulationError
from roughness.surface.arguments import as_heightmap, heightmap_argument
from roughness.surface.heightmap import Heightmap

from . import mesh as meshing
from .config import DEEP_INDENTATION_TISSUES, MAX_INDENTATION_TISSUES, BlockSpec, SimConfig
from .contact import ContactError, ContactProblem, ContactResult, ContactRound, solve_contact
from .converged import InitialSet, estimated
from .curved import FLAT, BaseShape, base_surface, textured_surface
from .elasticity import rigid_body_modes, stiffness
from .face import ContactFace
from .linsolve import AMGCache, SolverError
from .result import Note, Result
from .strain import StrainSampler
from .variation import PairSampling, variation

MIN_FOOTPRINT_PIXELS = 10  # the skin footprint must span at least this many pixels across
LOCKING_POISSON = 0.49  # P1 elements lock above this Poisson ratio


@dataclass(frozen=True)
class BaseField:
    """The untextured base under the block at one load: lambda3 on the sampling grid, the indentation
    (mm), and what a texture's contact solve starts from: the warm-start solutions and AMG state."""

    lambda3: np.ndarray
    indentation_mm: float
    warm: tuple[np.ndarray, np.ndarray]
    amg: AMGCache


class Block:
    """Texture-independent parts of one configuration, built once and reused.

    Mesh (cached on disk), stiffness, the contact problem with its reusable AMG hierarchy,
    strain sampler and the untextured (flat) base field per load. Thread-safe: nothing a texture's
    solve uses is changed by it (each contact loop works on a fork of its base field's AMG state),
    and the base fields are made once, under a lock.
    """

    def __init__(self, spec: BlockSpec, cache: bool = True) -> None:
        self.spec = spec
        self.seconds: dict[str, float] = {}
        t = time.perf_counter()
        self.mesh = meshing.build(spec.mesh, cache=cache)
        self.seconds["mesh"] = time.perf_counter() - t
        t = time.perf_counter()
        bone = self.mesh.region == meshing.BONE
        young = np.where(bone, spec.bone_young_mpa, spec.young_mpa)
        poisson = np.where(bone, spec.bone_poisson, spec.poisson)
        k = stiffness(self.mesh, young, poisson).tocsr()
        self.seconds["assembly"] = time.perf_counter() - t
        bottom = self.mesh.bottom
        self.problem = ContactProblem(
            stiffness=k,
            amg=AMGCache(rigid_body_modes(self.mesh.points)),
            bottom=bottom,
            bottom_xy=self.mesh.points[bottom, :2],
            top=self.mesh.top,
            n_dofs=3 * len(self.mesh.points),
            face=ContactFace(self.mesh, bottom),
        )
        self.area = self.problem.face.area
        t = time.perf_counter()
        self.sampler = StrainSampler(self.mesh, spec.depth_mm, spec.window_mm, spec.grid_mm)
        self.seconds["sampler"] = time.perf_counter() - t
        self._base: dict[tuple[BaseShape, float, str, int], BaseField] = {}
        self._lock = threading.Lock()
        self.runs = 0

    def count_run(self) -> bool:
        """Count one texture's solve; True for the block's first (whose stages include the block's set-up)."""
        with self._lock:
            self.runs += 1
            return self.runs == 1

    def base(self, force_n: float, contact: str, max_rounds: int = SimConfig.max_rounds,
             shape: BaseShape = FLAT) -> BaseField:
        """The untextured base ``shape`` under the block at ``force_n``, solved once (from the pristine AMG state)."""
        key = (shape, force_n, contact, max_rounds)
        with self._lock:
            if key not in self._base:
                surface = base_surface(shape, self.spec.mesh.width_mm)
                # Start from the nodes within two tissue thicknesses of the base's top (not down a convex base's side).
                initial = None if shape.flat else surface(*self.problem.bottom_xy.T) > -2 * self.spec.mesh.tissue_mm
                amg = self.problem.amg.fork()
                solved = solve_contact(self.problem, surface, force_n, contact == "frictionless",
                                       max_rounds=max_rounds, initial=initial, amg=amg)
                self._base[key] = BaseField(self.sampler.max_compression(solved.u), solved.indentation_mm,
                                            solved.warm, amg)
            return self._base[key]


def texture_surface(heightmap: Heightmap, centre_mm: tuple[float, float], z0: float, periodic: bool):
    """Texture height (mm) relative to the undeformed skin face, in block coordinates."""
    cx, cy = centre_mm

    def surface(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return heightmap.sample(cx + x, cy + y, periodic=periodic) - z0

    return surface


class Simulator:
    """Runs the FEM model for many textures, preparing each configuration once.

    Thread-safe, and a texture's result does not depend on what was solved before or beside it:
    threads may share one simulator (and its prepared blocks) and get the sequential answers bit for bit.
    """

    def __init__(self, config: SimConfig | None = None, cache: bool = True, max_blocks: int = 4) -> None:
        if config is not None and not isinstance(config, SimConfig):
            raise InputError(f"config must be a SimConfig (or None for the defaults), got {type(config).__name__}",
                             parameter="config")
        self.config = config or SimConfig()
        self.cache = flag("cache", cache)
        self.max_blocks = integer("max_blocks", max_blocks, minimum=1)
        self._blocks: OrderedDict[BlockSpec, Block] = OrderedDict()
        self._lock = threading.Lock()

    def block(self, config: SimConfig) -> Block:
        """The prepared block for a resolved configuration, keyed by its ``block_spec()``."""
        key = config.block_spec()
        with self._lock:
            if key not in self._blocks:
                self._blocks[key] = Block(key, cache=self.cache)
                while len(self._blocks) > self.max_blocks:
                    self._blocks.popitem(last=False)
            self._blocks.move_to_end(key)
            return self._blocks[key]

    def face_xy(self, config: SimConfig) -> np.ndarray:
        """x, y (mm) of the contact-face nodes of a resolved configuration's block, (n, 2)."""
        return self.block(config).problem.bottom_xy

    def run(self, heightmap: Heightmap | np.ndarray, centre_mm: tuple[float, float] | None = None, tile: bool = False,
            callback: Callable[[ContactRound], None] | None = None, estimate_error: bool = True,
            pixel_mm: float | None = None, **overrides) -> Result:
        """Roughness V of ``heightmap`` under the skin footprint centred at ``centre_mm`` (mm).

        ``heightmap`` is a ``Heightmap`` or a 2-D array of heights (mm) with its pixel size ``pixel_mm`` (mm).
        ``overrides`` replace ``SimConfig`` fields; ``callback`` receives each contact round's statistics.
        With ``estimate_error`` (and always for fidelity ``converged``) a coarser level is solved too, for
        the discretization-error estimate (``simulate.converged``); without it, ``solve``: one level.
        """
        config = self.config.updated(**overrides)
        flag("estimate_error", estimate_error)
        function("callback", callback)
        heightmap = as_heightmap(heightmap, pixel_mm, "heightmap")
        heightmap.require_footprint(config.width_mm, centre_mm, flag("tile", tile))  # before any mesh is made
        if estimate_error or config.fidelity == "converged":
            return estimated(self, heightmap, centre_mm, tile, callback, **overrides)
        return self.solve(heightmap, centre_mm, tile, callback, **overrides)

    def solve(self, heightmap: Heightmap, centre_mm: tuple[float, float] | None = None, tile: bool = False,
              callback: Callable[[ContactRound], None] | None = None, initial: InitialSet | None = None,
              **overrides) -> Result:
        """V at one level (no discretization-error estimate); ``initial`` maps contact-face points
        (n, 2) in mm to the starting contact set (default: what the flat block's indentation touches)."""
        t_start = time.perf_counter()
        config = self.config.updated(**overrides).resolved(heightmap)
        centre = centre_mm or heightmap.centre_mm
        heightmap.require_footprint(config.width_mm, centre, tile)
        _require_resolved_footprint(heightmap, config)
        block = self.block(config)
        stages = dict(block.seconds) if block.count_run() else {}
        t = time.perf_counter()
        shape = config.base_shape()
        base = block.base(config.force_n, config.contact, config.max_rounds, shape)
        stages["base_field"] = time.perf_counter() - t
        if shape.flat:
            z0 = heightmap.max_in_footprint(config.width_mm, centre, periodic=tile)
            surface = texture_surface(heightmap, centre, z0, tile)
        else:
            surface, _ = textured_surface(heightmap, centre, shape, config.texture_along, config.width_mm, tile)
        # Initial contact set: given, or what the untextured base's indentation at this force would touch.
        initial = (initial(block.problem.bottom_xy) if initial is not None
                   else surface(*block.problem.bottom_xy.T) >= -base.indentation_mm)
        t = time.perf_counter()
        try:
            state = solve_contact(block.problem, surface, config.force_n, config.contact == "frictionless",
                                  max_rounds=config.max_rounds, initial=initial, warm=base.warm, callback=callback,
                                  amg=base.amg.fork())
        except (ContactError, SolverError) as err:
            raise SimulationError(str(err)) from err
        stages["contact"] = time.perf_counter() - t
        _require_small_strain_regime(config, state, shape, base.indentation_mm)
        t = time.perf_counter()
        lam3 = block.sampler.max_compression(state.u)
        stages["strain"] = time.perf_counter() - t
        t = time.perf_counter()
        fluct = lam3 - base.lambda3
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
            converged=state.success,
            iterations=state.rounds,
            unresolved_nodes=state.unresolved,
            cycled=state.cycled,
            cg_iterations=state.cg_iterations,
            amg_setups=state.amg_setups,
            nodes=len(block.mesh.points),
            dofs=3 * len(block.mesh.points),
            seconds=time.perf_counter() - t_start,
            stage_seconds=stages,
            fluctuation=fluct,
            lambda3=lam3,
            grid_axis_mm=block.sampler.axis,
            contact_history=state.contact_history,
            notes=_notes(config, state, heightmap),
            config=config,
            state=state,
            contact_check=state.check,
        )


def _require_resolved_footprint(heightmap: Heightmap, config: SimConfig) -> None:
    """InputError if the skin footprint spans fewer than MIN_FOOTPRINT_PIXELS pixels."""
    across = config.width_mm / heightmap.pixel_mm
    if across < MIN_FOOTPRINT_PIXELS:
        raise InputError(f"the {config.width_mm:g} mm skin footprint spans only {across:.3g} pixels of "
                         f"{heightmap.pixel_mm:g} mm (at least {MIN_FOOTPRINT_PIXELS} needed): the texture is not "
                         "resolved at the fingertip's scale; is the pixel size in mm?", parameter="pixel_mm")


def _require_small_strain_regime(config: SimConfig, state: ContactResult, shape: BaseShape,
                                 base_indentation_mm: float) -> None:
    """InputError if the skin was pushed beyond MAX_INDENTATION_TISSUES tissue thicknesses; it names the
    curved base when the base without its texture already pushes it that far, else the force."""
    ratio = state.indentation_mm / config.tissue_mm
    base_ratio = base_indentation_mm / config.tissue_mm
    if not shape.flat and base_ratio > MAX_INDENTATION_TISSUES:
        raise InputError(
            f"on the {shape.describe()} the skin would be pushed {base_indentation_mm:.4g} mm, {base_ratio:.3g} times "
            f"its {config.tissue_mm:g} mm thickness (limit {MAX_INDENTATION_TISSUES:g}), before any texture: the "
            f"base is too sharp for {config.force_n:g} N; use a larger radius (or a force below about "
            f"{config.force_n * MAX_INDENTATION_TISSUES / base_ratio:.2g} N)", parameter="curvature_mm")
    if ratio > MAX_INDENTATION_TISSUES:
        below = config.force_n * MAX_INDENTATION_TISSUES / ratio
        raise InputError(
            f"the skin would be pushed {state.indentation_mm:.4g} mm into the texture, {ratio:.3g} times its "
            f"{config.tissue_mm:g} mm thickness (limit {MAX_INDENTATION_TISSUES:g}): linear elasticity cannot "
            f"answer this; a force of {config.force_n:g} N is far too large for this texture (stay below about "
            f"{below:.2g} N), or its heights are not in mm", parameter="force_n")


def _notes(config: SimConfig, state: ContactResult, heightmap: Heightmap) -> list[Note]:
    out = []
    ratio = state.indentation_mm / config.tissue_mm
    if ratio > 1:
        out.append(Note("indentation", f"indentation {state.indentation_mm:.2f} mm exceeds the {config.tissue_mm} mm "
                        "tissue: linear small-strain elasticity past its range (as in the paper's model)",
                        unusual=ratio > DEEP_INDENTATION_TISSUES))
    if not state.success:
        out.append(Note("not_converged", f"{state.message}; {state.unresolved} nodes still violate contact",
                        unusual=True))
    if state.cycled:
        out.append(Note("cycled", "the contact set revisited an earlier state (cycling); damped steps followed",
                        unusual=not state.success))
    if config.element == "p1" and config.poisson > LOCKING_POISSON:
        out.append(Note("locking", f"P1 elements lock at Poisson ratio {config.poisson} > {LOCKING_POISSON}: strain "
                        "is underestimated; use element p2", unusual=True))
    feature = heightmap.feature_size_mm()
    if feature < config.h_contact_mm:
        out.append(Note("unresolved_texture", f"texture features (~{feature:.2g} mm) are finer than the contact mesh "
                        f"({config.h_contact_mm} mm): they are under-resolved; use a finer fidelity", unusual=True))
    return out


SHARED = Simulator()  # the process's FEM simulator: every configuration runs on it (simulate.prepared)


def roughness(heightmap: Heightmap | np.ndarray, centre_mm: tuple[float, float] | None = None, tile: bool = False,
              simulator: Simulator | None = None, pixel_mm: float | None = None, units_ok: bool = False,
              **config) -> Result:
    """FEM roughness of a heightmap (or a 2-D array of heights in mm with its ``pixel_mm``, mm); keyword arguments
    override ``SimConfig`` fields. Numbers that look like metres or micrometres are refused (``units_ok=True``:
    they are mm), and every argument is checked before a mesh is made."""
    if simulator is not None and not isinstance(simulator, Simulator):
        raise InputError(f"simulator must be a roughness.Simulator (or None for the shared one), got "
                         f"{type(simulator).__name__}", parameter="simulator")
    heightmap = heightmap_argument(heightmap, pixel_mm, "heightmap", units_ok)
    return (simulator or SHARED).run(heightmap, centre_mm, tile, **config)
