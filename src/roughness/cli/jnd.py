"""`roughness jnd A B`: can a fingertip tell two textures apart? V, equivalent lambda, JND distance, verdict."""
from __future__ import annotations

import argparse

from .common import add_reading_args, defaults, finish, json_text, load_input, readings, write_stdout
from .printer import add_printer_arg, printer_of


def add_parser(sub) -> None:
    from roughness.prediction import PREDICT_ENGINES, predict

    given = defaults(predict)
    p = sub.add_parser("jnd", help="tell two textures apart? their V, equivalent lambda and distance in JNDs")
    p.add_argument("a", metavar="HEIGHTMAP_A", help="first texture (heightmap file; FILE:height-mm=MM,pixel-mm=MM "
                   "gives its own units)")
    p.add_argument("b", metavar="HEIGHTMAP_B", help="second texture (heightmap file, as A)")
    p.add_argument("--engine", choices=PREDICT_ENGINES, default=given["engine"],
                   help=f"surrogate, spectral, fem, or auto: the surrogate, FEM outside its domain "
                        f"(default: {given['engine']})")
    p.add_argument("--model", help="ONNX surrogate (default: the shipped model)")
    add_reading_args(p)
    add_printer_arg(p, "the distance and verdict are between the two printed textures; the digital ones' are "
                       "reported beside them")
    p.add_argument("--json", action="store_true", help="one JSON object (default: text)")
    finish(p, run)


def run(args: argparse.Namespace) -> int:
    from roughness.core.provenance import combined
    from roughness.prediction import predictions

    printer = printer_of(args)  # an unknown printer is refused before any file is read
    maps = [load_input(args, path, several=True) for path in (args.a, args.b)]
    named = list(zip([args.a, args.b], maps))
    prints = []
    if printer is not None:
        from roughness.surface.printing import printed

        prints = [printed(hm, printer) for hm in maps]
        named = [(f"{name} as printed", result.heightmap) for name, result in zip([args.a, args.b], prints)] + named
    results = predictions(named, args.engine, args.model)  # checked as they were loaded
    pa, pb = results[:2]
    distance = jnd_between(pa, pb)
    digital = jnd_between(*results[2:]) if printer is not None else None
    if args.json:
        extra = {} if digital is None else {
            "digital": {"a": results[2].as_dict(), "b": results[3].as_dict(), **digital.as_dict()},
            "printer": printer.as_dict(), "print_notes": list(dict.fromkeys(n for r in prints for n in r.notes))}
        write_stdout(json_text({"a": pa.as_dict(), "b": pb.as_dict(), **distance.as_dict(), **extra,
                                "readings": readings(args),
                                "provenance": combined([p.provenance for p in results]).as_dict()}))
        return 0
    lines = [_line(p) for p in (pa, pb)]
    lines.append(distance_line(distance, uncertainty_kinds(pa, pb)))
    if digital is not None:
        lines += [f"printer {printer.describe()}", *("digital " + _line(p) for p in results[2:]),
                  "digital " + distance_line(digital, uncertainty_kinds(*results[2:])),
                  *(f"print note: {n}" for n in dict.fromkeys(n for r in prints for n in r.notes))]
    write_stdout("\n".join(lines))
    return 0


def jnd_between(pa, pb):
    """The ``JndDistance`` of two predictions on the standard scale of the first's fidelity."""
    from roughness.perceptual_scale import jnd_distance, load_scale

    return jnd_distance(load_scale(pa.fidelity), pa.roughness, pb.roughness, _uncertainty(pa), _uncertainty(pb))


def uncertainty_kinds(pa, pb) -> str:
    """Where the two V's uncertainties come from, in words."""
    return " and ".join(dict.fromkeys("Monte Carlo of V" if p.roughness_stderr is not None else "ensemble spread"
                                      for p in (pa, pb)))


def _uncertainty(p) -> float | None:
    """The standard error of a V: FEM's Monte Carlo error, else an ensemble's spread (treated as independent
    between the two textures, which overstates the distance's uncertainty when their errors are alike)."""
    return p.roughness_stderr if p.roughness_stderr is not None else p.roughness_std


def distance_line(distance, kinds: str) -> str:
    """The distance and verdict in words; none when both are below the scale, "at least" when one is."""
    tail = "(one JND = a 19% step in equivalent wavelength, told apart 75% of the time)"
    if distance.jnd is None:
        return f"distance: none, {distance.note}: {distance.verdict.upper()} {tail}"
    sure = (f" ± {2 * distance.jnd_stderr:.2f} (2 sigma: {kinds})" if distance.jnd_stderr is not None
            else " (no uncertainty: the surrogate is a single network without a spread)")
    rougher = "A rougher" if distance.jnd > 0 else "B rougher" if distance.jnd < 0 else "equally rough"
    bound = f"at least {abs(distance.jnd):.2f} JND" if distance.lower_bound else f"{abs(distance.jnd):.2f} JND"
    note = f" ({distance.note})" if distance.note else ""
    return f"distance: {bound}{sure}, {rougher}{note}: {distance.verdict.upper()} {tail}"


def _line(p) -> str:
    from roughness.prediction import domain_words

    se = _uncertainty(p)
    v = f"V = {p.roughness:.4f}" + (f" ± {se:.4f}" if se is not None else "")
    return f"{p.source}: {v} ({p.engine}, {domain_words(p)}), {p.placement.describe()}"
