"""Measured scans, TIFF resolution tags and non-square pixels (issue 28): read with their units, or refused.

Every format is written by SurfaceTopography's own writers (.x3p, .gwy, .nc) or by the format's
published layout (.x3p per ISO 25178-72, .sdf per ISO 25178-71, Zygo .datx through h5py, Digital
Surf .sur and Sensofar .plu binary headers as SurfaceTopography's readers document them), in
metres, micrometres and millimetres; each must load as the same heights in mm on the same pixels.
"""
from __future__ import annotations

import builtins
import hashlib
import json
import struct
import sys
import zipfile

import numpy as np
import pytest
import tifffile

from roughness.core.errors import InputError
from roughness.surface.heightmap import Heightmap
from roughness.surface.io import load_heightmap, read_heightmap, save_heightmap
from test_bad_inputs import _expect_refusal

MM = {"m": 1e-3, "um": 1e3, "mm": 1.0}  # file units per mm
NY, NX = 5, 7
PX, PY = 0.01, 0.012  # mm: non-square, as a 10 x 12 um scan


def _heights() -> np.ndarray:
    """(NY, NX) heights in mm whose rows and columns all differ (so a transposed read would show)."""
    y, x = np.mgrid[0:NY, 0:NX]
    return 0.001 * x + 0.0003 * y**2 + 0.0002


def _topography(unit: str, heights: np.ndarray = None, px: float = PX, py: float = PY):
    from SurfaceTopography import Topography

    h = _heights() if heights is None else heights
    ny, nx = h.shape
    f = MM[unit]
    return Topography(h.T * f, (nx * px * f, ny * py * f), unit=unit)  # SurfaceTopography indexes [x, y]


def _x3p_iso(path, unit_scale: float = 1e-3) -> None:
    """An .x3p built from ISO 25178-72 itself: main.xml (axes in metres) and bindata/data.bin (x fastest)."""
    data = (_heights() * unit_scale).astype("<f8").tobytes()  # rows are y: C order is x fastest
    md5 = hashlib.md5(data).hexdigest().upper()
    axis = "<{0}><AxisType>I</AxisType><DataType>D</DataType><Increment>{1!r}</Increment><Offset>0</Offset></{0}>"
    xml = ('<?xml version="1.0" encoding="UTF-8"?>\n'
           '<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2" '
           'xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance">'
           "<Record1><Revision>ISO5436 - 2000</Revision><FeatureType>SUR</FeatureType><Axes>"
           + axis.format("CX", PX * unit_scale) + axis.format("CY", PY * unit_scale)
           + "<CZ><AxisType>A</AxisType><DataType>D</DataType></CZ></Axes></Record1>"
           "<Record2><Date>2026-11-25T12:00:00</Date><Instrument><Manufacturer>test</Manufacturer><Model>test</Model>"
           "<Serial>1</Serial><Version>1</Version></Instrument><CalibrationDate>2026-11-25T12:00:00</CalibrationDate>"
           "<ProbingSystem><Type>NonContacting</Type><Identification>test</Identification></ProbingSystem>"
           "<Comment></Comment></Record2>"
           f"<Record3><MatrixDimension><SizeX>{NX}</SizeX><SizeY>{NY}</SizeY><SizeZ>1</SizeZ></MatrixDimension>"
           f"<DataLink><PointDataLink>bindata/data.bin</PointDataLink><MD5ChecksumPointData>{md5}"
           "</MD5ChecksumPointData></DataLink></Record3>"
           "<Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4></p:ISO5436_2>")
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("main.xml", xml)
        z.writestr("bindata/data.bin", data)
        z.writestr("md5checksum.hex", f"{hashlib.md5(xml.encode()).hexdigest().upper()} *main.xml\n")


def _sdf(path, unit: str) -> None:
    """ISO 25178-71 ASCII .sdf: scales in metres per unit step, NumPoints along x, one line per profile (y)."""
    m_per_value = 1e-3 / MM[unit]
    header = ["aISO-1.0", "ManufacID = roughness-test", "CreateDate = 251120261200", "ModDate = 251120261200",
              f"NumPoints = {NX}", f"NumProfiles = {NY}", f"Xscale = {PX * 1e-3!r}", f"Yscale = {PY * 1e-3!r}",
              f"Zscale = {m_per_value!r}", "Zresolution = -1", "Compression = 0", "DataType = 7", "CheckType = 0",
              "*"]
    rows = [" ".join(repr(float(v)) for v in row) for row in _heights() * MM[unit]]
    path.write_text("\n".join(header + rows + ["*", "*"]) + "\n")


