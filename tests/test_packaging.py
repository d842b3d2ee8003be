"""One import name: the wheel installs ``roughness`` only, and the Python examples of the README and the manual run."""
from __future__ import annotations

import os
import re
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from conftest import _source_copy, source_modules, source_packages

ROOT = Path(__file__).resolve().parents[1]
GENERIC_NAMES = ("simulate", "dataset", "surrogate", "models")
PUBLIC_API = ("Heightmap", "InputError", "SimulationError", "load_heightmap", "save_heightmap", "SimConfig",
              "Simulator", "Result", "fem_roughness", "predict", "Prediction", "StandardScale", "load_scale",
              "standard_texture", "named_texture", "open_dataset", "as_heightmap", "tune", "palette", "tactile_image",
              "homogeneity", "embed_trials", "fit_embedding", "predict_map", "MapPrediction", "PredictOptions",
              "CurvedBase")


def _purelib(python: Path) -> Path:
    out = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                         check=True, capture_output=True, text=True)
    return Path(out.stdout.strip())


def test_wheel_installs_one_top_level_name(installed):
    site = _purelib(installed)
    assert site != Path(sysconfig.get_paths()["purelib"])
    names = {p.name for p in site.iterdir() if not p.name.endswith((".dist-info", ".pth"))}
    assert "roughness" in names
    assert not names & set(GENERIC_NAMES), names
    package = site / "roughness"
    for sub in GENERIC_NAMES:
        assert (package / sub / "__init__.py").is_file(), sub
    assert (package / "models" / "roughness-cnn.onnx").is_file()
    assert (package / "models" / "standard_scale.json").is_file()
    top_level = next(site.glob("roughness-*.dist-info"))
    record = (top_level / "RECORD").read_text().splitlines()
    assert all(line.startswith(("roughness/", "roughness-", "../../../bin/")) for line in record), record[:5]


def test_wheel_holds_every_package_of_the_source_tree(installed):
    site = _purelib(installed)
    missing = [name for name in source_packages() if not (site / name.replace(".", "/") / "__init__.py").is_file()]
    assert not missing, f"packages not in the wheel (pyproject.toml [tool.setuptools] packages): {missing}"


