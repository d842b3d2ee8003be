"""The Object page through NiceGUI's test client (no browser): open a mesh into the 3D view, preview it textured,
map its feel (legend and table as the command prints them), tune, and download the textured mesh."""
from __future__ import annotations

import io
import math
import re
from importlib import resources

import pytest
import trimesh
from nicegui import ui

from roughness.studio.pages.object import example_path

pytestmark = pytest.mark.anyio
JOB_RETRIES = 600  # should_see waits 0.1 s a try: a job (a fresh process, then the library) within a minute


def field(user, kind, label: str):
    """The one element of ``kind`` whose label contains ``label``."""
    [element] = [e for e in user.find(kind).elements if label in (e.props.get("label") or "")]
    return element


def views(user) -> list[str]:
    """The addresses of the glTF files in the 3D view."""
    [scene] = user.find(ui.scene).elements
    return [obj.args[0] for obj in scene.objects.values() if type(obj).__name__ == "Gltf"]


async def open_example(user) -> None:
    await user.open("/object")
    user.find("Open the example knob").click()
    await user.should_see("knob.stl: 128 triangles, 24 x 24 x 24 mm")


async def test_example_opens_into_the_3d_view(studio):
    await open_example(studio.user)
    [address] = views(studio.user)
    response = await studio.http.get(address)
    shown = trimesh.load(io.BytesIO(response.content), file_type="glb", force="mesh")
    assert len(shown.faces) == 128 and shown.is_watertight
    await studio.user.should_see("The 3D view shows the object as read, untextured.")


async def test_preview_then_feel_map_with_legend_and_the_commands_table(studio):
    from roughness.cli.object_feel import feel_lines
    from roughness.dataset.textures import named_texture
    from roughness.objects.feel import feel_map
    from roughness.objects.layout import make_mapping
    from roughness.objects.meshes import read_mesh

    user = studio.user
    await open_example(user)
    user.find("Preview the textured object").click()
    await user.should_see("preview: textured 128 of 128 faces with triangles of at most 1 mm", retries=JOB_RETRIES)
    field(user, ui.select, "Engine").set_value("surrogate")
    user.find("Map the feel").click()
    await user.should_see("Colours: JND from standard-1.0 (positive: rougher)", retries=JOB_RETRIES)
    await user.should_see("light grey untextured, dark grey refused")
    mesh = read_mesh(example_path()).mesh
    texture = named_texture("standard-1.0")
    expected = feel_map(mesh, make_mapping("triplanar", texture, mesh), {"all": mesh.faces[:, 0] >= 0}, None,
                        "surrogate", reference="standard-1.0")
    for line in feel_lines(expected, "knob.stl")[1:]:  # the first line holds the seconds it took
        await user.should_see(line)
    assert len(views(user)) == 1  # the feel map replaced the preview


def cli_feel_lines(*options: str) -> list[str]:
    """What `roughness object feel knob.stl` prints (the example knob, named as the page names it) with
    ``options``."""
    import subprocess
    import sys

    with resources.as_file(example_path()) as knob:
        out = subprocess.run([sys.executable, "-m", "roughness.cli", "object", "feel", knob.name, "--quiet",
                              *options], cwd=knob.parent, capture_output=True, text=True, check=True).stdout
    return out.splitlines()


async def test_a_printer_maps_the_printed_object_as_the_command_does(studio):
    user = studio.user
    await open_example(user)
    field(user, ui.select, "Printer profile").set_value("fdm-0.4-0.2")
    field(user, ui.select, "Engine").set_value("surrogate")
    user.find("Map the feel").click()
    await user.should_see("The 3D view shows the feel map on the object as printed by fdm-0.4-0.2",
                          retries=JOB_RETRIES)
    command = cli_feel_lines("--texture", "standard-1.0", "--engine", "surrogate", "--reference", "standard-1.0",
                             "--printer", "fdm-0.4-0.2")
    assert command[0].startswith("as printed (fdm-0.4-0.2): knob.stl: ")
    await user.should_see(command[0].split("; ")[0])  # the rest of the first line holds the seconds it took
    for line in command[1:]:  # the table of the printed object, then each region as printed beside digital
        await user.should_see(line.strip())
    [beside] = [line for line in command if line.strip().startswith("all: as printed (fdm-0.4-0.2) V ")]
    (printed, printed_u), (digital, digital_u) = [tuple(map(float, m)) for m in
                                                  re.findall(r"V (\d\.\d+) ± (\d\.\d+)", beside)]
    assert abs(printed - digital) > math.hypot(printed_u, digital_u)  # FDM's 0.2 mm layers change how it feels