def _datx(path, unit: str) -> None:
    """A Zygo .datx (HDF5): MetaData links Root -> Measurement -> Surface; converters give metres per pixel."""
    import h5py

    converter = np.dtype([("Category", h5py.string_dtype("ascii")), ("BaseUnit", h5py.string_dtype("ascii")),
                          ("HWUnit", h5py.string_dtype("ascii")), ("Parameters", "<f8", (4,))])
    meta = np.dtype([("Source", "S64"), ("Link", "S64"), ("Destination", "S64")])
    with h5py.File(path, "w") as f:
        f["MetaData"] = np.array([(b"Root", b"Measurement", b"{m}"), (b"{m}", b"Surface", b"{s}"),
                                  (b"{s}", b"Path", b"/Measurement/Surface")], dtype=meta)
        surface = f.create_dataset("Measurement/Surface", data=_heights() * MM[unit])
        surface.attrs["Unit"] = np.array([unit.encode()])
        for name, pixel in (("X Converter", PX), ("Y Converter", PY)):
            surface.attrs.create(name, np.array([("LateralCat", "Pixels", "Pixels", (0, pixel * 1e-3, 0, 0))],
                                                dtype=converter))
        surface.attrs.create("Z Converter", np.array([("HeightCat", unit, unit, (0, 1, 0, 0))], dtype=converter))


SUR_HEADER = "<12sHHHH30s30sHHHHHIIHiiiiIfff16s16s16s16s16s16s16s16s16sfffHHHIIIHHHHHHHfIIHHH128sfff34s"


def _sur(path, unit: str) -> None:
    """Digital Surf .sur: the 512-byte header (32-bit counts, steps and units), then rows of x (y outer)."""
    step = 1e-6  # height per count, in ``unit``
    counts = np.round(_heights() * MM[unit] / step).astype("<i4")
    u = unit.encode()
    fields = [b"DIGITAL SURF", 0, 1, 1, 2, b"", b"", 0, 0, 0, 0, 1, 0, 0, 32, int(counts.min()), int(counts.max()),
              NX, NY, NX * NY, PX * MM[unit], PY * MM[unit], step, b"X", b"Y", b"Z", u, u, u, u, u, u, 1.0, 1.0, 1.0,
              0, 0, 0, 0, 0, 0, 0, 0, 0, 25, 11, 2026, 0, 0.0, 0, 0, 0, 0, 0, b"", 0.0, 0.0, 0.0, b""]
    header = struct.pack(SUR_HEADER, *fields)
    assert len(header) == 512
    path.write_bytes(header + counts.tobytes())


def _plu(path) -> None:
    """Sensofar .plu (micrometres by definition): header, calibration, configuration, one float32 layer."""
    um = _heights() * 1e3
    out = struct.pack("<128sI256s", b"Wed Nov 25 12:00:00 2026", 0, b"")
    out += struct.pack("<IIIfffffff", NY, NX, NX * NY, 1.0, PX * 1e3, PY * 1e3, 0, 0, 1.0, 0)
    out += struct.pack("<IIIII", 3, 0, 0, 0, 0)  # topography, area type 0: the plain scan settings follow
    out += struct.pack("<IIIIIdfII", NX, NY, NX, NY, 0, 0.0, 0.0, 0, 0)
    out += struct.pack("<BBBBB3sI", 0, 1, 0, 0, 0, b"", 0)  # one layer, no RGB images
    out += struct.pack("<II", NY, NX) + um.astype("<f4").tobytes() + struct.pack("<ff", um.min(), um.max())
    path.write_bytes(out)


def _write(kind: str, unit: str, path) -> None:
    if kind == "x3p":
        _topography(unit).to_x3p(str(path))
    elif kind == "x3p-iso":
        _x3p_iso(path, 1e-3)
    elif kind == "gwy":
        _topography(unit).to_gwy(str(path))
    elif kind == "nc":
        _topography(unit).to_netcdf(str(path))
    elif kind == "sdf":
        _sdf(path, unit)
    elif kind == "datx":
        _datx(path, unit)
    elif kind == "sur":
        _sur(path, unit)
    else:
        _plu(path)


