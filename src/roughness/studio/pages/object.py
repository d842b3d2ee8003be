"""The Object page: a mesh in an orbit/zoom 3D view, a texture laid on it (mapping, region), a coarse textured
preview, the feel map coloured on the object with its legend and per-region table, object tune, and the textured
mesh at full resolution (its size estimated before it starts) as STL or 3MF.

Everything comes from the library as ``roughness object`` uses it: ``objects.meshes.read_mesh`` reads (with its
checks), ``objects.regions`` selects faces (the command's ``--region`` kinds; faces also by clicking the view),
``objects.layout.make_mapping`` lays the texture, ``objects.texturing.texture_mesh`` textures,
``objects.print_plan`` estimates, ``objects.feel.feel_map`` maps the feel (``feel_figure.feel_colours`` colours it,
``cli.object_feel.map_lines`` words it), ``objects.tuning.tune_on_object`` tunes; ``studio.object_printer`` adds
a printer (``--printer``). The slow steps are background jobs; the 3D view shows glTF files from the tab's session
folder (three.js, served by NiceGUI: offline).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path

import numpy as np
from nicegui import events, ui

from roughness.core.errors import InputError
from roughness.objects.meshes import Written
from roughness.objects.regions import KINDS, Region, parse_region
from roughness.objects.tuning import ObjectTuneResult
from roughness.studio.jobs import Report, cli_flags
from roughness.surface.heightmap import Heightmap
from roughness.surface.printing import PrintProfile

from ..job_panel import JobPanel
from ..object_printer import ObjectFeel, print_lines, printed_feel
from ..printer_choice import PrinterChoice
from ..sessions import Session
from ..uploads import MAX_UPLOAD_BYTES, upload_path

PATH = "/object"
TITLE = "Object"
SUMMARY = "put a texture on a 3D model, see where it feels how rough, tune it, download the textured mesh"
EXAMPLE = "knob.stl"
EXAMPLE_TEXT = "a knob: a 24 mm cylinder, 24 mm tall, 128 triangles"
PREVIEW_EDGE_MM = 1.0
"""Longest edge (mm) of the preview's textured triangles: coarse, so the preview stays quick."""
PREVIEW_MAX_TRIANGLES = 300_000
"""The most triangles a preview may have (estimated before it starts): more is for the full-resolution mesh."""
REGION_PARAMETERS = {"all": "", "cone": "AX,AY,AZ,DEG, e.g. 0,0,1,30 (the top)",
                     "angle": "AX,AY,AZ,MIN,MAX, e.g. 0,0,1,45,135 (the walls)",
                     "box": "X0,Y0,Z0,X1,Y1,Z1 (mm)", "colour": "R,G,B[,TOL] (0-255)",
                     "faces": "click the object in the view, or type face numbers: 0,3,10-20"}
"""What each region kind (``--region KIND:...``) takes after its colon."""
COLOUR_BY = {"V": "roughness", "JND from the reference": "jnd"}
NO_REFERENCE = "none"
SCALE_WORDS = {"viridis": "dark purple (smoothest) through green to yellow (roughest)",
               "coolwarm": "blue (smoother than the reference) through white (as rough) to red (rougher)"}


def example_path():
    """The bundled example mesh (``EXAMPLE_TEXT``)."""
    return resources.files("roughness.studio") / "example" / EXAMPLE


@dataclass(frozen=True)
class MeshFile:
    """A mesh file of the session and whether its units are confirmed (``--units-ok``); jobs read it again."""

    path: str
    units_ok: bool = False

    def read(self):
        """The ``ReadMesh`` (``roughness.objects.meshes.read_mesh``: the command's checks and notes)."""
        from roughness.objects.meshes import read_mesh

        return read_mesh(self.path, units_ok=self.units_ok)