async def test_a_printer_sets_the_full_resolution_edge_and_reports_the_print(studio):
    from roughness.cli.object_printing import texture_print
    from roughness.dataset.textures import named_texture
    from roughness.objects.print_plan import printer_edge
    from roughness.surface.printing import PROFILES

    user = studio.user
    await open_example(user)
    user.find("Estimate").click()
    digital = math.sqrt(2) * named_texture("standard-1.0").pixel_mm  # the default without a printer
    await user.should_see(f"full resolution, edges of {digital:.3g} mm: expected: about ")
    field(user, ui.select, "Printer profile").set_value("fdm-0.4-0.2")
    user.find("Estimate").click()
    edge = printer_edge(PROFILES["fdm-0.4-0.2"], named_texture("standard-1.0").pixel_mm)  # triplanar: its own pixel
    assert edge.edge_mm > 2 * digital  # half the 0.45 mm line: the printer's bound, not the texture's
    await user.should_see(f"full resolution, edges of {edge.edge_mm:.3g} mm: expected: about ")
    await user.should_see(edge.note())
    [plan] = [e.text for e in user.find(ui.label).elements if e.text.startswith("full resolution, edges of")]
    estimate = int(re.search(r"about ([\d,]+) triangles", plan)[1].replace(",", ""))
    user.find("Make the full-resolution mesh").click()
    await user.should_see("Download knob-textured-1.stl", retries=JOB_RETRIES)
    for line in texture_print(named_texture("standard-1.0"), PROFILES["fdm-0.4-0.2"], 0.05).lines():
        await user.should_see(line.strip())
    [link] = [e for e in user.find(ui.link).elements if "knob-textured-1.stl" in e.text]
    triangles = int(re.search(r"\(([\d,]+) triangles", link.text)[1].replace(",", ""))
    assert abs(triangles / estimate - 1) < 0.1  # textured at the printer's edge (the estimate: a sample's)


async def test_region_errors_are_the_commands_messages(studio):
    user = studio.user
    await open_example(user)
    field(user, ui.select, "Region kind").set_value("cone")
    field(user, ui.input, "Region parameters").set_value("0,0,1")
    user.find("Preview the textured object").click()
    await user.should_see("error: ")
    field(user, ui.input, "Region parameters").set_value("0,0,-1,10")  # the bottom: no textured wall left
    field(user, ui.select, "Region kind").set_value("box")
    field(user, ui.input, "Region parameters").set_value("100,100,100,101,101,101")
    user.find("Preview the textured object").click()
    await user.should_see("selects no face of the mesh")


async def test_clicking_the_object_picks_faces(studio):
    user = studio.user
    await open_example(user)
    field(user, ui.select, "Region kind").set_value("faces")
    mesh = trimesh.load(str(example_path()))
    top = int(mesh.face_normals[:, 2].argmax())
    centre = mesh.triangles_center[top]
    [scene] = user.find(ui.scene).elements
    scene._handle_click(type("Event", (), {"args": {  # the arguments NiceGUI's scene.js sends for a click
        "click_type": "click", "button": 0, "alt_key": False, "ctrl_key": False, "meta_key": False,
        "shift_key": False, "hits": [{"object_id": "x", "object_name": "", "point": dict(zip("xyz", centre))}]}})())
    await user.should_see(f"face {top} added to the region: 1 face(s) picked")
    assert field(user, ui.input, "Region parameters").value == str(top)


async def test_full_resolution_estimate_then_a_watertight_download(studio):
    user = studio.user
    await open_example(user)
    field(user, ui.number, "Edge, mm").set_value(1.5)
    user.find("Estimate").click()
    await user.should_see("full resolution, edges of 1.5 mm: expected: about ")
    field(user, ui.select, "Format").set_value("3MF")
    user.find("Make the full-resolution mesh").click()
    await user.should_see("Download knob-textured-1.3mf", retries=JOB_RETRIES)
    [link] = [e for e in user.find(ui.link).elements if "knob-textured-1.3mf" in e.text]
    response = await studio.http.get(link.props["href"])
    mesh = trimesh.load(io.BytesIO(response.content), file_type="3mf", force="mesh")
    assert mesh.is_watertight and mesh.is_volume
    assert f"({len(mesh.faces):,} triangles" in link.text


async def test_tune_on_the_object_reaches_the_target_and_is_used_next(studio):
    user = studio.user
    await open_example(user)
    field(user, ui.select, "Mapping").set_value("cylinder")
    field(user, ui.select, "Region kind").set_value("angle")
    field(user, ui.input, "Region parameters").set_value("0,0,1,45,135")
    field(user, ui.number, "Target equivalent wavelength").set_value(1.2)
    user.find(kind=ui.button, content="Tune").click()
    await user.should_see("target lambda 1.200 mm", retries=JOB_RETRIES)
    await user.should_see("JND from the target (reached within 0.1 JND")
    await user.should_see("now use standard-1.0 tuned (height x ")


async def test_a_mesh_in_metres_is_refused_until_its_units_are_confirmed(studio, tmp_path):
    from roughness.core.errors import InputError
    from roughness.objects.meshes import read_mesh

    user = studio.user
    await user.open("/object")
    knob = trimesh.load(str(example_path()))
    knob.apply_scale(0.001)  # exported in metres: 24 mm reads as 0.024 mm
    data = knob.export(file_type="stl")
    (tmp_path / "knob-m.stl").write_bytes(data)
    with pytest.raises(InputError) as refused:
        read_mesh(tmp_path / "knob-m.stl")
    [upload] = user.find(ui.upload).elements
    await upload.handle_uploads([ui.upload.SmallFileUpload("knob-m.stl", "model/stl", data)])
    message = str(refused.value).split(": ", 1)[1]  # after the file's path, which differs
    await user.should_see(message.replace("pass units_ok", "pass --units-ok"))
    user.find(ui.checkbox).click()
    await user.should_see("knob-m.stl: 128 triangles, 0.024 x 0.024 x 0.024 mm")


async def test_a_preview_too_fine_to_stay_interactive_is_refused_before_it_starts(studio):
    user = studio.user
    await open_example(user)
    field(user, ui.number, "Preview edge").set_value(0.1)  # about 1.7 million triangles on the knob
    user.find("Preview the textured object").click()
    await user.should_see("above the preview's 300,000: give a larger preview edge")
    await user.should_not_see("preview: starting")  # no job started
