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
                 "--size-mm", "60", "--step-mm", "2", "--outline-mm", "1", "--background", "none", "--json",
                 "--quiet"])  # every stripe textured (default: the background flat)
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


def test_a_palette_survives_the_printer():
    """fdm-0.4-0.2 prints standard-1.0 below half a layer flat and its first layers not even rising: the members
    are chosen among prints that keep their V, verified 2 JND apart as printed (they were three copies of height
    x 0.118, 0 JND apart)."""
    from roughness.surface.printing import PROFILES

    printer = Evaluator(fidelity="spectral", printer=PROFILES["fdm-0.4-0.2"])
    palette = family_palette(3, 2.0, evaluator=printer)
    assert palette.verified and palette.closest_jnd >= 2.0
    assert not any("tolerance" in note for note in palette.notes)
    told = family_palette(3, 2.0, evaluator=printer, tolerance_jnd=0.3)  # no tuning: a tolerance is said unused
    assert [m.recipe for m in told.members] == [m.recipe for m in palette.members]
    assert any("tolerance_jnd 0.3 is not used with a printer" in note for note in told.notes)
    heights = [m.recipe["height_factor"] for m in palette.members]
    assert len(set(heights)) == 3 and all(m.recipe["printer"] == "fdm-0.4-0.2" for m in palette.members)
    for m in palette.members:  # the distances are between prints: the verifier's V is the printed texture's
        assert m.fem.roughness == pytest.approx(printer.verify(m.heightmap).roughness, rel=1e-9)
        digital = printer.verify(m.heightmap, digital=True)
        assert abs(np.log(m.fem.equivalent_lambda_mm / digital.equivalent_lambda_mm)) / np.log(1.19) <= 1.2


def test_a_printed_palette_that_cannot_fit_says_how_many_fit_and_why():
    from roughness.surface.printing import PROFILES

    printer = Evaluator(fidelity="spectral", printer=PROFILES["fdm-0.4-0.2"])
    with pytest.raises(InputError, match=r"do not fit 4 JND apart as printed.*0.45 mm.*0.2 mm layers.*room for \d")\
            as err:
        family_palette(4, 4.0, evaluator=printer)
    assert err.value.parameter == "k" and printer.fem_runs == 0  # refused before any verification


def test_cli_writes_no_unverified_palette(tmp_path, capsys, monkeypatch):
    """A palette whose closest pair misses --min-jnd is reported, exit 1, and no folder is written."""
    from dataclasses import replace
    from functools import wraps

    import roughness.design.palette as design

    real = design.family_palette

    @wraps(real)  # the command's defaults are read from its signature
    def unverified(k, min_jnd, *args, **kwargs):  # as if the verifier found two members alike
        return replace(real(k, min_jnd, *args, **kwargs), distances_jnd=np.zeros((k, k)))

    monkeypatch.setattr(design, "family_palette", unverified)
    out = tmp_path / "pal"
    code = main(["palette", "--k", "2", "--min-jnd", "2", "--verify", "spectral", "--out", str(out), "--quiet"])
    text = capsys.readouterr().out
    assert code == 1 and "closest pair 0.00 JND (spectral): NOT VERIFIED >= 2 JND; nothing written" in text
    assert not out.exists()


def test_a_print_at_a_threshold_is_not_kept_and_fits_counts_greedily():
    from roughness.design.palette import _stable, fits

    kept = np.array([True] * 5 + [False] + [True] * 4)
    lam = np.exp(np.arange(10) * 0.05)  # neighbours 0.3 JND apart
    assert _stable(kept, lam, 1).tolist() == [False, True, True, True, False, False, False, True, True, False]
    jump = lam.copy()
    jump[3:] *= 1.19 ** 1.5  # a print jumping 1.5 JND between neighbours 2 and 3 (a layer more)
    assert _stable(kept, jump, 1).tolist()[1:5] == [True, False, False, False]
    assert fits(np.array([0.0, 1.0, 2.1, 4.0]), 2.0) == 2 and fits(np.array([0.0, 2.0, 4.0]), 2.0) == 3


def test_a_printed_palette_the_verifier_cannot_separate_is_refused_as_printed(monkeypatch):
    """The surrogate placed K apart but the verifier's prints are closer: refused naming the printer (no folder)."""
    import roughness.design.palette as design
    from roughness.surface.printing import PROFILES

    def too_close(candidates, k, min_jnd, *args, **kwargs):
        raise InputError(f"no {k} of the {len(candidates)} textures are {min_jnd:g} JND apart", parameter="min_jnd")

    monkeypatch.setattr(design, "folder_palette", too_close)
    printer = Evaluator(fidelity="spectral", printer=PROFILES["sla1s-47um"])
    with pytest.raises(InputError, match=r"JND apart as printed by sla1s-47um \(spectral; the surrogate placed \d+\)")\
            as err:
        family_palette(2, 2.0, evaluator=printer)
    assert err.value.parameter == "k"
