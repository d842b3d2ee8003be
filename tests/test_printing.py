"""Print-aware prediction: the printed surface of a heightmap (roughness.surface.printing) and --printer."""
from __future__ import annotations

import json

import numpy as np
import pytest

from roughness.cli import main
from roughness.core.errors import InputError
from roughness.dataset.textures import BumpRecipe, bump_texture, standard_texture
from roughness.surface.heightmap import Heightmap
from roughness.surface.printing import PROFILES, FdmProfile, SlaProfile, load_profile, printed, printer_profile
from test_bad_inputs import BASE, _expect_refusal

FDM = PROFILES["fdm-0.4-0.2"]


def _spectral_v(hm: Heightmap, tile: bool = False) -> float:
    from roughness.simulate.config import SimConfig
    from roughness.simulate.spectral.engine import SpectralSimulator

    return SpectralSimulator(SimConfig()).run(hm, None, tile).roughness


def _plate(pillars: list[tuple[int, int, int, float]], n: int = 80, pixel_mm: float = 0.05) -> Heightmap:
    """A flat map with square pillars (row, column, side in pixels, height mm)."""
    h = np.zeros((n, n))
    for i, j, side, height in pillars:
        h[i:i + side, j:j + side] = height
    return Heightmap(h, pixel_mm)


def test_texture_finer_than_the_nozzle_loses_most_of_its_v():
    """Bumps 0.35 mm apart (finer than the 0.45 mm bead of a 0.4 mm nozzle) print nearly flat: measured 0.0079 ->
    0.0004 with the spectral engine; bumps 1.5 mm apart keep most of theirs (the bead only cuts their tips)."""
    fine = bump_texture(BumpRecipe(lambda_mm=0.35, seed=3))
    v_fine, v_fine_printed = _spectral_v(fine), _spectral_v(printed(fine, FDM).heightmap)
    assert v_fine_printed < 0.5 * v_fine, (v_fine, v_fine_printed)
    coarse = standard_texture(1.5, seed=100)
    v_coarse, v_coarse_printed = _spectral_v(coarse), _spectral_v(printed(coarse, FDM).heightmap)
    assert 0.8 * v_coarse < v_coarse_printed < v_coarse, (v_coarse, v_coarse_printed)


def test_fdm_removes_parts_narrower_than_a_bead_and_keeps_wider_ones():
    # heights are whole layers, so quantisation changes nothing: only the bead acts
    hm = _plate([(10, 10, 6, 1.0), (40, 40, 20, 1.0)])  # 0.3 mm and 1.0 mm square pillars
    out = printed(hm, FDM).heightmap.heights
    assert out[10:16, 10:16].max() == 0.0  # narrower than the 0.45 mm line: not printed
    assert out[45:55, 45:55].min() == pytest.approx(1.0)  # the inside of a wide pillar is untouched
    edge = out[50, 40]  # its outermost pixel: the bead's rounded end drops it by up to half a layer
    assert 1.0 - FDM.layer_mm / 2 - 1e-12 <= edge < 1.0
    assert np.all(out <= hm.heights + 1e-12)  # an opening never adds material


def test_fdm_layers_round_to_the_nearest_whole_layer_above_the_lowest_point():
    hm = _plate([(0, 0, 40, 0.29), (40, 0, 40, 0.31)])  # wide terraces: no bead effect inside them
    out = printed(hm, FDM).heightmap.heights
    assert out[20, 20] == pytest.approx(0.2) and out[60, 20] == pytest.approx(0.4)
    assert np.all(out[5:35, 5:35] == out[20, 20]) and np.all(out[45:75, 5:35] == out[60, 20])  # away from edges
    layer = np.ceil(out / 0.2 - 1e-9)  # every pixel: a whole layer, or within half a layer under it (bead ends)
    assert np.all((out > (layer - 0.5) * 0.2 - 1e-12) & (out <= layer * 0.2 + 1e-12))


