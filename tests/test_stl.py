"""Printable plates: watertight, outward-facing, in millimetres, with the heights of the map."""
from __future__ import annotations

import io

import numpy as np
import pytest
import trimesh

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap
from roughness.surface.io import save_heightmap
from roughness.surface.stl import plate, stl_bytes

RNG = np.random.default_rng(5)


def _mesh(hm: Heightmap, base_mm: float = 2.0) -> trimesh.Trimesh:
    return trimesh.load(io.BytesIO(stl_bytes(plate(hm, base_mm))), file_type="stl")


@pytest.mark.parametrize("shape", [(2, 2), (3, 7), (40, 25)])
def test_plate_is_a_closed_outward_facing_solid(shape):
    hm = Heightmap(RNG.random(shape) * 0.8, 0.05)
    mesh = _mesh(hm)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.is_volume and mesh.volume > 0
    ny, nx = shape
    assert len(mesh.faces) == 2 * (ny - 1) * (nx - 1) + 3 * (2 * (nx - 1) + 2 * (ny - 1))


def test_plate_geometry_in_mm():
    """A plane z = 0.3 x + 0.1 y: exact volume (the triangulated top is the plane), bounds at the pixel centres."""
    ny, nx, p, base = 12, 20, 0.1, 1.5
    x, y = (np.arange(nx) + 0.5) * p, (np.arange(ny) + 0.5) * p
    hm = Heightmap(0.3 * x[None, :] + 0.1 * y[:, None] + 7.0, p)  # the offset is removed: the plate stands on z = 0
    mesh = _mesh(hm, base)
    width, depth = (nx - 1) * p, (ny - 1) * p
    mean_relief = 0.3 * width / 2 + 0.1 * depth / 2
    assert mesh.volume == pytest.approx(width * depth * (base + mean_relief), rel=1e-6)  # float32 vertices
    np.testing.assert_allclose(mesh.bounds, [[x[0], y[0], 0.0], [x[-1], y[-1], base + 0.3 * width + 0.1 * depth]],
                               rtol=1e-6)


def test_flat_map_is_a_box():
    mesh = _mesh(Heightmap(np.zeros((5, 5)), 1.0), base_mm=0.5)
    assert mesh.volume == pytest.approx(4 * 4 * 0.5)


@pytest.mark.parametrize("base", [0.0, -1.0, float("nan")])
def test_bad_base_thickness(base):
    with pytest.raises(InputError, match="base_mm must be a positive finite number"):
        plate(Heightmap(np.zeros((3, 3)), 0.1), base)


def test_save_stl_and_base_only_for_stl(tmp_path):
    hm = Heightmap(RNG.random((6, 6)), 0.1)
    save_heightmap(hm, tmp_path / "p.stl", base_mm=1.0)
    assert trimesh.load(tmp_path / "p.stl").is_watertight
    with pytest.raises(InputError, match="base_mm applies only to STL"):
        save_heightmap(hm, tmp_path / "p.npz", base_mm=1.0)


def test_texture_make_writes_a_printable_plate(tmp_path, capsys):
    out = tmp_path / "plate.stl"
    assert main(["texture", "make", "woven", "--size-mm", "4", "--out", str(out), "--base-mm", "1"]) == 0
    mesh = trimesh.load(out)
    assert mesh.is_watertight and mesh.bounds[0][2] == 0.0 and 1.0 < mesh.bounds[1][2] < 2.5
    assert main(["texture", "make", "woven", "--size-mm", "4", "--out", str(out)]) == 2  # exists: refused
    assert "already exists" in capsys.readouterr().err
