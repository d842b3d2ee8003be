"""Shared fixtures: one BLAS thread, a private mesh cache, small block configurations."""
from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import pytest  # noqa: E402

from roughness.simulate.mesh import MeshSpec, build  # noqa: E402

# A small block (4 x 4 x 2 mm, h 0.4 mm): exact-property and fast-path tests of the FEM core.
SMALL_MESH = MeshSpec(width_mm=4.0, tissue_mm=2.0, h_contact_mm=0.4, fine_depth_mm=1.0, h_max_mm=0.8)


@pytest.fixture(scope="module", params=[1, 2], ids=["P1", "P2"])
def mesh(request):
    """The small block with P1 and with P2 elements."""
    return build(MeshSpec(**{**SMALL_MESH.__dict__, "order": request.param}))


@pytest.fixture(scope="session", autouse=True)
def mesh_cache(tmp_path_factory):
    """Meshes are cached per test session, never in the user's home."""
    path = tmp_path_factory.mktemp("mesh-cache")
    os.environ["ROUGHNESS_CACHE"] = str(path)
    yield path