@dataclass(frozen=True)
class Lay:
    """How the texture lies on the object: the texture (its name, heightmap), the mapping and the region (the
    ``--region`` text; ``faces:`` takes face numbers here, clicked or typed, where the command takes a file)."""

    texture_name: str
    texture: Heightmap
    mapping: str = "triplanar"
    region: str = "all"

    def parsed_region(self) -> Region:
        """The region (``parse_region``; clicked or typed face numbers as a ``faces`` region)."""
        kind, _, text = self.region.partition(":")
        return Region("faces", ids=_face_numbers(text)) if kind == "faces" else parse_region(self.region)

    def on(self, mesh):
        """The region, its faces (bool per face; InputError if none) and the mapping of the texture on them."""
        from roughness.objects.layout import make_mapping

        region = self.parsed_region()
        faces = np.asarray(region.faces(mesh), dtype=bool)
        if not faces.any():
            raise InputError(f"region {self.region!r} selects no face of the mesh", parameter="region")
        return region, faces, make_mapping(self.mapping, self.texture, mesh, faces)


def _face_numbers(text: str) -> tuple[int, ...]:
    """Face numbers typed as ``0,3,10-20`` (the format of ``--region faces:FILE``)."""
    ids: list[int] = []
    for word in filter(None, (w.strip() for w in text.replace(" ", ",").split(","))):
        low, dash, high = word.partition("-")
        if not (low.isdigit() and (not dash or high.isdigit())):
            raise InputError(f"face numbers are whole numbers from 0 and ranges A-B, got {word!r}", "region")
        ids += range(int(low), int(high if dash else low) + 1)
    if not ids:
        raise InputError("a faces region needs face numbers: click the object or type them", "region")
    return tuple(ids)


@dataclass(frozen=True)
class Preview:
    """The coarse textured object: its glTF (bytes) and what texturing did, in words."""

    glb: bytes
    lines: tuple[str, ...]


def preview(report: Report, mesh_file: MeshFile, lay: Lay, edge_mm: float) -> Preview:
    """The job: the object textured with triangles of at most ``edge_mm`` (mm), as glTF."""
    from roughness.objects.texturing import texture_mesh

    mesh = mesh_file.read().mesh
    region, _, mapping = lay.on(mesh)
    result = texture_mesh(mesh, mapping, region, edge_mm, meter=_meter(report))
    lines = (f"preview: textured {result.textured_faces_in:,} of {result.triangles_in:,} faces with triangles of at "
             f"most {edge_mm:g} mm ({result.triangles_out:,} triangles; detail finer than that is not shown); "
             f"heights up to {result.max_height_mm:.3f} mm", *(f"note: {n}" for n in result.notes))
    return Preview(_mesh_glb(result.mesh), lines)


def feel(report: Report, mesh_file: MeshFile, lay: Lay, engine: str, reference: str | None,
         printer: PrintProfile | None = None) -> ObjectFeel:
    """The job: the feel map of the object with the texture (``roughness.objects.feel.feel_map``, curvature by the
    measured correction), JNDs from ``reference`` (a texture name) if given; with ``printer``, of the printed
    object, the digital one beside it (``object_printer.printed_feel``)."""
    from roughness.objects.feel import feel_map

    mesh = mesh_file.read().mesh
    _, faces, mapping = lay.on(mesh)
    share = 1.0 if printer is None else 0.5  # with a printer the object is mapped twice

    def judge(laid, start: float, what: str):
        def progress(done: int, total: int) -> None:
            report(start + share * done / total, f"{what}: {done}/{total} footprints judged")

        return feel_map(mesh, laid, {lay.region: faces}, None, engine, "correction", reference, progress=progress)

    if printer is None:
        return ObjectFeel(judge(mapping, 0.0, "the object"))
    return printed_feel(lay.texture, mapping, lambda hm: replace(lay, texture=hm).on(mesh)[2], printer, judge)


def tune(report: Report, mesh_file: MeshFile, lay: Lay, target_lambda_mm: float, by: str) -> ObjectTuneResult:
    """The job: the texture scaled ``by`` height or lateral size until the object's curved parts feel like
    ``target_lambda_mm`` (``roughness.objects.tuning.tune_on_object``, the spectral engine)."""
    from roughness.objects.layout import make_mapping
    from roughness.objects.tuning import tune_on_object

    mesh = mesh_file.read().mesh
    _, faces, _ = lay.on(mesh)
    return tune_on_object(mesh, lay.texture, lambda hm: make_mapping(lay.mapping, hm, mesh, faces), target_lambda_mm,
                          {lay.region: faces}, by, progress=lambda line: report(None, line))


@dataclass(frozen=True)
class Exported:
    """The full-resolution mesh written, and with a printer the texture's V as printed beside digital (lines)."""

    written: Written
    printing: tuple[str, ...] = ()


