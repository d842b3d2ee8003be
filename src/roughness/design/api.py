"""The design tools with plain arguments (arrays or paths, numbers, strings), for Python and notebooks.

``roughness.tune``, ``roughness.palette``, ``roughness.tactile_image`` and ``roughness.homogeneity`` are
these functions: they build the ``Evaluator`` and ``Target`` the tools' modules take and call them, as
the CLI subcommands do (without the CLI's files and printing).
"""
from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughness.core.checks import choice, file_path, flag, integer, positive
from roughness.core.errors import InputError
from roughness.surface.arguments import heightmap_argument
from roughness.surface.heightmap import Heightmap, pixel_size

from . import homogeneity as _homogeneity
from . import lines as _lines
from . import palette as _palette
from . import tactile_image as _tactile
from . import tune as _tune
from .colours import cluster_colours
from .evaluation import VERIFIERS, Evaluator
from .layout import plan_layout

if TYPE_CHECKING:
    from roughness.surface.printing import PrintProfile

HeightmapLike = Heightmap | np.ndarray | str | Path


def heightmap_arg(value: HeightmapLike, pixel_mm: float | None = None, height_mm: float | None = None,
                  parameter: str = "heightmap", units_ok: bool = False) -> Heightmap:
    """A ``Heightmap`` from a ``Heightmap``, a 2-D array of heights (mm) with ``pixel_mm`` (mm), or a file path
    (read with ``roughness.load_heightmap(path, pixel_mm, height_mm)``: units the file lacks must be given); its
    units checked as the command line checks a file's (``surface.arguments``; ``units_ok`` confirms them)."""
    if isinstance(value, (str, Path)):
        from roughness.surface.io import load_heightmap

        hm = load_heightmap(value, pixel_mm=pixel_mm, height_mm=height_mm)
        return heightmap_argument(hm, None, parameter, units_ok, str(value))
    if height_mm is not None:
        raise InputError("height_mm applies to image files only: an array holds heights in mm",
                         parameter="height_mm")
    return heightmap_argument(value, pixel_mm, parameter, units_ok)


def printer_arg(printer: object) -> PrintProfile | None:
    """A print profile from ``printer``: None or "none" (the digital texture), a profile (``PROFILES``), its name,
    a JSON profile file, or "default" (the project's default: $ROUGHNESS_PRINTER, ./roughness.toml, the user's
    config file; ``roughness.surface.printing.choose_printer``); InputError naming ``printer`` otherwise."""
    from roughness.surface.printing import FdmProfile, SlaProfile, choose_printer, chosen_profile, printer_profile

    if printer is None or isinstance(printer, (FdmProfile, SlaProfile)):
        return printer
    if not isinstance(printer, (str, Path)):
        raise InputError(f"printer must be a profile, its name, a JSON profile file, \"default\" or None, got "
                         f"{type(printer).__name__}", parameter="printer")
    spec = str(printer).strip()
    if spec.lower() == "none":
        return None
    return chosen_profile(choose_printer()) if spec.lower() == "default" else printer_profile(spec)


def evaluator_arg(model: str | Path | None, verify: str | None = None, printer: object = None) -> Evaluator:
    """The ``Evaluator`` of a design tool's ``model`` (an ONNX path, default the shipped one), ``verify`` (a FEM
    fidelity or "spectral", default the model's labels') and ``printer`` (``printer_arg``), checked before anything
    is loaded."""
    if verify is not None:
        choice("verify", verify, VERIFIERS)
    profile = printer_arg(printer)
    return Evaluator(None if model is None else str(file_path("model", model)), verify, printer=profile)


def family_arg(family: object) -> str:
    """``family`` if it names a texture a palette can vary (``roughness texture list``), else InputError."""
    from roughness.dataset.catalogue import names

    return choice("family", family, [name for name in names() if name != "bumps"])  # bumps needs its parameters


