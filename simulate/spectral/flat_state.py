"""The flat state: the strain and contact pressure of the untextured skin block at its centre, from the FEM.

The infinite layer under the mean pressure is in uniaxial compression (e_zz = -p / M, no lateral
strain), but the FEM's 10 mm block has free sides: at its centre the flat skin is compressed about
twice as much and spreads sideways (e_xx = e_yy ~ +0.21, e_zz ~ -1.2 at 10 N, stick). lambda3 is
nonlinear in the strain, so the texture's fluctuation depends on that state; with the block's
centre state the spectral V sits within -0.5% to -2% of `fine` FEM on the standard scale, with the
layer's own state -4% to +1% (studies/results/spectral_validation.md). The free sides also gather the
load toward the middle: the flat block's contact pressure over its central 1 mm^2 is 0.128 MPa at 10 N,
1.28 times the footprint's mean, and pressing the layer at that pressure brings partial contact close
to the FEM's (contact fraction median -0.5 points instead of -3.0 on the validation set).

The tensor is the FEM's strain at the receptor depth, and the pressure its contact pressure, averaged
over the central 1 mm x 1 mm, at `fine`; standard configurations ship in
``models/spectral_flat_state.json`` (regenerate: ``python -m roughness.simulate.spectral.flat_state``),
others are computed once per process (seconds).
"""
from __future__ import annotations

import json
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from roughness.core.hashing import canonical_json
from roughness.models import MODELS_DIR

from ..config import SimConfig

TABLE = MODELS_DIR / "spectral_flat_state.json"
FIDELITY = "fine"
CENTRE_MM = 1.0  # side of the central square the tensor is averaged over
FIELDS = ("young_mpa", "poisson", "tissue_mm", "width_mm", "bone", "bone_young_mpa", "bone_poisson", "bone_mm",
          "force_n", "contact", "depth_mm")


def key_of(config: SimConfig) -> str:
    """The table key: the configuration fields the flat state depends on, as canonical JSON."""
    return canonical_json({name: getattr(config, name) for name in FIELDS})


@dataclass(frozen=True)
class FlatState:
    """The untextured skin at the block's centre: strain at the receptor depth (3, 3) and contact pressure (MPa)."""

    strain: np.ndarray
    pressure_mpa: float


def computed(config: SimConfig) -> FlatState:
    """The FEM's flat state at the block centre for ``config`` (seconds: one FEM solve)."""
    from ..contact import solve_contact
    from ..curved import FLAT, base_surface
    from ..model import Simulator

    simulator = Simulator(replace(config, fidelity=FIDELITY, h_contact_mm=None))
    block = simulator.block(simulator.config.resolved(None))
    solved = solve_contact(block.problem, base_surface(FLAT, config.width_mm), config.force_n,
                           config.contact == "frictionless", max_rounds=config.max_rounds)
    strain = block.sampler.strain(solved.u)
    central = np.abs(block.sampler.axis) <= CENTRE_MM / 2
    tensor = strain[np.ix_(central, central)].mean(axis=(0, 1))
    face = block.problem.face
    middle = (np.abs(block.problem.bottom_xy) <= CENTRE_MM / 2).all(axis=1)
    pressure = face.pressure(solved.normal_reaction)[middle] @ face.area[middle] / face.area[middle].sum()
    return FlatState((tensor + tensor.T) / 2, float(pressure))


@lru_cache(maxsize=1)
def _table() -> dict[str, dict]:
    return json.loads(TABLE.read_text()) if TABLE.is_file() else {}


@lru_cache(maxsize=32)
def _cached(key: str) -> FlatState:
    stored = _table().get(key)
    if stored is None:
        return computed(SimConfig(**json.loads(key)))
    return FlatState(np.array(stored["strain"]), float(stored["pressure_mpa"]))


def block_flat_state(config: SimConfig) -> FlatState:
    """The flat state for ``config``: from the shipped table, else computed once per process."""
    return _cached(key_of(config))


def write_table(path: Path = TABLE) -> dict[str, dict]:
    """Compute the standard configurations' flat states (stick and frictionless, 5 to 20 N) and write the table."""
    table = {}
    for contact in ("stick", "frictionless"):
        for force in (5.0, 10.0, 20.0):
            config = SimConfig(contact=contact, force_n=force)
            state = computed(config)
            table[key_of(config)] = {"strain": np.round(state.strain, 6).tolist(),
                                     "pressure_mpa": round(state.pressure_mpa, 6)}
    path.write_text(json.dumps(table, indent=1, sort_keys=True) + "\n")
    return table


if __name__ == "__main__":
    for key, entry in write_table().items():
        print(key, np.diag(entry["strain"]), entry["pressure_mpa"])