def export(report: Report, mesh_file: MeshFile, lay: Lay, edge_mm: float | None, out: str,
           printer: PrintProfile | None = None) -> Exported:
    """The job: the object textured at full resolution (``edge_mm``; None: from ``printer``, else sqrt(2) x the
    texture's pixel on the surface, as ``object texture``), written to ``out`` (.stl or .3mf, a new file; checked a
    closed solid first); the mesh is the digital design."""
    from roughness.objects.meshes import write_mesh
    from roughness.objects.print_plan import chosen_edge
    from roughness.objects.texturing import texture_mesh

    mesh = mesh_file.read().mesh
    region, _, mapping = lay.on(mesh)
    printing = print_lines(lay.texture, printer, mapping.pixel_mm)  # a pixel too coarse for it refused first
    meter = _meter(report)
    result = texture_mesh(mesh, mapping, region, chosen_edge(edge_mm, printer, mapping.pixel_mm)[0], meter=meter)
    return Exported(write_mesh(result.mesh, out, overwrite=False, progress=meter(f"writing {Path(out).name}")),
                    printing)


def _meter(report: Report):
    """texture_mesh's ``meter``: each step's fraction done, reported with its name."""
    return lambda step: (lambda done: report(done, step))


def _glb(vertices: np.ndarray, faces: np.ndarray, vertex_colours: np.ndarray | None = None) -> bytes:
    """A mesh (mm) as binary glTF with normals and a matte, non-metallic material (glTF's default is a metal, which
    three.js shows black without an environment); ``vertex_colours`` (RGBA 0..255) paint it."""
    import trimesh

    shown = trimesh.Trimesh(vertices, faces, process=False)
    shown.visual = trimesh.visual.TextureVisuals(
        material=trimesh.visual.material.PBRMaterial(metallicFactor=0.0, roughnessFactor=0.8))
    if vertex_colours is not None:
        shown.visual.vertex_attributes["color"] = vertex_colours
    return shown.export(file_type="glb", include_normals=True)


def _mesh_glb(mesh) -> bytes:
    """A trimesh as glTF (``_glb``)."""
    return _glb(np.asarray(mesh.vertices), np.asarray(mesh.faces))


def _painted_glb(triangles: np.ndarray, colours: np.ndarray) -> bytes:
    """Triangles (n, 3, 3) mm, each painted its colour (n, 4 RGBA 0..1), as glTF (``_glb``)."""
    corners = np.repeat(np.rint(np.asarray(colours) * 255).astype(np.uint8), 3, axis=0)
    return _glb(triangles.reshape(-1, 3), np.arange(3 * len(triangles)).reshape(-1, 3), corners)


def plan_of(mesh, lay: Lay, edge_mm: float | None, printer: PrintProfile | None = None):
    """The ``MeshPlan`` of texturing ``mesh`` as ``lay`` says with edges of ``edge_mm`` (None: the command's default,
    from ``printer`` if given, ``print_plan.chosen_edge``) and the default's rule (or None); InputError if it would
    pass the mesh limit (with the coarsest edge that fits)."""
    from roughness.objects.print_plan import chosen_edge, mesh_plan, require_within

    _, faces, mapping = lay.on(mesh)
    edge, rule = chosen_edge(edge_mm, printer, mapping.pixel_mm)
    vertices, triangles = np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces)
    plan = mesh_plan(vertices, triangles, faces, edge)
    require_within(plan, vertices, triangles, faces)
    return plan, rule


def plan_line(mesh, lay: Lay, edge_mm: float | None, printer: PrintProfile | None = None) -> tuple[str, str | None]:
    """The full-resolution mesh's estimate in words (``objects.print_plan``; the printer's edge rule if it set the
    edge) and its slicer warning (or None)."""
    plan, rule = plan_of(mesh, lay, edge_mm, printer)
    return f"full resolution, edges of {plan.edge_mm:.3g} mm: {plan.line()}" + (f"; {rule}" if rule else ""), \
        plan.warning()


