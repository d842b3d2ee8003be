"""One import name: the wheel installs ``roughness`` only, and the Python examples of the README and the manual run."""
from __future__ import annotations

import os
import re
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

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


def _source_packages() -> set[str]:
    """Every package of the source tree, by its installed name (roughness/x/y -> roughness.x.y)."""
    return {".".join(init.parent.relative_to(ROOT).parts) for init in (ROOT / "roughness").glob("**/__init__.py")}


def test_wheel_holds_every_package_of_the_source_tree(installed):
    site = _purelib(installed)
    missing = [name for name in _source_packages() if not (site / name.replace(".", "/") / "__init__.py").is_file()]
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


def test_checkout_imports_the_checkout():
    import roughness
    import roughness.simulate

    assert Path(roughness.simulate.__file__).resolve() == ROOT / "roughness" / "simulate" / "__init__.py"
    assert Path(roughness.__file__).resolve() == ROOT / "roughness" / "__init__.py"


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
