"""Shared fixtures: one BLAS thread, a private mesh cache, small block configurations."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import tomllib

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np  # noqa: E402
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


@pytest.fixture(scope="session", autouse=True)
def no_default_printer(tmp_path_factory):
    """The suite judges what each test asks for: no project default printer from the user's environment or
    config (ROUGHNESS_PRINTER, $XDG_CONFIG_HOME/roughness/config.toml); tests that need one set it themselves."""
    os.environ.pop("ROUGHNESS_PRINTER", None)
    os.environ["XDG_CONFIG_HOME"] = str(tmp_path_factory.mktemp("config-home"))
    yield


ROOT = Path(__file__).resolve().parents[1]


def source_packages() -> dict[str, Path]:
    """Every package of the source tree by its import name (``roughness.simulate.spectral``), with its folder: the
    folders pyproject.toml maps to import names ([tool.setuptools.package-dir]) and the packages inside them."""
    with open(ROOT / "pyproject.toml", "rb") as f:
        mapping = tomllib.load(f)["tool"]["setuptools"]["package-dir"]
    return {".".join((name, *init.parent.relative_to(ROOT / folder).parts)): init.parent
            for name, folder in mapping.items() for init in (ROOT / folder).rglob("__init__.py")}


def package_view(dest: Path) -> Path:
    """``dest`` holding the package as an install lays it out (roughness/, roughness/simulate/, ...), made of symlinks
    to the checkout's folders: for tools that read source trees rather than import (mypy cannot follow an editable
    install's import hook)."""
    with open(ROOT / "pyproject.toml", "rb") as f:
        mapping = tomllib.load(f)["tool"]["setuptools"]["package-dir"]
    for name, folder in sorted(mapping.items()):  # "roughness" first: the others go inside it
        target = dest.joinpath(*name.split("."))
        if name == "roughness":
            target.mkdir(parents=True)
            for child in (ROOT / folder).iterdir():
                (target / child.name).symlink_to(child)
        else:
            target.symlink_to(ROOT / folder)
    return dest


def source_modules() -> dict[str, Path]:
    """Every module of the package by its import name (a package's ``__init__.py`` by the package's name)."""
    return {(package if path.stem == "__init__" else f"{package}.{path.stem}"): path
            for package, folder in source_packages().items() for path in folder.glob("*.py")}


@pytest.fixture()
def workdir(tmp_path, monkeypatch):
    """A case folder with valid inputs, the cwd of the case; heavy work replaced by a tripwire."""
    rng = np.random.default_rng(0)
    np.save(tmp_path / "map.npy", rng.random((240, 240)) * 0.5)
    (tmp_path / "maps").mkdir()
    np.save(tmp_path / "maps" / "a.npy", rng.random((240, 240)) * 0.5)
    (tmp_path / "data.h5").write_bytes(b"placeholder")
    (tmp_path / "checkpoint.pt").write_bytes(b"placeholder")
    (tmp_path / "trials.csv").write_text("subject,reference,left,right,answer\ns1,a,b,c,left\ns1,b,a,c,left\n")
    (tmp_path / "stimuli.csv").write_text("stimulus,texture\na,standard-1.0\nb,standard-1.25\nc,flattop-0.3\n")
    (tmp_path / "embedding.csv").write_text("stimulus,coordinate,low,high\na,-1,-1.2,-0.8\nb,0.1,0,0.2\nc,0.9,0.8,1\n")
    (tmp_path / "truth.csv").write_text("stimulus,roughness\na,0.05\nb,0.08\nc,0.1\n")
    from PIL import Image

    Image.fromarray(np.repeat(np.uint8([[0, 128, 255]]), 30, axis=0).repeat(3, axis=1)[..., None].repeat(3, axis=2)
                    ).save(tmp_path / "picture.png")  # three flat colours
    import trimesh

    trimesh.creation.box((10, 10, 10)).export(tmp_path / "mesh.stl")
    monkeypatch.chdir(tmp_path)
    _tripwires(monkeypatch)
    return tmp_path


def _tripwires(monkeypatch) -> None:
    def tripped(*args, **kwargs):
        raise AssertionError("bad input reached a heavy computation")

    # the modules themselves, not attribute chains from the package (which once failed after the studio's tests:
    # studio_helpers.package_kept)
    from roughness.dataset import build
    from roughness.design import hidden_shapes
    from roughness.objects import texturing
    from roughness.simulate.model import Simulator

    monkeypatch.setattr(Simulator, "run", tripped)
    monkeypatch.setattr(build, "build", tripped)
    monkeypatch.setattr(texturing, "texture_mesh", tripped)
    monkeypatch.setattr(hidden_shapes, "hidden_plate", tripped)


def _source_copy(dest: Path) -> Path:
    """The project's files as a fresh clone would have them (no build or cache folders)."""
    ignore = shutil.ignore_patterns(".git", "build", "*.egg-info", "__pycache__", ".pytest_cache", "venv", "*.h5",
                                    "_build", "repo")  # the manual's build and its generated mirror (docs/)
    shutil.copytree(ROOT, dest, ignore=ignore)
    return dest


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """A fresh virtual environment with the wheel installed (dependencies from the running environment)."""
    root = tmp_path_factory.mktemp("wheel")
    source = _source_copy(root / "src")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-build-isolation",
                    "--no-index", "--wheel-dir", str(root / "dist"), str(source)], check=True, cwd=root)
    [wheel] = (root / "dist").glob("roughness-*.whl")
    venv = root / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    python = venv / "bin" / "python"
    # --ignore-installed: the running environment may already hold roughness (CI installs it there), and the
    # venv sees it through --system-site-packages; without the flag pip would call the wheel satisfied and skip it
    subprocess.run([str(python), "-m", "pip", "install", "--quiet", "--no-deps", "--no-index", "--ignore-installed",
                    str(wheel)], check=True, cwd=root)
    return python


@pytest.fixture
def anyio_backend() -> str:
    """Async tests run on asyncio, the loop NiceGUI serves on (anyio would also run them on trio where that is
    installed, as in CI's interpreter, and NiceGUI's client cannot run there)."""
    return "asyncio"


@pytest.fixture
async def studio():
    """The Roughness Studio (local, no token) under NiceGUI's browser-less test client, fresh for each test
    (tests/studio_helpers.py; async tests: ``pytestmark = pytest.mark.anyio``)."""
    from studio_helpers import running_studio

    async with running_studio() as running:
        yield running