def legend_text(drawn, by: str) -> str:
    """The colour legend in words: what the colours mean and the values at their ends."""
    norm = drawn.norm
    words = SCALE_WORDS.get(drawn.cmap.name, drawn.cmap.name)
    ends = (f"from {norm.vmin:+.2f} to {norm.vmax:+.2f} JND, 0 at the reference" if by == "jnd" else
            f"from V {norm.vmin:.4f} to V {norm.vmax:.4f}")
    return (f"Colours: {drawn.label}, {ends}: {words}; light grey untextured, dark grey refused (no V there)"
            + drawn.note)


def tune_lines(result: ObjectTuneResult) -> list[str]:
    """An object tune in words: the target, the factor found, the object's curved parts against the target."""
    o, flat = result.on_object, result.flat
    where = "curved parts" if o.curved else "judged parts (none curved)"
    judged = np.isfinite(result.feel.uncertainty)  # as `roughness object tune` gives it: the footprints' median
    spread = f" (± {np.median(result.feel.uncertainty[judged]):.4f} per footprint, median)" if judged.any() else ""
    return [f"target lambda {result.target_lambda_mm:.3f} mm (V {result.target_roughness:.4f}, spectral scale)",
            f"tuned: {flat.by} x {flat.factor:.4g}; as a flat tile lambda {flat.achieved.equivalent_lambda_mm:.3f} mm "
            f"({result.flat_jnd_error:+.2f} JND from the target)",
            f"on the object's {where}: median V {o.roughness:.4f}{spread} over {o.points} footprints, lambda {o.lambda_mm:.3f} "
            f"mm, {o.jnd_error:+.2f} JND from the target ({'reached' if result.reached else 'NOT reached'} within "
            f"{result.tolerance_jnd:g} JND, {result.rounds} round(s))", *(f"note: {n}" for n in result.notes)]


