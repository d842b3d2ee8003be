"""`roughness homogeneity`: standard textures pass, two halves of different lambda fail, placements agree."""
from __future__ import annotations

import json

import numpy as np
import pytest

from roughness.cli import main
from roughness.dataset.textures import standard_texture
from roughness.design.evaluation import Evaluator
from roughness.design.homogeneity import Homogeneity, homogeneity, mirrored_window
from roughness.surface.heightmap import Heightmap
from roughness.surface.io import save_heightmap

EVALUATOR = Evaluator()


@pytest.fixture(scope="module")
def halves() -> Heightmap:
    """30 mm: lambda 0.75 mm on the left, 1.25 mm on the right (3 JND apart on the standard scale)."""
    a = standard_texture(0.75, seed=1, size_mm=30.0).heights
    b = standard_texture(1.25, seed=1, size_mm=30.0).heights
    return Heightmap(np.hstack([a[:, :300], b[:, 300:]]), 0.05)


@pytest.mark.parametrize("lam", [0.625, 1.0, 1.625])
def test_standard_textures_feel_homogeneous(lam):
    result = homogeneity(standard_texture(lam, seed=2), tile=True, evaluator=EVALUATOR)
    assert isinstance(result, Homogeneity) and len(result.roughness) == 50
    assert result.verdict == "homogeneous" and result.spread_jnd < 0.4


def test_two_halves_of_different_lambda_fail(halves):
    result = homogeneity(halves, evaluator=EVALUATOR)
    assert result.verdict == "inhomogeneous" and result.paper_verdict == "inhomogeneous"
    assert result.relative_variance > 1e-2 and result.spread_jnd > 0.8
    left = result.roughness[result.x_mm < 10].mean()  # footprints wholly on the fine half feel smoother
    right = result.roughness[result.x_mm > 20].mean()
    assert left < right


def test_the_number_is_stable_across_window_placements(halves):
    flat_ok = [homogeneity(standard_texture(1.0, seed=2), tile=True, seed=s, evaluator=EVALUATOR) for s in range(4)]
    bad = [homogeneity(halves, seed=s, evaluator=EVALUATOR) for s in range(4)]
    for results in (flat_ok, bad):
        spreads = [r.spread_jnd for r in results]
        # the SD of 50 windows has a ~10% sampling error (sqrt(1 / (2 * 49))); 4 placements stay within 1.7x
        assert max(spreads) / min(spreads) < 1.7
        assert len({r.verdict for r in results}) == 1
    assert max(r.spread_jnd for r in flat_ok) < min(r.spread_jnd for r in bad) / 2


def test_a_small_window_is_felt_alone_as_a_seamless_tile():
    hm = standard_texture(1.0, seed=0)
    tile = mirrored_window(hm, (6.0, 6.0), 5.0)
    h = tile.heights
    assert h.shape == (200, 200)
    assert np.array_equal(h[:100, :100], hm.heights[70:170, 70:170])
    assert np.array_equal(h[:, 0], h[:, -1]) and np.array_equal(h[0], h[-1])  # mirror edges: no jump on wrapping
    result = homogeneity(hm, window_mm=5.0, n=10, tile=True, evaluator=EVALUATOR)
    assert result.window_mm == 5.0 and np.isfinite(result.roughness).all()


def test_fem_engine_agrees_on_a_clear_case(halves):
    """Coarse FEM on 3 windows (two mostly on the fine half, one on the coarse): the reference sees the halves."""
    result = homogeneity(halves, engine="fem", n=3, seed=3, evaluator=EVALUATOR)
    assert result.engine == "fem" and result.in_domain.all()
    assert result.range_jnd > 1.0


def test_cli_writes_the_map_and_refuses_to_overwrite(tmp_path, capsys):
    path = tmp_path / "t.npz"
    save_heightmap(standard_texture(1.0, seed=2), path)
    out = tmp_path / "map.png"
    assert main(["homogeneity", str(path), "--tile", "--n", "20", "--map", str(out), "--json", "--quiet"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["verdict"] == "homogeneous" and summary["windows"] == 20 and out.stat().st_size > 1000
    before = out.read_bytes()
    assert main(["homogeneity", str(path), "--tile", "--map", str(out)]) == 2
    assert "already exists" in capsys.readouterr().err and out.read_bytes() == before
    assert main(["homogeneity", str(path), "--n", "2"]) == 2
    assert main(["homogeneity", str(path), "--window-mm", "40"]) == 2
    assert "--window-mm" in capsys.readouterr().err