ROUND_TRIPS = [(kind, unit) for kind in ("x3p", "gwy", "nc", "sdf", "datx", "sur") for unit in ("m", "um", "mm")] + [
    ("x3p-iso", "m"), ("plu", "um")]


@pytest.mark.parametrize("kind,unit", ROUND_TRIPS)
def test_a_scan_loads_in_mm_with_its_pixels_per_axis(tmp_path, kind, unit):
    path = tmp_path / f"scan.{kind.split('-')[0]}"
    _write(kind, unit, path)
    with pytest.raises(InputError, match="not square.*resample_square") as refused:
        load_heightmap(path)
    assert refused.value.parameter == "resample_square"
    reading = read_heightmap(path, resample_square=True)
    assert reading.pixel_file_mm == pytest.approx((PX, PY), rel=1e-6)  # float32 steps in .sur/.plu
    assert reading.pixel_from == "file" and reading.heightmap.pixel_mm == pytest.approx(PX, rel=1e-6)
    h = reading.heightmap.heights
    assert h.shape == (round(NY * PY / PX), NX)  # 6 x 7: y resampled to the finer x step
    # rows 0 and the last sit at the same y as the file's first and last rows' centres clamp: compare columns
    resolution = 1e-6 / MM[unit] if kind == "sur" else 1e-9  # .sur stores counts of 1e-6 units
    tolerance = max(resolution, 1e-6 * float(np.abs(_heights()).max()))  # float32 in .plu
    assert np.allclose(h[0], _heights()[0], atol=tolerance)  # x runs along rows: a transposed read fails here
    assert np.allclose(h[:, 0] - h[0, 0], _expected_column(h.shape[0]), atol=2 * tolerance)


def _expected_column(ny: int) -> np.ndarray:
    """Column 0 of the resampled map: bilinear in y between the file's rows (clamped at the ends)."""
    y = (np.arange(ny) + 0.5) * PX / PY - 0.5
    return np.interp(y, np.arange(NY), _heights()[:, 0]) - _heights()[0, 0]


@pytest.mark.parametrize("unit", ["m", "um", "mm"])
def test_square_scans_load_without_resampling(tmp_path, unit):
    path = tmp_path / "scan.x3p"
    _topography(unit, px=PX, py=PX).to_x3p(str(path))
    hm = load_heightmap(path)
    assert hm.pixel_mm == pytest.approx(PX, rel=1e-12)
    assert np.allclose(hm.heights, _heights(), rtol=0, atol=1e-15)


def test_the_iso_layout_and_surfacetopography_agree_on_orientation(tmp_path):
    _x3p_iso(tmp_path / "iso.x3p")
    _topography("mm").to_x3p(str(tmp_path / "st.x3p"))
    a = read_heightmap(tmp_path / "iso.x3p", resample_square=True).heightmap.heights
    b = read_heightmap(tmp_path / "st.x3p", resample_square=True).heightmap.heights
    assert np.array_equal(a, b)


def test_resampling_is_bilinear_reported_and_recorded(tmp_path):
    path = tmp_path / "scan.x3p"
    _topography("um").to_x3p(str(path))
    reading = read_heightmap(path, resample_square=True)
    record = reading.as_dict()
    assert record["resampled"] == {"method": "bilinear", "shape_before": [NY, NX], "pixel_before_mm": pytest.approx(
        [PX, PY]), "shape_after": [6, NX], "pixel_after_mm": pytest.approx(PX)}
    assert record["unit"] == "m" and record["format"].startswith("XML 3D surface profile")
    assert any("resampled (bilinear) from 7 x 5 pixels of 0.01 mm (x) by 0.012 mm (y) to 7 x 6 square pixels"
               in note for note in reading.notes)
    json.dumps(record)  # plain JSON


def test_a_given_pixel_size_never_overrides_a_scans_units(tmp_path):
    path = tmp_path / "scan.x3p"
    _topography("um", px=PX, py=PX).to_x3p(str(path))
    assert load_heightmap(path, pixel_mm=PX).pixel_mm == pytest.approx(PX)  # the same value is fine
    with pytest.raises(InputError, match="states its pixel size with its unit") as err:
        load_heightmap(path, pixel_mm=0.05)
    assert err.value.parameter == "pixel_mm"
    with pytest.raises(InputError, match=r"carry their unit \(m\).*drop height_mm"):
        load_heightmap(path, height_mm=1.0)


