"""`roughness palette` and `roughness tactile-image`: distinguishable textures, FEM-verified, and a plate made of them."""
from __future__ import annotations

import json

import numpy as np
import pytest

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.dataset.textures import standard_texture
from roughness.design.evaluation import Evaluator
from roughness.design.palette import family_palette, folder_palette, load_palette, widest_selection

EVALUATOR = Evaluator()


def test_widest_selection_maximises_the_smallest_gap():
    x = np.array([0.0, 0.4, 1.0, 2.1, 2.2, 3.0, 4.0])
    chosen, gap = widest_selection(x, 3)
    assert gap == pytest.approx(1.9) and sorted(x[chosen]) == [0.0, 2.1, 4.0]  # 2.1 beats 2.2 (1.8) and 1.0 (1.0)
    chosen, gap = widest_selection(x, 7)
    assert gap == pytest.approx(0.1) and sorted(chosen) == list(range(7))


def test_a_palette_that_cannot_fit_is_refused_before_any_fem():
    before = EVALUATOR.fem_runs
    with pytest.raises(InputError, match=r"do not fit 3 JND apart.*room for \d"):
        family_palette(8, 3.0, evaluator=EVALUATOR)
    assert EVALUATOR.fem_runs == before


def test_folder_palette_picks_the_farthest_candidates_fem_verified():
    names = [0.625, 0.75, 0.875, 1.0, 1.625]
    candidates = [(f"standard-{lam}", standard_texture(lam, seed=2)) for lam in names]
    palette = folder_palette(candidates, 2, 3.0, EVALUATOR)
    assert [m.name for m in palette.members] == ["standard-0.625", "standard-1.625"]
    assert palette.verified and palette.closest_jnd >= 3.0  # lambda 0.625 vs 1.625: 5.5 JND on the standard scale
    with pytest.raises(InputError, match="no 3 of the 5 textures are 3 JND apart"):
        folder_palette(candidates, 3, 3.0, EVALUATOR)


@pytest.fixture(scope="module")
def palette_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("palette") / "pal"
    code = main(["palette", "--k", "3", "--min-jnd", "2", "--out", str(out), "--quiet"])
    return code, out


def test_cli_palette_every_pair_fem_verified(palette_dir, capsys):
    code, out = palette_dir
    assert code == 0
    summary = json.loads((out / "palette.json").read_text())
    d = np.abs(np.array(summary["distances_jnd"]))
    assert summary["verified"] and d[np.triu_indices(3, 1)].min() >= 2.0
    assert [m["name"] for m in summary["members"]] == ["texture-1", "texture-2", "texture-3"]
    v = [m["fem_roughness"] for m in summary["members"]]
    assert v == sorted(v) and (out / "preview.png").stat().st_size > 1000
    assert [name for name, _, _ in load_palette(out)] == ["texture-1", "texture-2", "texture-3"]


def test_cli_palette_refuses_an_existing_folder(palette_dir, capsys):
    _, out = palette_dir
    before = (out / "palette.json").read_bytes()
    assert main(["palette", "--k", "3", "--out", str(out)]) == 2
    assert "already exists" in capsys.readouterr().err and (out / "palette.json").read_bytes() == before
    assert main(["palette", "--k", "9", "--min-jnd", "3", "--out", str(out.parent / "new")]) == 2
    assert "--k" in capsys.readouterr().err and not (out.parent / "new").exists()


def test_cli_tactile_image_from_a_palette(palette_dir, tmp_path, capsys):
    """The issue's check: a synthetic 3-colour picture; a watertight mesh; regions apart; the map shows them."""
    trimesh = pytest.importorskip("trimesh")
    from PIL import Image

    _, pal = palette_dir
    rgb = np.zeros((24, 60, 3), dtype=np.uint8)
    rgb[:, :20], rgb[:, 20:40], rgb[:, 40:] = (250, 240, 200), (200, 40, 40), (20, 20, 90)
    Image.fromarray(rgb).save(tmp_path / "picture.png")
    out = tmp_path / "plate"
    code = main(["tactile-image", str(tmp_path / "picture.png"), "--palette", str(pal), "--out", str(out),
                 "--size-mm", "60", "--step-mm", "2", "--outline-mm", "1", "--json", "--quiet"])
    summary = json.loads(capsys.readouterr().out)
    assert code == 0
    mesh = trimesh.load(out / "plate.stl")
    assert mesh.is_watertight and mesh.extents[0] == pytest.approx(59.9, abs=1e-3)
    texture_d = np.abs(np.array(summary["texture_distances_jnd"], dtype=float))
    assert texture_d[np.triu_indices(3, 1)].min() >= 2.0  # the FEM-verified palette: the requested 2 JND
    plate_d = np.array(summary["plate_distances_jnd"], dtype=float)
    assert plate_d[1, 0] > 1.0 and plate_d[2, 1] > 1.0  # the plate's own map (surrogate) orders and separates them
    v = np.load(out / "roughness_map.npy")
    assert v.shape == (8, 26)  # footprint centres 5..55 mm and 5..19 mm, 2 mm apart
    for name in ("plate.npz", "plate.json", "relief.png", "roughness_map.png"):
        assert (out / name).stat().st_size > 0
    assert main(["tactile-image", str(tmp_path / "picture.png"), "--palette", str(pal), "--out", str(out)]) == 2


def test_progress_names_the_verifier_that_answered():
    """Under a spectral verifier the progress lines say so (they said "FEM lambda" whatever the verifier)."""
    lines: list[str] = []
    names = [0.625, 1.625]
    candidates = [(f"standard-{lam}", standard_texture(lam, seed=2)) for lam in names]
    spectral = Evaluator(fidelity="spectral")
    folder_palette(candidates, 2, 3.0, spectral, progress=lines.append)
    family_palette(2, 2.0, evaluator=spectral, progress=lines.append)
    assert len(lines) == 4 and all(line.count("spectral") == 1 and "FEM" not in line for line in lines), lines