def test_sla_pixel_grid_and_light_bleed():
    # a 0.1 mm LCD pixel over a 0.025 mm map: heights held over each 4 x 4 block of map pixels
    rng = np.random.default_rng(1)
    hm = Heightmap(rng.random((40, 40)), 0.025)
    out = printed(hm, SlaProfile("coarse-lcd", 0.1, 0.05, 0.0)).heightmap.heights
    blocks = out.reshape(10, 4, 10, 4)
    assert np.all(blocks == blocks[:, :1, :, :1])
    # a bleed of one pixel removes a single-pixel spike (its blurred dose 1/(2 pi) < 1/2), keeps a 10 x 10 block
    hm = _plate([(20, 20, 1, 0.05), (50, 50, 10, 0.05)])
    out = printed(hm, SlaProfile("bleed", 0.05, 0.05, 0.05)).heightmap.heights
    assert out[20, 20] == 0.0 and out[55, 55] == pytest.approx(0.05)


def test_what_the_map_cannot_resolve_is_said_or_refused():
    coarse = Heightmap(np.zeros((40, 40)) + np.eye(40), 0.3)  # a 0.45 mm bead is 1.5 pixels of 0.3 mm
    with pytest.raises(InputError, match="cannot be represented at this resolution") as err:
        printed(coarse, FDM)
    assert err.value.parameter == "printer"
    notes = printed(standard_texture(1.0), PROFILES["msla-35um"]).notes  # 35 um LCD pixels on 50 um map pixels
    assert any("pixel grid has no effect at this resolution" in n for n in notes)
    assert any("prints flat" in n for n in printed(_plate([(0, 0, 5, 0.05)]), FDM).notes)  # 0.05 mm under 0.2 mm


def test_profiles_by_name_and_from_json(tmp_path):
    assert printer_profile("msla-35um") is PROFILES["msla-35um"]
    assert all(p.source and p.source != "custom profile" for p in PROFILES.values())  # each says where it comes from
    path = tmp_path / "mine.json"
    path.write_text(json.dumps({"kind": "fdm", "nozzle_mm": 0.6, "layer_mm": 0.3}))
    mine = printer_profile(str(path))
    assert mine == FdmProfile("mine", 0.6, 0.3, 1.125 * 0.6, 0.049, "custom profile mine.json")
    with pytest.raises(InputError, match="unknown printer 'prusa-xl'") as err:
        printer_profile("prusa-xl")
    assert err.value.parameter == "printer"


BAD_PROFILES = {
    "not JSON": "{kind: fdm",
    "NaN": '{"kind": "fdm", "nozzle_mm": NaN, "layer_mm": 0.2}',
    "Infinity": '{"kind": "sla", "pixel_mm": 0.05, "layer_mm": Infinity, "bleed_mm": 0.02}',
    "huge": '{"kind": "fdm", "nozzle_mm": 0.4, "layer_mm": 1e400}',
    "negative": '{"kind": "sla", "pixel_mm": -0.05, "layer_mm": 0.05, "bleed_mm": 0.02}',
    "a string": '{"kind": "fdm", "nozzle_mm": "0.4", "layer_mm": 0.2}',
    "a boolean": '{"kind": "fdm", "nozzle_mm": true, "layer_mm": 0.2}',
    "layer thicker than the nozzle": '{"kind": "fdm", "nozzle_mm": 0.4, "layer_mm": 0.5}',
    "unknown field": '{"kind": "fdm", "nozzle_mm": 0.4, "layer_mm": 0.2, "speed": 60}',
    "missing field": '{"kind": "sla", "pixel_mm": 0.05, "layer_mm": 0.05}',
    "unknown kind": '{"kind": "sls", "layer_mm": 0.1}',
    "kind not a string": '{"kind": ["fdm"], "nozzle_mm": 0.4, "layer_mm": 0.2}',
    "nested too deep": "[" * 60_000,
    "not UTF-8": b'{"kind": "fdm", "name": "\xff", "nozzle_mm": 0.4, "layer_mm": 0.2}',
    "not an object": "[0.4, 0.2]",
    "empty name": '{"kind": "fdm", "name": "", "nozzle_mm": 0.4, "layer_mm": 0.2}',
}


@pytest.mark.parametrize("case", BAD_PROFILES)
def test_bad_json_profiles_are_refused_with_the_reason(tmp_path, case):
    path, content = tmp_path / "bad.json", BAD_PROFILES[case]
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(InputError, match="printer profile") as err:
        load_profile(path)
    assert err.value.parameter == "printer"


