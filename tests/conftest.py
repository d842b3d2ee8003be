"""Shared fixtures: one BLAS thread, a private mesh cache, small block configurations."""
from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import pytest  # noqa: E402


@pytest.fixture(scope="session", autouse=True)
def mesh_cache(tmp_path_factory):
    """Meshes are cached per test session, never in the user's home."""
    path = tmp_path_factory.mktemp("mesh-cache")
    os.environ["ROUGHNESS_CACHE"] = str(path)
    yield path