def rgb_array(picture: np.ndarray) -> np.ndarray:
    """RGB pixels (h, w, 3) uint8 from an array: (h, w) grey or (h, w, 3) RGB, integers 0..255 or floats 0..1
    (as ``matplotlib.pyplot.imread`` gives); InputError for anything else."""
    from roughness.core.limits import MAX_IMAGE_PIXELS, check_size

    try:
        a = np.asarray(picture)
    except (TypeError, ValueError):  # rows of different lengths
        a = np.asarray(None)
    if a.dtype.kind not in "uif" or a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] != 3) or 0 in a.shape:
        raise InputError(f"picture must be an (h, w) grey or (h, w, 3) RGB array of numbers, got shape {a.shape}, "
                         f"dtype {a.dtype}", parameter="picture")
    check_size(f"picture pixels ({a.shape[0]:,} x {a.shape[1]:,})", a.shape[0] * a.shape[1], MAX_IMAGE_PIXELS,
               "picture")
    if np.ma.getmask(picture) is not np.ma.nomask and np.ma.getmaskarray(picture).any():
        raise InputError("picture has masked pixels: every pixel needs a colour", parameter="picture")
    top = 1.0 if a.dtype.kind == "f" else 255
    if not np.all(np.isfinite(a)) or a.min() < 0 or a.max() > top:
        raise InputError(f"picture values must be finite and within 0..{top:g} ({a.dtype})", parameter="picture")
    rgb = np.round(a * (255 / top)).astype(np.uint8)
    return rgb if rgb.ndim == 3 else np.repeat(rgb[..., None], 3, axis=2)


def tune(heightmap: HeightmapLike, *, target_lambda_mm: float | None = None, target_v: float | None = None,
         like: HeightmapLike | None = None, jnd: float | None = None, by: str = "height",
         pixel_mm: float | None = None, height_mm: float | None = None, factor_range: tuple[float, float] | None = None,
         tolerance_jnd: float = _tune.TOLERANCE_JND, max_fem: int = _tune.MAX_FEM, tile: bool = False,
         verify: str | None = None, model: str | Path | None = None, units_ok: bool = False,
         printer: object = None) -> _tune.TuneResult:
    """Scale a texture by height or lateral size until it feels like a target roughness.

    Parameters
    ----------
    heightmap : Heightmap, array of heights (mm) or path
        The texture to tune; an array needs ``pixel_mm``.
    target_lambda_mm : float, optional
        Target equivalent wavelength on the standard scale (mm).
    target_v : float, optional
        Target roughness V (dimensionless strain variation).
    like : Heightmap, array or path, optional
        A reference texture to match (its V from the verifier).
    jnd : float, optional
        Target this many just-noticeable differences from ``heightmap`` (positive: rougher).
        Exactly one of ``target_lambda_mm``, ``target_v``, ``like`` and ``jnd`` is given.
    by : {"height", "lateral"}
        The knob: heights or lateral size scaled.
    pixel_mm, height_mm : float, optional
        Pixel size (mm) of arrays; units of image files (mm).
    factor_range : (float, float), optional
        Smallest and largest scale factor searched (default: the knob's).
    tolerance_jnd : float
        Stop when the verifier's answer is this close to the target (JND).
    max_fem : int
        At most this many verifications.
    tile : bool
        The map is one period of a periodic texture.
    verify : str, optional
        The verifier: a FEM fidelity ("coarse", "default", "fine") or "spectral" (default: the model's labels').
    model : str or Path, optional
        ONNX surrogate model (default: the shipped one).
    units_ok : bool
        The heights are mm even though they look like metres or micrometres (default: refuse them).
    printer : str, profile or None
        Judge every texture as this printer prints it (``roughness.surface.printing.PROFILES`` name, a profile, a
        JSON profile file, or "default": the project's default printer); None: the digital texture.

    Returns
    -------
    TuneResult
        ``.heightmap`` the scaled texture, ``.factor``, ``.achieved`` (V, its standard error, wavelength in mm),
        ``.jnd_error`` and ``.reached``.
    """
    hm = heightmap_arg(heightmap, pixel_mm, height_mm, units_ok=units_ok)
    reference = None if like is None else heightmap_arg(like, pixel_mm, height_mm, "like", units_ok)
    choice("by", by, _tune.KNOBS)
    factor_range = None if factor_range is None else _factor_range(factor_range)
    positive("tolerance_jnd", tolerance_jnd)
    integer("max_fem", max_fem, minimum=1)
    tile = flag("tile", tile)
    evaluator = evaluator_arg(model, verify, printer)
    target = _tune.target_of(evaluator, target_lambda_mm, target_v, reference, "reference", tile, jnd, hm)
    return _tune.tune(hm, target, by, evaluator, factor_range, tolerance_jnd, max_fem, tile)


def _factor_range(value: object) -> tuple[float, float]:
    """``factor_range`` as two rising positive factors, or InputError naming it."""
    pair = list(value) if isinstance(value, (tuple, list)) else []
    if len(pair) != 2:
        raise InputError(f"factor_range must be two factors (smallest, largest), got {value!r}",
                         parameter="factor_range")
    lo, hi = (positive("factor_range", f) for f in pair)
    if not lo < hi:
        raise InputError(f"factor_range must rise (smallest, largest), got {lo:g}..{hi:g}", parameter="factor_range")
    return lo, hi


