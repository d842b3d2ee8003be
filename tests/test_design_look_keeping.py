"""Look-keeping tuning (roughness.design.look_keeping): the same feel as plain tune with less change of look."""
from __future__ import annotations

import numpy as np
import pytest

from roughness.cli import main
from roughness.dataset.textures import standard_texture
from roughness.design.evaluation import Evaluator
from roughness.design.look_keeping import keep_look
from roughness.design.tune import target_of


@pytest.fixture(scope="module")
def kept():
    evaluator = Evaluator(fidelity="spectral")
    tile = standard_texture(1.0)
    return keep_look(tile, target_of(evaluator, jnd=1.0, heightmap=tile, tile=True), evaluator, tile=True,
                     laterals=(1.0, 1.2))


def test_the_kept_mix_reaches_the_target_and_looks_least_changed(kept):
    chosen = kept.chosen
    assert chosen.reached and abs(chosen.result.jnd_error) <= chosen.result.tolerance_jnd
    reached = [c for c in kept.candidates if c.reached]
    assert chosen.look.difference == min(c.look.difference for c in reached)
    height_alone = next(c for c in kept.candidates if c.lateral == 1.0)
    assert height_alone.reached and chosen.look.difference < height_alone.look.difference / 2


def test_every_candidate_is_reported(kept):
    lateral = [c.lateral for c in kept.candidates]
    assert lateral[1:3] == [1.0, 1.2] and len(lateral) >= 3  # lateral alone first, then the grid, then refinements
    summary = kept.summary()
    assert len(summary["candidates"]) == len(kept.candidates) and np.isfinite(summary["look_jnd"])


def test_keep_look_takes_no_factor_range(tmp_path, capsys):
    np.save(tmp_path / "t.npy", standard_texture(1.0).heights)
    code = main(["tune", str(tmp_path / "t.npy"), "--pixel-mm", "0.05", "--jnd", "1", "--keep-look", "--min-factor",
                 "0.5", "--out", str(tmp_path / "o.npz")])
    assert code == 2 and "--keep-look" in capsys.readouterr().err