def test_a_missing_extra_says_how_to_install_it(tmp_path, monkeypatch):
    path = tmp_path / "scan.sur"
    _sur(path, "um")
    real_import = builtins.__import__

    def no_surfacetopography(name, *args, **kwargs):
        if name.split(".")[0] == "SurfaceTopography":
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.delitem(sys.modules, "SurfaceTopography", raising=False)
    monkeypatch.setattr(builtins, "__import__", no_surfacetopography)
    installed = r'SurfaceTopography, which is not installed; pip install "roughness\[scans\]"'
    with pytest.raises(InputError, match=installed):
        load_heightmap(path)


@pytest.mark.parametrize("name,content", [
    ("bad.x3p", b"PK\x03\x04 not a zip"), ("bad.sur", b"DIGITAL SURF" + b"\x00" * 20),
    ("bad.plu", b"\x00" * 100), ("bad.datx", b"\x89HDF\r\n\x1a\n" + b"\x00" * 50), ("bad.gwy", b"GWYPxx"),
    ("bad.sdf", b"aISO-1.0\nNumPoints = x\n")])
def test_a_corrupt_scan_is_an_input_error_naming_the_file_and_format(tmp_path, name, content):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(InputError, match=rf"cannot read {path} as "):
        load_heightmap(path)


def test_a_truncated_scan_is_refused(tmp_path):
    path = tmp_path / "scan.sur"
    _sur(path, "um")
    path.write_bytes(path.read_bytes()[:-10])
    with pytest.raises(InputError, match=f"cannot read {path} as Digital Surf SUR"):
        load_heightmap(path)


def test_a_scan_is_sized_before_its_heights_are_read(tmp_path, monkeypatch):
    import roughness.surface.scans as scans
    from roughness.core.limits import Limit

    path = tmp_path / "scan.x3p"
    _topography("um").to_x3p(str(path))
    monkeypatch.setattr(scans, "MAX_HEIGHTMAP_PIXELS", Limit(NX * NY - 1, "MAX_HEIGHTMAP_PIXELS"))
    import SurfaceTopography.IO.X3P as x3p

    monkeypatch.setattr(x3p.X3PReader, "topography", lambda *a, **k: pytest.fail("heights read before the check"))
    with pytest.raises(InputError, match=r"pixels its channel 'Default' declares \(7 x 5\): 35, above the limit"):
        load_heightmap(path)


def test_holes_stay_holes(tmp_path):
    heights = _heights().copy()
    heights[2, 3] = np.nan
    path = tmp_path / "holes.x3p"
    _topography("um", heights, PX, PX).to_x3p(str(path))
    with pytest.raises(InputError, match="1 NaN/Inf pixel"):
        load_heightmap(path)


def test_holes_in_a_scan_reach_fill(workdir, capsys):  # noqa: F811
    """One loading pipeline for every format: a scan's missing points are refused without --fill and filled with
    it, reported and recorded like those of any other file."""
    from roughness.cli import main

    h = np.random.default_rng(2).random((240, 240)) * 0.5
    h[100:104, 50:60] = np.nan
    _topography("um", h, 0.05, 0.05).to_x3p(str(workdir / "holes.x3p"))
    assert main(["predict", "holes.x3p", "--engine", "spectral"]) == 2
    assert "40 missing points (NaN)" in capsys.readouterr().err
    assert main(["predict", "holes.x3p", "--engine", "spectral", "--fill", "--json"]) == 0
    out, err = capsys.readouterr()
    assert "note: holes.x3p: filled 40 missing points" in err
    record = json.loads(out)["readings"][0]
    assert record["steps"] == [{"step": "filled", "pixels": 40, "fraction": pytest.approx(40 / 240**2)}]
    assert record["format"].startswith("XML 3D surface profile") and record["pixel_from"] == "file"


def test_only_unambiguous_suffixes_name_a_reader_and_the_tools_own_stay_here():
    """.npy, .npz, .h5 and .tif are read by roughness.surface.io (no pickle: allow_pickle=False); suffixes that several
    readers claim (text, .mat, .csv, .xlsx, .zip, .dat) go to SurfaceTopography's detection; .nms names none."""
    from roughness.surface.scans import FORMATS

    assert not {".npy", ".npz", ".mat", ".txt", ".asc", ".csv", ".xlsx", ".zip", ".dat", ".h5", ".tif",
                ".nms"} & set(FORMATS)
    assert {".x3p", ".sur", ".plu", ".datx", ".gwy", ".sdf", ".spm", ".ibw", ".opdx", ".zon", ".stp"} <= set(FORMATS)