COMMANDS = [("predict",), ("tune",), ("palette",)]


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("case", ["unknown name", "NaN", "negative", "unknown field", "too coarse"])
def test_bad_printer_exits_2_before_any_work(workdir, capsys, command, case):  # noqa: F811 (the fixture)
    """The bad-input matrix for --printer: exit 2, the message names --printer or the problem, no file changes."""
    (workdir / "nan.json").write_text(BAD_PROFILES["NaN"])
    (workdir / "neg.json").write_text(BAD_PROFILES["negative"])
    (workdir / "extra.json").write_text(BAD_PROFILES["unknown field"])
    (workdir / "fine.json").write_text('{"kind": "fdm", "nozzle_mm": 0.06, "layer_mm": 0.02, "line_width_mm": 0.07}')
    printer = {"unknown name": "prusa-xl", "NaN": "nan.json", "negative": "neg.json", "unknown field": "extra.json",
               "too coarse": "fine.json"}[case]  # too coarse: a 0.07 mm bead on 0.05 mm pixels
    _expect_refusal([*command, *BASE[command], "--printer", printer], workdir, capsys,
                    ("--printer", "cannot be represented"))


def test_predict_reports_digital_printed_and_the_difference(tmp_path, capsys):
    path = tmp_path / "s.npy"
    np.save(path, standard_texture(1.0).heights)
    assert main(["predict", str(path), "--pixel-mm", "0.05", "--engine", "spectral", "--printer", "fdm-0.4-0.2",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    diff = out["print_difference"]
    assert out["roughness"] == diff["printed_roughness"] and out["digital"]["roughness"] == diff["digital_roughness"]
    assert diff["printed_roughness"] < diff["digital_roughness"] and diff["difference_jnd"] < 0
    assert out["printer"]["name"] == "fdm-0.4-0.2" and out["print_steps"]
    assert main(["predict", str(path), "--pixel-mm", "0.05", "--engine", "spectral", "--printer", "msla-35um"]) == 0
    text = capsys.readouterr().out
    assert "as printed: V = " in text and "V digital" in text and "JND" in text


def test_tune_judges_the_print_and_saves_the_digital_design(tmp_path, capsys):
    path, out = tmp_path / "s.npy", tmp_path / "tuned.npz"
    np.save(path, standard_texture(1.0).heights)
    code = main(["tune", str(path), "--pixel-mm", "0.05", "--target-lambda", "1.1", "--out", str(out),
                 "--verify", "spectral", "--printer", "fdm-0.4-0.2", "--json", "--quiet"])
    summary = json.loads(capsys.readouterr().out)
    assert code in (0, 1)
    diff = summary["printing"]["differences"]["result"]
    assert diff["printed_roughness"] == summary["achieved_roughness"]  # the target is met by the print
    from roughness.surface.io import load_heightmap

    saved = load_heightmap(out)  # the file is the digital design: its own V is the digital one
    assert _spectral_v(saved) == pytest.approx(diff["digital_roughness"], rel=1e-9)
    assert diff["digital_roughness"] > diff["printed_roughness"]


def test_palette_judges_members_as_printed_and_records_both(tmp_path, capsys):
    folder = tmp_path / "candidates"
    folder.mkdir()
    for lam in (0.625, 1.0, 1.5):
        np.save(folder / f"s{lam}.npy", standard_texture(lam).heights)
    out = tmp_path / "palette"
    code = main(["palette", "--k", "2", "--min-jnd", "1", "--from", str(folder), "--pixel-mm", "0.05",
                 "--out", str(out), "--verify", "spectral", "--printer", "msla-35um", "--quiet"])
    text = capsys.readouterr().out
    assert code == 0 and "judged as printed by msla-35um" in text
    saved = json.loads((out / "palette.json").read_text())
    differences = saved["printing"]["differences"]
    assert saved["printing"]["printer"]["name"] == "msla-35um"
    for member in saved["members"]:  # the members' V are their prints'; the digital V is recorded beside it
        diff = differences[member["name"]]
        assert member["fem_roughness"] == diff["printed_roughness"]
        assert diff["digital_roughness"] > 0 and diff["difference_jnd"] is not None


def test_map_with_a_printer_maps_the_print(tmp_path, capsys, monkeypatch):
    """--map with --printer (or the project's default printer) maps the printed plate: the map is the one of the
    printed heightmap, says so, and differs from the digital map; --printer none maps the digital heightmap."""
    from roughness.maps import predict_map

    hm = standard_texture(1.0)
    path = tmp_path / "s.npy"
    np.save(path, hm.heights)
    args = ["predict", str(path), "--pixel-mm", "0.05", "--engine", "spectral", "--tile", "--step-mm", "4",
            "--json", "--quiet"]

    def mapped(*extra: str) -> tuple[np.ndarray, dict]:
        out = tmp_path / f"m{len(list(tmp_path.glob('m*.npy')))}.npy"
        assert main([*args, "--map", str(out), *extra]) == 0
        return np.load(out), json.loads(capsys.readouterr().out)

    explicit, summary = mapped("--printer", "fdm-0.4-0.2")
    assert summary["printer"]["name"] == "fdm-0.4-0.2" and "mapped as printed by" in summary["notes"][0]
    expected = predict_map(printed(hm, PROFILES["fdm-0.4-0.2"], True).heightmap, "spectral", 4.0, True).map
    np.testing.assert_allclose(explicit, expected.roughness, rtol=1e-9)
    digital, summary = mapped("--printer", "none")
    assert summary["printer"] is None and not np.allclose(digital, explicit, rtol=1e-3)
    monkeypatch.setenv("ROUGHNESS_PRINTER", "fdm-0.4-0.2")  # the project's default printer is not ignored
    default, summary = mapped()
    assert summary["printer"]["name"] == "fdm-0.4-0.2"
    np.testing.assert_allclose(default, explicit, rtol=1e-9)


def test_a_recipe_with_printers_makes_the_printed_twins_of_its_unprinted_samples():
    """print_probability 1 with the same seed: each record is the unprinted recipe's with a printer drawn last, its
    heightmap that one printed; recipes without printers keep their JSON (their datasets resume)."""
    from roughness.dataset.recipe import Recipe, realise, sample_record

    plain = Recipe(name="p", seed=3, families={"grating": 1.0, "dots": 1.0})
    twins = Recipe(name="p", seed=3, families={"grating": 1.0, "dots": 1.0}, print_probability=1.0,
                   printers=["fdm-0.4-0.2", "msla-35um"])
    assert "print" not in plain.to_json() and '"printers"' in twins.to_json()
    for i in range(3):
        a, b = sample_record(plain, i), sample_record(twins, i)
        assert {k: v for k, v in b.items() if k != "printer"} == a and b["printer"] in twins.printers
        np.testing.assert_array_equal(realise(b).heights, printed(realise(a), PROFILES[b["printer"]]).heightmap.heights)
    with pytest.raises(InputError, match="printers must be a list of print profile names"):
        Recipe(print_probability=0.5, printers=["no-such-printer"])
    with pytest.raises(InputError, match="needs printers"):
        Recipe(print_probability=0.5)


@pytest.fixture
def no_default(monkeypatch, tmp_path):
    """No project default printer from the tester's environment or config files."""
    monkeypatch.delenv("ROUGHNESS_PRINTER", raising=False)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    return tmp_path


def test_default_printer_precedence_flag_env_folder_user(no_default, monkeypatch):
    from roughness.surface.printing import choose_printer, chosen_profile

    work, user = no_default / "work", no_default / "config" / "roughness"
    work.mkdir(), user.mkdir(parents=True)
    monkeypatch.chdir(work)
    assert chosen_profile(choose_printer()) is None
    (user / "config.toml").write_text('printer = "fdm-0.4-0.1"\n')
    assert chosen_profile(choose_printer()).name == "fdm-0.4-0.1"
    (work / "roughness.toml").write_text('printer = "sla1s-47um"\n')
    profile = chosen_profile(choose_printer())
    assert profile.name == "sla1s-47um" and "(from roughness.toml)" in profile.describe()
    monkeypatch.setenv("ROUGHNESS_PRINTER", "msla-35um")
    profile = chosen_profile(choose_printer())
    assert profile == PROFILES["msla-35um"] and profile.describe().endswith("(from ROUGHNESS_PRINTER)")
    flagged = chosen_profile(choose_printer("fdm-0.4-0.2"))
    assert flagged is FDM and "(from" not in flagged.describe()
    assert chosen_profile(choose_printer("none")) is None  # --printer none beats every default
    monkeypatch.setenv("ROUGHNESS_PRINTER", "NONE")
    assert chosen_profile(choose_printer()) is None


@pytest.mark.parametrize("text, words", [('printer = 3\n', "printer must be a profile name"),
                                         ('printr = "fdm-0.4-0.2"\n', "unknown key(s) printr"),
                                         ('printer = "fdm\n', "not valid TOML"),
                                         ('printer = "prusa-xl"\n', "from roughness.toml")])
def test_a_bad_config_file_is_refused_naming_it(no_default, monkeypatch, text, words):
    from roughness.surface.printing import choose_printer, chosen_profile

    monkeypatch.chdir(no_default)
    (no_default / "roughness.toml").write_text(text)
    with pytest.raises(InputError, match="roughness.toml") as err:
        chosen_profile(choose_printer())
    assert words in str(err.value) and err.value.parameter == "printer"


def test_a_config_file_profile_path_is_read_from_the_config_folder(no_default, monkeypatch):
    from roughness.surface.printing import choose_printer, chosen_profile

    (no_default / "mine.json").write_text('{"kind": "fdm", "nozzle_mm": 0.6, "layer_mm": 0.3}')
    (no_default / "roughness.toml").write_text('printer = "mine.json"\n')
    sub = no_default / "sub"
    sub.mkdir()
    monkeypatch.chdir(no_default)
    assert chosen_profile(choose_printer()).nozzle_mm == 0.6


def test_homogeneity_judges_the_print_with_the_digital_beside(no_default, capsys):
    path = no_default / "s.npy"
    np.save(path, standard_texture(1.0).heights)
    args = ["homogeneity", str(path), "--pixel-mm", "0.05", "--n", "5"]
    assert main([*args, "--printer", "fdm-0.4-0.2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["printing"]["printer"]["name"] == "fdm-0.4-0.2"
    assert out["mean_roughness"] < out["digital"]["mean_roughness"]  # the 0.45 mm line cuts the caps
    assert main([*args, "--printer", "fdm-0.4-0.2"]) == 0
    text = capsys.readouterr().out
    assert "as printed: HOMOGENEOUS" in text and "digital design: HOMOGENEOUS" in text


def test_jnd_between_prints_names_a_default_printer_and_none_switches_it_off(no_default, monkeypatch, capsys):
    a, b = no_default / "a.npy", no_default / "b.npy"
    np.save(a, standard_texture(1.0).heights)
    np.save(b, standard_texture(0.625).heights)
    monkeypatch.setenv("ROUGHNESS_PRINTER", "fdm-0.4-0.2")
    args = ["jnd", str(a), str(b), "--pixel-mm", "0.05", "--engine", "spectral"]
    assert main([*args, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["printer"]["chosen_by"] == "ROUGHNESS_PRINTER"
    assert out["a"]["roughness"] < out["digital"]["a"]["roughness"] and out["jnd"] != out["digital"]["jnd"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "as printed: V = " in text and "(from ROUGHNESS_PRINTER)" in text and "digital distance" in text
    assert main([*args, "--printer", "none"]) == 0
    text = capsys.readouterr().out
    assert "printed" not in text and "printer" not in text


def test_api_homogeneity_takes_a_printer(no_default):
    import roughness

    result = roughness.homogeneity(standard_texture(1.0), n=4, printer="fdm-0.4-0.2")
    assert result.mean_roughness < result.digital.mean_roughness  # the print's, the digital one beside it
    assert result.print_result.profile is FDM and result.digital.digital is None
    assert roughness.homogeneity(standard_texture(1.0), n=4).digital is None
    with pytest.raises(InputError) as err:
        roughness.homogeneity(standard_texture(1.0), n=4, printer=3)
    assert err.value.parameter == "printer"