class ObjectPage:
    """The page's controls and results for one session."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.mesh_file: MeshFile | None = None
        self.refused: Path | None = None  # an upload refused, read again if its units are confirmed
        self.mesh = None  # the trimesh read from it
        self.lay: Lay | None = None
        self.shown = 0  # glTF files shown so far: each gets a new name
        self.exports = 0
        self._mesh_card()
        self._lay_card()
        self._feel_card()
        self._tune_card()
        self._export_card()

    def _mesh_card(self) -> None:
        with ui.card().classes("w-full"):
            ui.label("1. The object").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("items-end gap-4"):
                ui.button("Open the example knob", on_click=self.open_example)
                ui.upload(label=f"Mesh: STL, OBJ, PLY or 3MF (up to {MAX_UPLOAD_BYTES // 2**20} MiB)",
                          auto_upload=True, max_file_size=MAX_UPLOAD_BYTES,
                          on_upload=self.on_upload).props('accept=".stl,.obj,.ply,.3mf"')
                self.units_ok = ui.checkbox("The file's size is right as read (--units-ok)",
                                            on_change=self.retry_units)
            self.error = ui.label("").classes("text-red-10").props('role="alert"')
            self.mesh_text = ui.column().classes("gap-0").props('role="status" aria-live="polite"')
            self.view_text = ui.label("").classes("text-sm")
            with ui.scene(width=640, height=420, on_click=self.on_click).props(
                    'role="img" aria-label="3D view of the object: drag to orbit, scroll to zoom; what it shows is said above it"') as self.scene:
                pass
            self.picked_text = ui.label("").props('aria-live="polite"')

    def _lay_card(self) -> None:
        from roughness.dataset.textures import texture_names
        from roughness.objects.layout import MAPPINGS

        with ui.card().classes("w-full"):
            ui.label("2. Texture, mapping and region").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("items-end gap-4"):
                self.texture = ui.select(texture_names(), value="standard-1.0", label="Texture (--texture)").classes("w-48")
                self.mapping = ui.select(list(MAPPINGS), value="triplanar", label="Mapping (--mapping)").classes("w-48")
                self.region_kind = ui.select(list(KINDS), value="all", label="Region kind (--region)",
                                             on_change=self._region_hint).classes("w-48")
                self.region_text = ui.input("Region parameters", placeholder="").classes("w-96")
                self._region_hint()
            with ui.row().classes("items-end gap-4"):
                self.printer = PrinterChoice()
                ui.label("with a printer, the feel map is of the printed object (the digital one beside it in its "
                         "table) and the full-resolution mesh's edge defaults to what the printer reproduces; the "
                         "preview, the tune and the mesh written are the digital design").classes("text-sm w-[36rem]")
            with ui.row().classes("items-end gap-4"):
                self.preview_edge = ui.number("Preview edge, mm", value=PREVIEW_EDGE_MM, min=0.05, max=20, step=0.25,
                                              format="%.3g").classes("w-40")
                ui.button("Preview the textured object", on_click=self.start_preview)
            self.preview_job = JobPanel("the preview")
            self.preview_text = ui.column().classes("gap-0").props('role="status" aria-live="polite"')

    def _feel_card(self) -> None:
        from roughness.dataset.textures import texture_names
        from roughness.objects.feel import ENGINES

        with ui.card().classes("w-full"):
            ui.label("3. How it feels").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("items-end gap-4"):
                self.engine = ui.select(list(ENGINES), value="spectral", label="Engine (--engine)").classes("w-48")
                self.reference = ui.select([NO_REFERENCE, *texture_names()], value="standard-1.0",
                                           label="JND from (--reference)").classes("w-48")
                self.colour_by = ui.select(list(COLOUR_BY), value="JND from the reference",
                                           label="Colour by (--colour-by)").classes("w-56")
                ui.button("Map the feel", on_click=self.start_feel)
            self.feel_job = JobPanel("the feel map")
            self.legend = ui.row().classes("items-center gap-2")
            self.legend_text = ui.label("").props('role="status" aria-live="polite"')
            self.feel_text = ui.column().classes("gap-0 font-mono text-xs whitespace-pre")

    def _tune_card(self) -> None:
        with ui.card().classes("w-full"):
            ui.label("4. Tune the texture on the object").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("items-end gap-4"):
                self.target = ui.number("Target equivalent wavelength, mm (--target-lambda)", value=1.0, min=0.1, max=5,
                                        step=0.05, format="%.4g").classes("w-72")
                self.by = ui.select(["height", "lateral"], value="height", label="Scale by (--by)").classes("w-40")
                ui.button("Tune", on_click=self.start_tune)
            self.tune_job = JobPanel("the tune")
            self.tune_text = ui.column().classes("gap-0").props('role="status" aria-live="polite"')

    def _export_card(self) -> None:
        with ui.card().classes("w-full"):
            ui.label("5. The textured mesh").classes("text-lg").props('role="heading" aria-level="2"')
            with ui.row().classes("items-end gap-4"):
                self.export_edge = ui.number("Edge, mm (--edge-mm; empty: the printer's, else sqrt(2) x the texture's pixel)",
                                             min=0.01, max=20, format="%.3g").classes("w-[34rem]")
                self.export_format = ui.select(["STL", "3MF"], value="STL", label="Format").classes("w-32")
                ui.button("Estimate", on_click=self.estimate)
                ui.button("Make the full-resolution mesh", on_click=self.start_export)
            self.plan_text = ui.label("").props('role="status" aria-live="polite"')
            self.export_job = JobPanel("the full-resolution mesh")
            self.downloads = ui.column().classes("gap-1")

    # the object

    def open_example(self) -> None:
        with resources.as_file(example_path()) as path:  # the installed package's file (read, never written)
            self._open(MeshFile(str(path)))

    async def on_upload(self, event: events.UploadEventArguments) -> None:
        try:
            path = upload_path(self.session, event.file.name, event.file.size())
        except InputError as err:
            self.show_error(f"error: {err}")
            return
        await event.file.save(path)
        self._open(MeshFile(str(path), bool(self.units_ok.value)))

    def retry_units(self) -> None:
        """The units confirmed (or not) after an upload was refused: read it again."""
        if self.refused is not None:
            self._open(MeshFile(str(self.refused), bool(self.units_ok.value)))

    def _open(self, mesh_file: MeshFile) -> None:
        try:
            read = mesh_file.read()
        except InputError as err:
            from roughness.cli.common import error_message

            self.refused = Path(mesh_file.path)
            self.show_error(f"error: {error_message(err, {'units_ok': '--units-ok'})}")  # the checkbox's flag
            return
        self.refused = None
        self.error.set_text("")
        self.mesh_file, self.mesh, self.lay = mesh_file, read.mesh, None
        size = read.mesh.extents
        self.mesh_text.clear()
        with self.mesh_text:
            for line in [f"{Path(read.path).name}: {read.triangles:,} triangles, {size[0]:.3g} x {size[1]:.3g} x "
                         f"{size[2]:.3g} mm, area {read.mesh.area:.3g} mm^2", *(f"note: {n}" for n in read.notes)]:
                ui.label(line)
        self.show(_mesh_glb(read.mesh), "the object as read, untextured")
        lo, hi = read.mesh.bounds
        centre, reach = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
        self.scene.move_camera(*(centre + reach * np.array([0.55, -0.75, 0.5])), *centre, duration=0)

    def show(self, glb: bytes, what: str, painted: bool = False) -> None:
        """Show a glTF in the 3D view (from the session folder), and say in words what it shows; ``painted``: in
        its own vertex colours (else light grey)."""
        self.shown += 1
        name = f"view-{self.shown}.glb"
        self.session.path(name).write_bytes(glb)
        self.scene.clear()
        with self.scene:
            ui.scene.gltf(self.session.download_url(name)).material(None if painted else "#c8c8c8")
        self.view_text.set_text(f"The 3D view shows {what}.")

    def on_click(self, event: events.SceneClickEventArguments) -> None:
        """A click on the object adds the face under it to a faces region (or removes it)."""
        hits = event.hits  # the view holds the object only
        if self.mesh is None or not hits or self.region_kind.value != "faces":
            return
        _, _, [face] = self.mesh.nearest.on_surface([[hits[0].x, hits[0].y, hits[0].z]])
        picked = set(_face_numbers(self.region_text.value or "")) if self.region_text.value else set()
        picked ^= {int(face)}
        self.region_text.set_value(",".join(str(i) for i in sorted(picked)))
        self.picked_text.set_text(f"face {int(face)} {'added to' if int(face) in picked else 'removed from'} the "
                                  f"region: {len(picked)} face(s) picked")

    def _region_hint(self) -> None:
        self.region_text.props(f'placeholder="{REGION_PARAMETERS[self.region_kind.value]}"')
        self.region_text.set_visibility(self.region_kind.value != "all")

    def show_error(self, text: str) -> None:
        self.error.set_text(text)

    def current_lay(self) -> Lay:
        """The texture, mapping and region as chosen (the tuned texture if the last tune made one for this
        texture); InputError without an object."""
        from roughness.dataset.textures import named_texture

        if self.mesh_file is None:
            raise InputError("open an object first")
        kind, text = self.region_kind.value, (self.region_text.value or "").strip()
        region = kind if kind == "all" else f"{kind}:{text}"
        tuned = self.lay is not None and self.lay.texture_name.startswith(f"{self.texture.value} tuned")
        if tuned:
            return replace(self.lay, mapping=self.mapping.value, region=region)
        return Lay(self.texture.value, named_texture(self.texture.value), self.mapping.value, region)

    def _start(self, panel: JobPanel, name: str, function, *args, on_done, command: str | None = None) -> Lay | None:
        try:
            lay = self.current_lay()
            lay.on(self.mesh)  # the region and mapping checked before a job starts
        except InputError as err:
            self.show_error(f"error: {err}")
            return None
        self.error.set_text("")
        self.lay = lay
        panel.start(name, function, self.mesh_file, lay, *args, on_done=on_done,  # errors worded as `roughness command`'s
                    flags=cli_flags(command) if command else None)
        return lay

    # preview, feel, tune, export

    def start_preview(self) -> None:
        edge = self.preview_edge.value
        if edge is None or edge <= 0:
            self.show_error("error: the preview edge is a positive length in mm")
            return
        try:
            plan, _ = plan_of(self.mesh, self.current_lay(), float(edge))
        except InputError as err:
            self.show_error(f"error: {err}")
            return
        if plan.triangles > PREVIEW_MAX_TRIANGLES:
            self.show_error(f"error: a preview with edges of {edge:g} mm would have about {plan.triangles:,} "
                            f"triangles, above the preview's {PREVIEW_MAX_TRIANGLES:,}: give a larger preview edge "
                            "(the full resolution is made under 5. The textured mesh)")
            return
        self._start(self.preview_job, "preview", preview, float(edge), on_done=self.preview_made)

    def preview_made(self, made: Preview) -> None:
        self.show(made.glb, f"the object textured with {self.lay.texture_name} at preview resolution")
        self.preview_text.clear()
        with self.preview_text:
            for line in made.lines:
                ui.label(line)

    def start_feel(self) -> None:
        reference = None if self.reference.value == NO_REFERENCE else self.reference.value
        by = COLOUR_BY[self.colour_by.value]
        if by == "jnd" and reference is None:
            self.show_error("error: colouring by JND needs a reference texture (--reference)")
            return
        self._start(self.feel_job, "feel map", feel, self.engine.value, reference, self.printer.profile,
                    on_done=lambda result: self.feel_made(result, by), command="object feel")

    def feel_made(self, result: ObjectFeel, by: str) -> None:
        from roughness.objects.feel_figure import feel_colours

        _, faces, _ = self.lay.on(self.mesh)
        drawn = feel_colours(self.mesh, result.feel, faces, by)
        self.show(_painted_glb(drawn.triangles, drawn.colours),
                  f"the feel map on {result.shows()}, coloured by {drawn.label}", painted=True)
        stops = ", ".join(f"rgb({r * 255:.0f},{g * 255:.0f},{b * 255:.0f}) {100 * t:.0f}%"
                          for t in np.linspace(0, 1, 9) for r, g, b, _ in [drawn.cmap(t)])
        low, high = (f"{drawn.norm.vmin:+.2f} JND", f"{drawn.norm.vmax:+.2f} JND") if by == "jnd" else \
            (f"V {drawn.norm.vmin:.4f}", f"V {drawn.norm.vmax:.4f}")
        self.legend.clear()
        with self.legend:
            ui.label(low)
            ui.element("div").style(f"width: 240px; height: 16px; background: linear-gradient(to right, {stops})") \
                .props('aria-hidden="true"')
            ui.label(high)
        self.legend_text.set_text(legend_text(drawn, by))
        self.feel_text.clear()
        with self.feel_text:
            for line in result.lines(Path(self.mesh_file.path).name):
                ui.label(line)

    def start_tune(self) -> None:
        target = self.target.value
        if target is None or target <= 0:
            self.show_error("error: --target-lambda: the target is an equivalent wavelength in mm")
            return
        self._start(self.tune_job, "tune", tune, float(target), self.by.value, on_done=self.tuned)

    def tuned(self, result: ObjectTuneResult) -> None:
        base = self.lay.texture_name.split(" tuned", 1)[0]
        self.lay = replace(self.lay, texture_name=f"{base} tuned ({result.flat.by} x {result.flat.factor:.4g})",
                           texture=result.heightmap)
        self.tune_text.clear()
        with self.tune_text:
            for line in [*tune_lines(result), f"the preview, feel map and mesh now use {self.lay.texture_name} "
                                              "(choose another texture to leave it)"]:
                ui.label(line)

    def _export_edge(self) -> float | None:
        edge = self.export_edge.value
        if edge is not None and edge <= 0:
            raise InputError("--edge-mm: the edge is a positive length in mm")
        return None if edge is None else float(edge)

    def estimate(self) -> bool:
        """Show the full-resolution mesh's estimate; False (and the message) if it cannot be made."""
        try:
            lay = self.current_lay()
            line, warning = plan_line(self.mesh, lay, self._export_edge(), self.printer.profile)
        except InputError as err:
            self.show_error(f"error: {err}")
            return False
        self.error.set_text("")
        self.plan_text.set_text(line + (f"; warning: {warning}" if warning else ""))
        return True

    def start_export(self) -> None:
        if not self.estimate():
            return
        self.exports += 1
        suffix = self.export_format.value.lower()
        name = f"{Path(self.mesh_file.path).stem}-textured-{self.exports}.{suffix}"
        self._start(self.export_job, "full-resolution mesh", export, self._export_edge(),
                    str(self.session.path(name)), self.printer.profile, on_done=self.exported,
                    command="object texture")

    def exported(self, made: Exported) -> None:
        written = made.written
        name = Path(written.path).name
        with self.downloads:
            ui.link(f"Download {name} ({written.triangles:,} triangles, {written.bytes / 1e6:.1f} MB; "
                    f"{written.check.line()})", self.session.download_url(name)).props(f'download="{name}"').classes("text-primary")
            for line in made.printing:
                ui.label(line)


def build(session: Session) -> None:
    ObjectPage(session)
