"""The flat state: the strain of the untextured skin block at the footprint's centre, from the FEM.

The infinite layer under the mean pressure is in uniaxial compression (e_zz = -p / M, no lateral
strain), but the FEM's 10 mm block has free sides: at its centre the flat skin is compressed about
twice as much and spreads sideways (e_xx = e_yy ~ +0.21, e_zz ~ -1.2 at 10 N, stick). lambda3 is
nonlinear in the strain, so the texture's fluctuation depends on that state; with the block's
centre state the spectral V sits within -0.5% to -2% of `fine` FEM on the standard scale, with the
layer's own state -4% to +1% (studies/spectral_flat_state.md). The tensor is the FEM's strain at the
receptor depth averaged over the central 1 mm x 1 mm, at `fine`; standard configurations ship in
``models/spectral_flat_state.json`` (regenerate: ``python -m roughness.simulate.spectral.flat_state``),
others are computed once per process (seconds).
"""
from __future__ import annotations

import json
from dataclasses import replace
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


def computed(config: SimConfig) -> np.ndarray:
    """The FEM's flat-state strain (3, 3) at the block centre for ``config`` (seconds: one FEM solve)."""
    from ..curved import FLAT, base_surface
    from ..contact import solve_contact
    from ..model import Simulator

    simulator = Simulator(replace(config, fidelity=FIDELITY, h_contact_mm=None))
    block = simulator.block(simulator.config.resolved(None))
    solved = solve_contact(block.problem, base_surface(FLAT, config.width_mm), config.force_n,
                           config.contact == "frictionless", max_rounds=config.max_rounds)
    strain = block.sampler.strain(solved.u)
    axis = block.sampler.axis
    central = np.abs(axis) <= CENTRE_MM / 2
    tensor = strain[np.ix_(central, central)].mean(axis=(0, 1))
    return (tensor + tensor.T) / 2


@lru_cache(maxsize=1)
def _table() -> dict[str, list[list[float]]]:
    return json.loads(TABLE.read_text()) if TABLE.is_file() else {}


@lru_cache(maxsize=32)
def _cached(key: str) -> np.ndarray:
    stored = _table().get(key)
    return np.array(stored) if stored is not None else computed(SimConfig(**json.loads(key)))


def block_flat_state(config: SimConfig) -> np.ndarray:
    """The flat state (3, 3) for ``config``: from the shipped table, else computed once per process."""
    return _cached(key_of(config)).copy()


def write_table(path: Path = TABLE) -> dict[str, list[list[float]]]:
    """Compute the standard configurations' flat states (stick and frictionless, 5 to 20 N) and write the table."""
    table = {}
    for contact in ("stick", "frictionless"):
        for force in (5.0, 10.0, 20.0):
            config = SimConfig(contact=contact, force_n=force)
            table[key_of(config)] = np.round(computed(config), 6).tolist()
    path.write_text(json.dumps(table, indent=1, sort_keys=True) + "\n")
    return table


if __name__ == "__main__":
    for key, tensor in write_table().items():
        print(key, np.diag(tensor))