# TIFF resolution tags


def test_the_tools_own_tiff_carries_standard_resolution_tags(tmp_path):
    hm = Heightmap(_heights(), 0.04)
    save_heightmap(hm, tmp_path / "own.tif")
    with tifffile.TiffFile(tmp_path / "own.tif") as tif:
        page = tif.pages[0]
        x, y = (page.tags[n].value for n in ("XResolution", "YResolution"))
        assert int(page.tags["ResolutionUnit"].value) == 3  # centimetre
        assert 10 * x[1] / x[0] == pytest.approx(0.04, rel=1e-6) and 10 * y[1] / y[0] == pytest.approx(0.04, rel=1e-6)
    # the tags alone, as other software reads them: the description removed
    tifffile.imwrite(tmp_path / "tags.tif", hm.heights.astype(np.float32), resolution=(x, y),
                     resolutionunit="CENTIMETER", metadata=None)
    reading = read_heightmap(tmp_path / "tags.tif")
    assert reading.heightmap.pixel_mm == pytest.approx(0.04, rel=1e-6) and reading.pixel_from == "TIFF resolution tags"
    assert any("from its TIFF resolution tags" in note for note in reading.notes)


@pytest.mark.parametrize("unit,per_unit,pixel_mm", [("CENTIMETER", 200.0, 0.05), ("INCH", 508.0, 0.05),
                                                    ("MILLIMETER", 25.0, 0.04), ("MICROMETER", 0.1, 0.01)])
def test_tiff_resolution_tags_in_any_unit(tmp_path, unit, per_unit, pixel_mm):
    path = tmp_path / "t.tif"
    tifffile.imwrite(path, _heights().astype(np.float32), resolution=(per_unit, per_unit), resolutionunit=unit,
                     metadata=None)
    assert read_heightmap(path).heightmap.pixel_mm == pytest.approx(pixel_mm, rel=1e-6)


def test_tiff_tags_without_a_unit_are_no_pixel_size(tmp_path):
    path = tmp_path / "t.tif"
    tifffile.imwrite(path, _heights().astype(np.float32), metadata=None)  # 1 x 1, ResolutionUnit NONE
    with pytest.raises(InputError, match="need pixel_mm"):
        load_heightmap(path)


def test_non_square_tiff_tags_refused_or_resampled(tmp_path):
    path = tmp_path / "t.tif"
    tifffile.imwrite(path, _heights().astype(np.float32), resolution=(10 / PX, 10 / PY), resolutionunit="CENTIMETER",
                     metadata=None)
    with pytest.raises(InputError, match=r"0.01 mm \(x\) by 0.012 mm \(y\), from its TIFF resolution tags"):
        load_heightmap(path)
    reading = read_heightmap(path, resample_square=True)
    assert reading.heightmap.shape == (6, NX) and reading.resampling is not None


def test_a_given_pixel_size_replaces_tiff_tags_with_a_note(tmp_path):
    path = tmp_path / "picture.tif"
    tifffile.imwrite(path, (_heights() * 1e5).astype(np.uint16), resolution=(72, 72), resolutionunit="INCH",
                     metadata=None)  # picture software's habit
    reading = read_heightmap(path, pixel_mm=0.05, height_mm=1.0)
    assert reading.heightmap.pixel_mm == 0.05 and reading.pixel_from == "given"
    assert any("resolution tags say 0.352778 mm" in note and "pixel_mm = 0.05 mm was given and is used" in note
               for note in reading.notes)
    with pytest.warns(UserWarning, match="resolution tags say"):
        load_heightmap(path, pixel_mm=0.05, height_mm=1.0)


# the CLI: exit 2 with a specific message, or a recorded resampling


def _scan_files(folder) -> None:
    _topography("um").to_x3p(str(folder / "nonsquare.x3p"))
    h = np.random.default_rng(0).random((240, 240)) * 0.5
    _topography("um", h, 0.05, 0.05).to_x3p(str(folder / "scan.x3p"))
    (folder / "corrupt.sur").write_bytes(b"DIGITAL SURF" + b"\x00" * 40)


