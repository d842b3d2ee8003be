"""Real scan files from the reader library's own test data (tests/data/scans/README.md: source, commit, licence).

Each format family that was refused by its suffix is read through SurfaceTopography's detection (one code path,
``roughness.surface.scans.read_scan``) and must agree with SurfaceTopography on grid, pixel size and heights, in
mm; a line scan and files without units are refused with that reason; a Park Systems TIFF is read as its data, not
its 8-bit colour thumbnail; and these micrometre-scale scans are refused as too small to feel, not as metres.
"""
from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
import tifffile

from roughness.core.errors import InputError
from roughness.surface.io import read_heightmap
from roughness.surface.scans import MM_PER
from test_bad_inputs import _expect_refusal

DATA = Path(__file__).parent / "data" / "scans"
# file -> (the reader's name, the unit the file states, (nx, ny)) as SurfaceTopography 1.27 reads them
READ = {
    "example_ps.tiff": ("Park Systems TIFF", "µm", (512, 512)),
    "top-1.top": ("WSxM", "nm", (256, 256)),
    "txt_example.txt": ("Plain text", "m", (6, 3)),
}
REFUSED = {
    "10x10-one_channel_without_name.ibw": "(Igor binary wave) states no length unit",
    "xyz-1.txt": "(Plain text (x,y,z coordinates)) states no length unit",
    "opdx-3.opdx": "is a line scan (3,001 points), not a height map",
}


def test_the_files_are_the_recorded_ones_and_small():
    readme = (DATA / "README.md").read_text()
    files = sorted(p.name for p in DATA.iterdir() if p.name != "README.md")
    assert files == sorted([*READ, *REFUSED])
    for name in files:
        assert f"`{name}`" in readme, f"{name} has no source recorded"
    assert sum((DATA / name).stat().st_size for name in files) < 2_000_000


@pytest.mark.parametrize("name", sorted(READ))
def test_a_scan_of_any_format_reads_in_mm_as_the_reader_library_reads_it(name):
    import SurfaceTopography

    kind, unit, grid = READ[name]
    reading = read_heightmap(DATA / name)
    topography = SurfaceTopography.open_topography(str(DATA / name)).topography()
    assert (reading.kind, reading.unit, reading.heightmap.shape[::-1]) == (kind, unit, grid)
    scale = MM_PER[unit]
    nx, ny = grid
    assert reading.pixel_file_mm == pytest.approx((topography.physical_sizes[0] * scale / nx,
                                                   topography.physical_sizes[1] * scale / ny), rel=1e-12)
    assert np.array_equal(reading.heightmap.heights, np.asarray(topography.heights()).T * scale)


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_line_scans_and_files_without_units_are_refused_with_that_reason(name):
    with pytest.raises(InputError, match=REFUSED[name].replace("(", r"\(").replace(")", r"\)")):
        read_heightmap(DATA / name)


def test_a_park_systems_tiff_is_read_as_its_data_not_its_thumbnail():
    with tifffile.TiffFile(DATA / "example_ps.tiff") as tif:  # the trap: the TIFF image is an 8-bit picture
        thumbnail = tif.pages[0].asarray()
        assert thumbnail.dtype == np.uint8 and 50432 in tif.pages[0].tags  # Park Systems' magic tag
    reading = read_heightmap(DATA / "example_ps.tiff")
    heights = reading.heightmap.heights
    assert reading.pixel_from == "file" and reading.unit == "µm"
    assert heights.dtype == np.float64 and len(np.unique(heights)) > 256  # no colour-map indices
    assert 0 < np.ptp(heights) < 1e-3  # mm: an AFM scan's relief, under a micrometre


def test_a_park_systems_tiff_without_the_reader_library_is_refused_not_read_as_a_picture(tmp_path, monkeypatch):
    path = tmp_path / "park.tiff"
    shutil.copy(DATA / "example_ps.tiff", path)
    monkeypatch.setitem(sys.modules, "SurfaceTopography", None)
    monkeypatch.setitem(sys.modules, "SurfaceTopography.IO", None)
    with pytest.raises(InputError, match=r"Park Systems AFM TIFF: its image is a colour thumbnail.*roughness\[scans\]"):
        read_heightmap(path, pixel_mm=0.05, height_mm=1.0)


def test_an_unknown_suffix_without_the_reader_library_names_the_extra(tmp_path, monkeypatch):
    path = tmp_path / "scan.xyz123"
    shutil.copy(DATA / "top-1.top", path)
    monkeypatch.setitem(sys.modules, "SurfaceTopography", None)
    with pytest.raises(InputError, match=r"unsupported heightmap format '\.xyz123'.*roughness\[scans\]"):
        read_heightmap(path)


def test_the_format_comes_from_the_contents_not_the_suffix(tmp_path):
    """A WSxM file under a suffix no reader claims is still found by SurfaceTopography's detection."""
    path = tmp_path / "afm.scan"
    shutil.copy(DATA / "top-1.top", path)
    assert read_heightmap(path).kind == "WSxM"
    (tmp_path / "notes.scan").write_text("no heights here\n")
    with pytest.raises(InputError, match="none of the scan formats SurfaceTopography detects"):
        read_heightmap(tmp_path / "notes.scan")


@pytest.mark.parametrize("name,covers", [("example_ps.tiff", "0.001 mm x 0.001 mm"),
                                         ("top-1.top", "0.0006 mm x 0.0006 mm"),
                                         ("txt_example.txt", "0.001 mm x 0.0005 mm")])
def test_micrometre_scans_are_refused_as_too_small_to_feel_not_as_metres(workdir, capsys, name, covers):
    shutil.copy(DATA / name, workdir / name)
    for argv in (["predict", name, "--engine", "spectral"], ["predict", name, "--engine", "spectral", "--tile"]):
        _expect_refusal(argv, workdir, capsys, (f"the scan covers {covers}; a fingertip footprint is 10 mm: too small "
                                                "to feel, even tiled",))


@pytest.mark.parametrize("name", ["10x10-one_channel_without_name.ibw", "opdx-3.opdx"])
def test_the_cli_refuses_them_with_their_reason(workdir, capsys, name):
    shutil.copy(DATA / name, workdir / name)
    _expect_refusal(["predict", name, "--engine", "spectral"], workdir, capsys, (REFUSED[name],))