def palette(k: int, *, min_jnd: float = 2.0, family: str = _palette.DEFAULT_FAMILY, by: str = "height",
            candidates: str | Path | Mapping[str, HeightmapLike] | None = None, pixel_mm: float | None = None,
            tolerance_jnd: float = _tune.TOLERANCE_JND, seed: int = 0, tile: bool = False,
            verify: str | None = None, model: str | Path | None = None, units_ok: bool = False,
            printer: object = None) -> _palette.Palette:
    """``k`` textures that feel different from each other, at least ``min_jnd`` apart (verified).

    Parameters
    ----------
    k : int
        Number of textures (at least 2).
    min_jnd : float
        Smallest distance between any two members (just-noticeable differences).
    family : str
        Without ``candidates``: the named texture whose variants (scaled ``by`` height or lateral size) are tuned.
    by : {"height", "lateral"}
        The knob for a family palette.
    candidates : folder path or mapping of name to Heightmap, array (mm) or path, optional
        Choose the ``k`` farthest apart among these instead; arrays need ``pixel_mm`` (mm).
    tolerance_jnd : float
        Tuning tolerance of a family palette's members (JND).
    seed : int
        Seed of the family's texture.
    tile : bool
        Candidates are periodic tiles.
    verify, model, units_ok, printer
        As in ``roughness.tune`` (with a printer, the members are chosen and verified as printed).

    Returns
    -------
    Palette
        ``.members`` (name, heightmap, verified V) smoothest first, ``.closest_jnd`` and ``.verified``;
        ``roughness.design.palette.save_palette`` writes it as the CLI does.
    """
    integer("k", k, minimum=2)
    positive("min_jnd", min_jnd)
    if pixel_mm is not None:
        pixel_size(pixel_mm)
    family_arg(family)
    choice("by", by, _tune.KNOBS)
    positive("tolerance_jnd", tolerance_jnd)
    integer("seed", seed, minimum=0)
    tile = flag("tile", tile)
    evaluator = evaluator_arg(model, verify, printer)
    if candidates is None:
        return _palette.family_palette(k, min_jnd, family, by, evaluator, tolerance_jnd, seed=seed)
    return _palette.folder_palette(_candidates(candidates, pixel_mm, units_ok), k, min_jnd, evaluator, tile)


def _candidates(candidates: object, pixel_mm: float | None, units_ok: bool) -> list[tuple[str, Heightmap]]:
    """A palette's (name, heightmap) candidates from a folder or a mapping of name to heightmap, checked."""
    if isinstance(candidates, (str, Path)):
        from roughness.surface.io import heightmap_files, load_heightmap

        files = heightmap_files(_folder("candidates", candidates))
        return [(name, heightmap_arg(load_heightmap(f, pixel_mm=pixel_mm), parameter="candidates", units_ok=units_ok))
                for name, f in zip(_palette.candidate_names(files), files)]
    if isinstance(candidates, Mapping):
        return [(str(name), heightmap_arg(hm, pixel_mm, parameter="candidates", units_ok=units_ok))
                for name, hm in candidates.items()]
    raise InputError("candidates must be a folder of heightmaps or a mapping of name to heightmap, got "
                     f"{type(candidates).__name__}", parameter="candidates")


def _folder(parameter: str, value: str | Path) -> Path:
    """``value`` as a Path, or InputError naming ``parameter`` unless it is an existing folder."""
    folder = file_path(parameter, value)
    if not folder.is_dir():
        raise InputError(f"{parameter}: {folder} is not a folder" + ("" if folder.exists() else " (it does not exist)"),
                         parameter=parameter)
    return folder