@pytest.mark.parametrize("argv,names", [
    (["predict", "nonsquare.x3p"], ("--resample-square",)),
    (["simulate", "nonsquare.x3p", "--fidelity", "coarse"], ("--resample-square",)),
    (["jnd", "scan.x3p", "nonsquare.x3p"], ("--resample-square",)),
    (["homogeneity", "nonsquare.x3p"], ("--resample-square",)),
    (["tune", "nonsquare.x3p", "--target-lambda", "1.0", "--out", "tuned.npz"], ("--resample-square",)),
    (["predict", "scan.x3p", "--pixel-mm", "0.1"], ("--pixel-mm",)),
    (["simulate", "scan.x3p", "--height-mm", "1", "--fidelity", "coarse"], ("--height-mm",)),
    (["predict", "corrupt.sur"], ("cannot read corrupt.sur as Digital Surf SUR",)),
    (["simulate", "corrupt.sur", "--fidelity", "coarse"], ("cannot read corrupt.sur as Digital Surf SUR",)),
])
def test_bad_scan_inputs_exit_2_naming_the_option(workdir, capsys, argv, names):  # noqa: F811
    _scan_files(workdir)
    _expect_refusal(argv, workdir, capsys, names)


def test_missing_extra_exits_2_with_the_install_command(workdir, capsys, monkeypatch):  # noqa: F811
    _scan_files(workdir)
    monkeypatch.setitem(sys.modules, "SurfaceTopography", None)  # import fails as if not installed
    _expect_refusal(["predict", "scan.x3p"], workdir, capsys, ('pip install "roughness[scans]"',))


def test_predict_resamples_on_request_and_records_it(workdir, capsys):  # noqa: F811
    from roughness.cli import main

    h = np.random.default_rng(1).random((200, 240)) * 0.5
    _topography("um", h, 0.05, 0.06).to_x3p(str(workdir / "big.x3p"))
    assert main(["predict", "big.x3p", "--engine", "spectral", "--resample-square", "--json"]) == 0
    out, err = capsys.readouterr()
    assert "note: big.x3p: resampled (bilinear) from 240 x 200 pixels of 0.05 mm (x) by 0.06 mm (y) to 240 x 240" in err
    reading = json.loads(out)["readings"][0]
    assert reading["resampled"]["shape_after"] == [240, 240] and reading["pixel_mm"] == pytest.approx(0.05)
    assert reading["unit"] == "m" and reading["pixel_file_mm"] == pytest.approx([0.05, 0.06])


def test_resampling_recovers_the_roughness_that_one_size_for_both_axes_loses():
    """A texture scanned on 0.05 x 0.06 mm pixels: resampled to square it feels as the texture (measured -0.01 JND,
    Monte Carlo error about 0.02 JND); read as if its pixels were square it is 0.34 JND smoother (spectral engine)."""
    from roughness.dataset.catalogue import make_texture
    from roughness.perceptual_scale import jnd_distance, load_scale
    from roughness.prediction import predict
    from roughness.surface.pixels import square

    hm = make_texture("standard-1.0")[0]
    ny, nx = int(hm.size_mm[1] / 0.06), hm.shape[1]
    scan = hm.sample(((np.arange(nx) + 0.5) * 0.05)[None, :], ((np.arange(ny) + 0.5) * 0.06)[:, None])
    resampled, _ = square(scan, 0.05, 0.06)
    truth, fixed, naive = predict([hm, Heightmap(resampled, 0.05), Heightmap(scan, 0.05)], engine="spectral")
    scale = load_scale(truth.fidelity)
    assert abs(jnd_distance(scale, fixed.roughness, truth.roughness).jnd) < 0.05
    assert jnd_distance(scale, naive.roughness, truth.roughness).jnd < -0.2


def test_unusable_tiff_tags_need_the_pixel_size_or_yield_to_it(tmp_path):
    path = tmp_path / "t.tif"
    tifffile.imwrite(path, _heights().astype(np.float32), resolution=((0, 1), (0, 1)), resolutionunit="CENTIMETER",
                     metadata=None)
    with pytest.raises(InputError, match="pixel_mm it states is not a positive finite number"):
        read_heightmap(path)
    assert read_heightmap(path, pixel_mm=0.05).heightmap.pixel_mm == 0.05


# pixels square within SQUARE_RTOL, scans too small to feel, units the file states