def test_installed_public_api_runs_outside_the_checkout(installed, tmp_path):
    # -S: no .pth files, so an editable install of the checkout elsewhere cannot fill in what the wheel lacks
    code = f"""
import sys
sys.path[:0] = [{str(_purelib(installed))!r}, {sysconfig.get_paths()["purelib"]!r}]
import roughness
assert sorted(roughness.__all__) == sorted({list(PUBLIC_API)!r} + ["__version__"])
for name in roughness.__all__:
    getattr(roughness, name)
assert roughness.__file__.startswith({str(_purelib(installed))!r}), roughness.__file__
hm = roughness.load_heightmap({str(ROOT / "examples" / "standard-1.0mm.png")!r}, pixel_mm=0.05, height_mm=1.0)
[p] = roughness.predict(hm, engine="surrogate")
assert 0.03 < p.roughness < 0.3, p.roughness
import importlib.util
for name in {list(GENERIC_NAMES)!r}:
    assert importlib.util.find_spec(name) is None or "roughness" not in str(importlib.util.find_spec(name).origin)
print("ok", p.roughness)
"""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    out = subprocess.run([str(installed), "-S", "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("ok")


def test_the_suite_runs_the_checkouts_code():
    """Installed regularly or editable, the package the tests import is this checkout's code, module for module
    (a stale install fails here, not somewhere deep in the suite)."""
    import importlib.util

    stale = [name for name, path in source_modules().items()
             if Path(importlib.util.find_spec(name).origin).read_bytes() != path.read_bytes()]
    assert not stale, f"installed modules differ from the checkout (reinstall: pip install .): {stale}"


IMPORT_EVERY_MODULE = """
import importlib, importlib.util, sys
import roughness
for name in sys.argv[1:]:
    importlib.import_module(name)
assert (roughness.models.MODELS_DIR / "roughness-cnn.onnx").is_file()
assert importlib.util.find_spec("roughness.roughness") is None
print(roughness.simulate.__file__)
"""
FIND_EVERY_MODULE = """
import importlib.resources, importlib.util, sys
for name in sys.argv[1:]:
    print(importlib.util.find_spec(name).origin)
assert (importlib.resources.files("roughness.models") / "roughness-cnn.onnx").is_file()
assert importlib.util.find_spec("roughness.roughness") is None
"""
NOT_IMPORTABLE_OUTSIDE = """
import importlib.util, sys
for name in ("simulate", "dataset", "surrogate", "models", "src"):
    spec = importlib.util.find_spec(name)
    assert spec is None or not str(spec.origin).startswith(sys.argv[1]), (name, spec.origin)
"""


def _imports_every_module(python: Path | str, cwd: Path) -> str:
    """Import every module of the source tree (``__main__`` modules left out: they run) with ``python`` run in
    ``cwd``; the file roughness.simulate came from."""
    names = sorted(name for name in source_modules() if not name.endswith(".__main__"))
    out = subprocess.run([str(python), "-c", IMPORT_EVERY_MODULE, *names], cwd=cwd, capture_output=True, text=True)
    assert out.returncode == 0, (cwd, out.stderr[-2000:])
    return out.stdout.strip()


def _nothing_of_the_checkout_importable_outside(python: Path | str, checkout: Path) -> None:
    out = subprocess.run([str(python), "-c", NOT_IMPORTABLE_OUTSIDE, str(checkout)], cwd="/", capture_output=True,
                         text=True)
    assert out.returncode == 0, out.stderr[-2000:]


def test_every_module_imports_from_the_root_and_from_elsewhere(tmp_path):
    """The running install (regular or editable) imports every module from the checkout's root and from another
    folder, finds the shipped models, and has no ``roughness.roughness``; outside the checkout, none of its folders
    is a package of its own."""
    assert _imports_every_module(sys.executable, ROOT) == _imports_every_module(sys.executable, tmp_path)
    _nothing_of_the_checkout_importable_outside(sys.executable, ROOT)


def test_an_editable_install_finds_every_module_in_the_checkout(tmp_path):
    """``pip install -e`` of a copy of the checkout maps the top-level folders to their import names too: every
    module is found at its file in the copy, from the copy's root and from elsewhere (the packages' ``__init__``
    files import nothing heavy, so this needs none of the dependencies, which the venv does not see)."""
    source = _source_copy(tmp_path / "checkout")
    venv = tmp_path / "venv"
    # the editable wheel is built by the running environment's setuptools (PEP 660: build_editable), as pip would with
    # build isolation; the venv's own pip only installs it (its bundled setuptools may predate editable wheels)
    build = ("import sys; from setuptools import build_meta; "
             "print(build_meta.build_editable(sys.argv[1]))")
    out = subprocess.run([sys.executable, "-c", build, str(tmp_path / "dist")], cwd=source, check=True,
                         capture_output=True, text=True)
    wheel = tmp_path / "dist" / out.stdout.strip().splitlines()[-1]
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = venv / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "--quiet", "--no-deps", "--no-index", "--ignore-installed",
                    str(wheel)], check=True, cwd=tmp_path)
    expected = {name: str(source / path.relative_to(ROOT)) for name, path in source_modules().items()}
    for cwd in (source, tmp_path):
        out = subprocess.run([str(python), "-c", FIND_EVERY_MODULE, *expected], cwd=cwd, capture_output=True,
                             text=True)
        assert out.returncode == 0, (cwd, out.stderr[-2000:])
        assert dict(zip(expected, out.stdout.split())) == expected
    _nothing_of_the_checkout_importable_outside(python, source)


def doc_python_blocks() -> dict[str, str]:
    """The ```python blocks of the README and of the manual's pages (docs/, not its generated repo/ and _build/),
    by ``FILE:N``: each runs as it stands from the repository root. Code shown but not run (it needs a cluster)
    is a ``{code-block} python`` instead."""
    pages = [ROOT / "README.md"] + sorted(p for p in (ROOT / "docs").rglob("*.md")
                                         if not {"repo", "_build"} & set(p.relative_to(ROOT / "docs").parts))
    return {f"{page.relative_to(ROOT)}:{n}": block for page in pages
            for n, block in enumerate(re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S), 1)}


def test_readme_and_manual_have_python_examples():
    blocks = doc_python_blocks()
    assert any(name.startswith("README.md:") for name in blocks) and len(blocks) >= 3
    assert all("import roughness" in b for b in blocks.values())


@pytest.mark.parametrize("name", list(doc_python_blocks()))
def test_readme_and_manual_python_example_runs(name):
    out = subprocess.run([sys.executable, "-c", doc_python_blocks()[name]], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