def tactile_image(picture: np.ndarray | str | Path, textures: str | Path | Sequence[HeightmapLike] | None = None, *,
                  k: int | None = None, min_jnd: float = 2.0, family: str = _palette.DEFAULT_FAMILY,
                  size_mm: float = _tactile.WIDTH_MM, page: str | None = None, pixel_mm: float | None = None,
                  texture_pixel_mm: float | None = None, outline_mm: float | None = None,
                  outline_height_mm: float | None = None, step_mm: float = _tactile.STEP_MM, strain: bool = False,
                  colour_tolerance: float = _tactile.TOLERANCE, lines: bool = True,
                  line_width_mm: float = _lines.MAX_STROKE_MM, line_colour: str | None = None,
                  line_bar_mm: float = _lines.LINE_WIDTH_MM, line_height_mm: float = _lines.LINE_HEIGHT_MM,
                  line_gap_mm: float = _lines.LINE_GAP_MM, background: str | None = "auto",
                  assign: Mapping[str, int | str] | None = None, key: bool = False,
                  key_labels: Mapping[str, str] | None = None, braille_table: str | None = None,
                  smooth_edges: bool = True, merge_small: bool = False,
                  verify: str | None = None,
                  model: str | Path | None = None, units_ok: bool = False,
                  printer: object = None) -> _tactile.TactilePlate:
    """A printable plate on which each flat colour of a picture is a texture that feels different.

    Parameters
    ----------
    picture : array (ny, nx, 3) of RGB or path of an image
        The picture; its flat colours become regions.
    textures : palette folder, sequence of Heightmap / array (mm) / path, optional
        The textures, smoothest first (a folder written by ``save_palette``); default: a palette of ``k``
        (default: as many as colours) variants of ``family``, ``min_jnd`` apart.
    size_mm : float
        Plate width (mm).
    page : str, optional
        Instead of ``size_mm``: fit the plate on this sheet (``roughness.design.pages.PAGES_MM``: a4, a3, letter,
        tabloid, braille) less its margins.
    pixel_mm : float, optional
        Plate pixel (mm); default 0.1, or with a printer the textures' own pixel where finer (so that the plate
        prints as its palette was verified; ``plate_pixel`` in ``roughness.design.tactile_image``).
    texture_pixel_mm : float, optional
        Pixel size (mm) of texture arrays.
    outline_mm, outline_height_mm : float, optional
        Raised outlines between regions: width and height (mm).
    step_mm : float
        Step of the roughness map (mm).
    strain : bool
        Also compute the FEM strain image (slow).
    colour_tolerance : float
        Colours within this CIE Delta E are one colour.
    lines : bool
        Detect thin strokes (narrower than ``line_width_mm`` on the plate, or of the colour ``line_colour``,
        "#rrggbb") and make them smooth raised lines ``line_bar_mm`` wide and ``line_height_mm`` high, textures
        ``line_gap_mm`` clear of them (mm; ``roughness.design.lines``).
    background : "auto", "#rrggbb" or None
        The colour left flat ("auto": the colour most on the picture's border; None: every region textured).
    assign : mapping of "#rrggbb" to palette member number (from 1, smoothest first) or "flat", optional
        Which colour gets which texture; default: the lightest textured colour the smoothest.
    smooth_edges : bool
        Region edges follow the shapes, not the picture's pixels (``roughness.design.edges``); False: nearest
        neighbour.
    merge_small : bool
        Textured areas narrower than 6.35 mm join the region nearest them (default: listed in the notes only).
    key, key_labels, braille_table : bool, mapping of "#rrggbb" to text, str, optional
        A key strip under the picture: each texture's sample beside its braille label (default labels a, b, c, ...;
        grade 1 English built in, or a liblouis ``braille_table``; ``roughness.design.key``).
    verify, model, units_ok, printer
        As in ``roughness.tune`` (``units_ok``: of the texture arrays; with a printer, a new palette is made of
        textures that stay ``min_jnd`` apart as printed and the roughness map is of the printed plate).

    Returns
    -------
    TactilePlate
        ``.heightmap`` the plate (mm), ``.regions`` (colour, texture, V on the plate); ``figures(plate)`` in
        ``roughness.design.tactile_image`` draws it.
    """
    with _renamed(image="picture"):  # the command line's name for the picture
        rgb = _tactile.read_image(picture) if isinstance(picture, (str, Path)) else rgb_array(picture)
        found = cluster_colours(rgb, colour_tolerance)
    _tactile.check_outline(outline_mm, outline_height_mm)
    positive("min_jnd", min_jnd)
    family_arg(family)
    strain = flag("strain", strain)
    if k is not None:
        integer("k", k, minimum=2)
        if textures is not None:
            raise InputError("k is the size of a palette made for the picture; give k or textures, not both",
                             parameter="k")
    if page is not None:
        from .pages import page_width

        size_mm = page_width(page, rgb.shape)
    evaluator = evaluator_arg(model, verify, printer)
    lines = flag("lines", lines)
    style = _lines.LineStyle(line_bar_mm, line_height_mm, line_gap_mm)
    layout = plan_layout(found, positive("size_mm", size_mm) / rgb.shape[1],
                         positive("line_width_mm", line_width_mm) if lines else None,
                         line_colour if lines else None, background, assign, style)
    spec = None
    if flag("key", key) or key_labels is not None or braille_table is not None:
        from .key import key_spec

        spec = key_spec(found, key_labels, braille_table)
    key_mm = _tactile.key_height(layout, spec, size_mm)
    _tactile.plate_shape(rgb.shape, size_mm, _tactile.PIXEL_MM if pixel_mm is None else pixel_mm, step_mm,
                         evaluator.footprint_mm, key_mm)  # refused before any palette
    with _renamed(palette="textures", pixel_mm="texture_pixel_mm"):  # the command line's --palette, this pixel
        chosen = _plate_textures(textures, texture_pixel_mm, units_ok) if textures is not None else None
    if chosen is None and not layout.textured:  # lines on a flat background: no palette
        chosen = []
    if chosen is None:
        made = _palette.family_palette(k or max(2, len(layout.textured)), min_jnd, family, "height", evaluator)
        chosen = [(m.name, m.heightmap, m.fem.roughness) for m in made.members]
    plate_pixel_mm, note = _tactile.plate_pixel(pixel_mm, rgb.shape, size_mm, [hm for _, hm, _ in chosen],
                                                evaluator.printer, key_mm)
    plate = _tactile.tactile_image(found, chosen, size_mm, plate_pixel_mm, outline_mm, outline_height_mm, step_mm,
                                   strain, evaluator, layout=layout, key=spec,
                                   smooth_edges=flag("smooth_edges", smooth_edges),
                                   merge_small=flag("merge_small", merge_small))
    return plate if note is None else replace(plate, notes=(note, *plate.notes))