@pytest.mark.parametrize("stretch", [1.00008, 1.0006, 0.9994])
def test_pixels_within_square_rtol_are_read_as_square_with_a_note(tmp_path, stretch):
    path = tmp_path / "scan.x3p"
    _topography("um", px=PX, py=PX * stretch).to_x3p(str(path))
    reading = read_heightmap(path)
    assert reading.resampling is None and reading.heightmap.shape == (NY, NX)
    assert reading.heightmap.pixel_mm == pytest.approx(PX * (1 + stretch) / 2, rel=1e-9)
    assert reading.pixel_file_mm == pytest.approx((PX, PX * stretch), rel=1e-9)
    assert any("less than 0.1% (SQUARE_RTOL): read as square pixels" in note for note in reading.notes)


def test_pixels_beyond_square_rtol_are_still_refused(tmp_path):
    path = tmp_path / "scan.x3p"
    _topography("um", px=PX, py=PX * 1.0012).to_x3p(str(path))
    with pytest.raises(InputError, match="not square"):
        load_heightmap(path)


def test_a_pixel_off_by_half_square_rtol_moves_v_far_less_than_a_jnd():
    """SQUARE_RTOL's claim, measured: the mean of two pixel sizes 0.1% apart is 0.05% off either; reading the
    standard texture lambda = 1.0 mm with its pixel 0.05% too large moves V by 0.003 JND at most (spectral engine,
    deterministic: the same heights on a stretched grid)."""
    from roughness.core.limits import SQUARE_RTOL
    from roughness.dataset.catalogue import make_texture
    from roughness.perceptual_scale import jnd_distance, load_scale
    from roughness.prediction import predict

    hm = make_texture("standard-1.0")[0]
    stretched = Heightmap(hm.heights, hm.pixel_mm * (1 + SQUARE_RTOL / 2))
    truth, off = predict([hm, stretched], engine="spectral")
    moved = abs(jnd_distance(load_scale("spectral"), off.roughness, truth.roughness).jnd)
    assert moved < 0.01  # the bound of core/limits.py: ln(1.0005) / ln(1.19) = 0.003 JND, with room for contact


def test_a_scan_states_its_units_so_implausible_numbers_are_the_surface_not_a_unit(workdir, capsys):  # noqa: F811
    h = np.random.default_rng(3).random((240, 240)) * 1e-4  # 0.1 um of relief on a 12 mm scan: polished
    _topography("um", h, 0.05, 0.05).to_x3p(str(workdir / "polished.x3p"))
    _expect_refusal(["predict", "polished.x3p", "--engine", "spectral"], workdir, capsys,
                    ("The file states its unit (m, converted to mm), so these are the surface's own numbers, not a "
                     "unit mistake: pass --units-ok",))
    from roughness.cli import main

    assert main(["predict", "polished.x3p", "--engine", "spectral", "--units-ok"]) == 0
    assert "looks like" not in capsys.readouterr().err


def test_the_smallest_scan_to_feel_is_five_floor_wavelengths_of_the_footprint_engines():
    from roughness.perceptual_scale import FLOOR_LAMBDA_MM
    from roughness.simulate.config import SimConfig
    from roughness.surface.tiling import FOOTPRINT_MM, MIN_PERIODS, MIN_SIDE_MM

    assert FOOTPRINT_MM == SimConfig().width_mm and MIN_SIDE_MM == MIN_PERIODS * FLOOR_LAMBDA_MM == 1.0


def test_a_scan_of_a_millimetre_or_more_is_not_too_small(workdir, capsys):  # noqa: F811
    """A 1.2 mm seamless scan of a periodic texture (0.3 mm grating) tiles; a 0.9 mm one is too small to feel."""
    from roughness.cli import main

    for side_px, name in ((24, "cell.x3p"), (18, "small.x3p")):
        x = np.arange(side_px) * 0.05
        h = np.tile(0.05 * np.sin(2 * np.pi * x / 0.3), (side_px, 1))
        _topography("um", h, 0.05, 0.05).to_x3p(str(workdir / name))
    assert main(["predict", "cell.x3p", "--engine", "spectral", "--tile"]) == 0
    _expect_refusal(["predict", "small.x3p", "--engine", "spectral", "--tile"], workdir, capsys,
                    ("the scan covers 0.9 mm x 0.9 mm; a fingertip footprint is 10 mm: too small to feel",))