@contextmanager
def _renamed(**names: str) -> Iterator[None]:
    """InputErrors raised inside, their parameter renamed from a lower layer's name to this function's."""
    try:
        yield
    except InputError as err:
        err.parameter = names.get(err.parameter or "", err.parameter)
        raise


def _plate_textures(textures: object, pixel_mm: float | None, units_ok: bool
                    ) -> list[tuple[str, Heightmap, float | None]]:
    """A plate's (name, heightmap, FEM V or None) textures from a palette folder or a list of heightmaps."""
    if isinstance(textures, (str, Path)):
        return [(name, hm, meta.get("fem_roughness")) for name, hm, meta in _palette.load_palette(textures)]
    if not isinstance(textures, (list, tuple)):
        raise InputError(f"textures must be a palette folder or a list of heightmaps, got {type(textures).__name__}",
                         parameter="textures")
    return [(f"texture {i + 1}", heightmap_arg(t, pixel_mm, parameter="textures", units_ok=units_ok), None)
            for i, t in enumerate(textures)]


def homogeneity(heightmap: HeightmapLike, *, pixel_mm: float | None = None, height_mm: float | None = None,
                engine: str = "surrogate", window_mm: float | None = None, n: int = _homogeneity.N_WINDOWS,
                seed: int = 0, tile: bool = False, model: str | Path | None = None, units_ok: bool = False,
                printer: object = None) -> _homogeneity.Homogeneity:
    """Does a texture feel the same everywhere? V over ``n`` windows, its spread in JND and the verdicts.

    Parameters
    ----------
    heightmap : Heightmap, array of heights (mm) or path
        The texture; an array needs ``pixel_mm`` (mm), an image file its units.
    engine : {"surrogate", "fem"}
        What computes V per window.
    window_mm : float, optional
        Window side (mm; default: the 10 mm skin footprint).
    n : int
        Number of windows.
    seed : int
        Seed of the window positions.
    tile : bool
        The map is one period of a periodic texture.
    model : str or Path, optional
        ONNX surrogate model (default: the shipped one).
    units_ok : bool
        The heights are mm even though they look like metres or micrometres (default: refuse them).
    printer : str, profile or None
        Judge every texture as this printer prints it (``roughness.surface.printing.PROFILES`` name, a profile, a
        JSON profile file, or "default": the project's default printer); None: the digital texture.

    Returns
    -------
    Homogeneity
        ``.verdict``, ``.range_jnd`` and ``.spread_jnd`` (JND), ``.relative_variance`` (the paper's measure); with a
        printer, those of the print, with ``.digital`` (the digital texture's, same windows) and ``.print_result``;
        ``save_map(result, heightmap)`` in ``roughness.design.homogeneity`` draws it.
    """
    hm = heightmap_arg(heightmap, pixel_mm, height_mm, units_ok=units_ok)
    evaluator = evaluator_arg(model, printer=printer)
    test = _homogeneity.homogeneity_as_printed if evaluator.printer else _homogeneity.homogeneity
    return test(hm, engine, window_mm, n, seed, tile, evaluator)
