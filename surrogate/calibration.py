"""The 13-texture standard reference scale: V -> equivalent bump wavelength and JND distance.

The table holds, per FEM fidelity, the mean FEM V of each standard texture (cap-topped bumps at
the paper's lambdas) over several seeds. A roughness V is placed on the scale by its equivalent
wavelength: log lambda interpolated in log V between the standard textures (V rises with lambda,
about as lambda^2), and beyond either end the exponent b of the power law V = a lambda^b fitted to
the whole table, from that end's standard (V = V_end (lambda / lambda_end)^b: continuous and rising
across the ends, where the fitted law itself is not: it gave two wavelengths to one V just below the
coarsest standard). The placement then says it is extrapolated. The paper measured its Weber fraction, 0.19, on
lambda, so distances are counted in just-noticeable differences of the equivalent wavelength:
ln(lambda_A / lambda_B) / ln(1.19). (A 19% step in V is only about half a JND.)

The scale has a floor (``StandardScale.floor``): the V of that extrapolation at ``FLOOR_LAMBDA_MM`` =
0.2 mm, the shortest bump wavelength the standard textures can be drawn with (``MIN_PIXELS_PER_LAMBDA``
= 4 pixels of the scale's 0.05 mm pixels), about 6.5 JND below the finest standard (0.625 mm): V about
0.0031 at every tabulated fidelity, a ninth of the finest standard's. Down to it the power law still
places bump textures at their own wavelength (the shipped surrogate reads bumps of 0.2, 0.25 and
0.3125 mm at 0.207, 0.242 and 0.292 mm); below it no standard-like texture could be equivalent, and
V there is within a few times the engines' own noise of zero (the ensemble's spread on a flat map is
1e-4). A V below the
floor is placed *below the scale*: no equivalent wavelength, no JND (``Placement.below_scale``),
instead of the power law's meaningless microns (a flat plate was "lambda 4e-6 mm, -68 JND").

Distances (``jnd_distance``) treat the floor as the scale's absolute threshold: a V below it is
counted at the floor, so a distance from a texture below the scale is a lower bound
(``JndDistance.lower_bound``), and two textures both below it are "too close" with no JND at all.
Standard errors are carried in V and mapped through d ln(lambda) = dV / (b max(V, floor)), which is
bounded at zero, instead of the relative errors se / V that explode there.

Regenerate the shipped table (``models/standard_scale.json``, a few minutes on 2 cores)::

    python -m roughness.surrogate.calibration --fidelities coarse default          # 5 seeds each
    python -m roughness.surrogate.calibration --fidelities fine                    # adds fine (~15 min)
    python -m roughness.surrogate.calibration --fidelities spectral                # the spectral engine (~1 min)

Each table also records the mean estimated discretization error of V per lambda (from the
next coarser mesh level, ``simulate.discretization``).
"""
from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np

from roughness.core.errors import InputError
from roughness.core.files import atomic_write
from roughness.models import MODELS_DIR

WEBER_FRACTION = 0.19
SCALE_PATH = MODELS_DIR / "standard_scale.json"
FLOOR_LAMBDA_MM = 4 * 0.05  # dataset.textures.MIN_PIXELS_PER_LAMBDA pixels of the standard 0.05 mm (dataset.grid)


@dataclass(frozen=True)
class Placement:
    """Where a roughness V sits on the standard scale (module docstring: the floor)."""

    equivalent_lambda_mm: float | None  # interpolated on the scale; the fitted power law beyond its ends; None below
    on_scale: bool  # False if V lies below the finest or above the coarsest standard texture
    nearest_standard: str  # e.g. "standard-1.0"
    jnd_from_nearest: float | None  # signed, on lambda: positive = rougher than the nearest standard; None below
    below_scale: bool = False  # V below the scale's floor: not placed
    floor: float = 0.0  # the floor's V

    def as_dict(self) -> dict:
        return {"equivalent_lambda_mm": self.equivalent_lambda_mm, "on_scale": self.on_scale,
                "extrapolated": not self.on_scale and not self.below_scale, "below_scale": self.below_scale,
                "scale_floor_roughness": self.floor, "nearest_standard": self.nearest_standard,
                "jnd_from_nearest": self.jnd_from_nearest}

    def describe(self) -> str:
        """The placement in words (no V)."""
        if self.below_scale:
            return f"below the standard scale (V < floor {self.floor:.4f}): no equivalent lambda"
        where = "" if self.on_scale else " (extrapolated off the scale)"
        return f"lambda {self.equivalent_lambda_mm:.3f} mm{where}"


def jnd(lambda_a_mm: float, lambda_b_mm: float) -> float:
    """Signed distance of two (equivalent) wavelengths in JNDs: ln(lambda_a / lambda_b) / ln(1 + 0.19)."""
    return math.log(lambda_a_mm / lambda_b_mm) / math.log(1 + WEBER_FRACTION)


@dataclass(frozen=True)
class StandardScale:
    """Mean FEM V (dimensionless strain variation) of the standard textures at one fidelity."""

    lambdas_mm: tuple[float, ...]
    roughness: tuple[float, ...]
    fidelity: str
    floor_lambda_mm: float = FLOOR_LAMBDA_MM  # the floor: V of the power law here (module docstring)

    def __post_init__(self) -> None:
        v = np.asarray(self.roughness)
        if len(v) != len(self.lambdas_mm) or len(v) < 2 or not np.all(v > 0) or not np.all(np.diff(v) > 0):
            raise ValueError(f"standard scale ({self.fidelity}) must be positive and rise with lambda: {self.roughness}")

    @cached_property
    def power_law(self) -> tuple[float, float]:
        """(a, b) of V = a lambda^b, least squares in log-log over the table (lambda in mm)."""
        b, log_a = np.polyfit(np.log(self.lambdas_mm), np.log(self.roughness), 1)
        return float(math.exp(log_a)), float(b)

    @cached_property
    def floor(self) -> float:
        """V below which a roughness is below the scale (module docstring): the scale's V at ``floor_lambda_mm``."""
        return self.roughness_at(self.floor_lambda_mm)

    def equivalent_lambda(self, roughness: float) -> tuple[float, bool]:
        """Equivalent wavelength (mm) of a roughness V, and whether it lies on the scale (not extrapolated).

        No floor: the design searches need a continuous map; what users see goes through ``place``."""
        _check(roughness)
        log_v, log_lambda = np.log(self.roughness), np.log(self.lambdas_mm)
        x = math.log(max(roughness, 1e-12))  # V = 0 (flat): the smallest V a float field resolves
        if log_v[0] <= x <= log_v[-1]:
            return float(np.exp(np.interp(x, log_v, log_lambda))), True
        end = 0 if x < log_v[0] else -1
        return float(math.exp(log_lambda[end] + (x - log_v[end]) / self.power_law[1])), False

    def roughness_at(self, lambda_mm: float) -> float:
        """V at an equivalent wavelength (mm): the inverse of ``equivalent_lambda``."""
        log_v, log_lambda = np.log(self.roughness), np.log(self.lambdas_mm)
        x = math.log(lambda_mm)
        if log_lambda[0] <= x <= log_lambda[-1]:
            return float(np.exp(np.interp(x, log_lambda, log_v)))
        end = 0 if x < log_lambda[0] else -1
        return float(math.exp(log_v[end] + self.power_law[1] * (x - log_lambda[end])))

    def place(self, roughness: float) -> Placement:
        """Equivalent lambda (mm) and signed JND distance (on lambda) from the nearest standard texture;
        below the floor neither (``below_scale``; the nearest standard is then the finest)."""
        floor = self.floor
        if _check(roughness) < floor:
            return Placement(None, False, f"standard-{self.lambdas_mm[0]:g}", None, True, floor)
        lam, on_scale = self.equivalent_lambda(roughness)
        nearest = int(np.argmin(np.abs(np.log(self.lambdas_mm) - math.log(lam))))
        return Placement(lam, on_scale, f"standard-{self.lambdas_mm[nearest]:g}", jnd(lam, self.lambdas_mm[nearest]),
                         False, floor)

    def floored_lambda(self, roughness: float) -> float:
        """Equivalent wavelength (mm) of V counted at the floor when below it: the scale's absolute threshold."""
        return self.equivalent_lambda(max(roughness, self.floor))[0]


def _check(roughness: float) -> float:
    """``roughness``; ValueError unless it is finite and >= 0."""
    if not math.isfinite(roughness) or roughness < 0:
        raise ValueError(f"roughness must be finite and >= 0, got {roughness}")
    return roughness


@dataclass(frozen=True)
class JndDistance:
    """Signed distance of two roughness values on the standard scale, in JNDs of the equivalent wavelength.

    A V below the scale's floor is counted at the floor (module docstring): the distance from it is then
    a lower bound (``lower_bound``); with both below there is no distance (``jnd`` None) and the verdict
    is "too close": the scale resolves nothing smoother than its floor.
    """

    jnd: float | None  # ln(lambda_a / lambda_b) / ln(1.19): positive = a feels rougher; None: both below the scale
    jnd_stderr: float | None  # from the values' standard errors (None if either has none, or both below the scale)
    a: Placement
    b: Placement

    @property
    def lower_bound(self) -> bool:
        """One of the two is below the scale: counted at the floor, so the distance is at least ``jnd``."""
        return self.a.below_scale != self.b.below_scale

    @property
    def verdict(self) -> str:
        """"tell apart" at one JND or more, "too close" below (and when both are below the scale);
        "borderline" if +-2 standard errors straddle 1."""
        if self.jnd is None:
            return "too close"
        d = abs(self.jnd)
        if self.jnd_stderr is not None and d - 2 * self.jnd_stderr < 1 <= d + 2 * self.jnd_stderr:
            return "borderline"
        return "tell apart" if d >= 1 else "too close"

    @property
    def note(self) -> str:
        """Why the distance is a bound or absent (empty when both are on or off the ends of the scale)."""
        floor = self.a.floor
        if self.a.below_scale and self.b.below_scale:
            return f"both below the standard scale (V < {floor:.4f}): too smooth for the scale to tell apart"
        if self.lower_bound:
            which = "A" if self.a.below_scale else "B"
            return (f"{which} is below the standard scale (V < {floor:.4f}) and is counted at its floor: "
                    "at least this far apart")
        return ""

    def as_dict(self) -> dict:
        return {"jnd": self.jnd, "jnd_stderr": self.jnd_stderr, "jnd_is_lower_bound": self.lower_bound,
                "below_scale": [k for k, p in (("a", self.a), ("b", self.b)) if p.below_scale],
                "verdict": self.verdict, "note": self.note}


def jnd_distance(scale: StandardScale, v_a: float, v_b: float, se_a: float | None = None,
                 se_b: float | None = None) -> JndDistance:
    """JND distance of V_a from V_b, each V counted at least at the scale's floor.

    Standard errors (of V) propagate through lambda ~ V^(1/b) of the fitted power law, with the slope
    at the floor for a V below it: se of ln lambda = se / (b max(V, floor)), bounded as V -> 0.
    """
    a, b = scale.place(v_a), scale.place(v_b)
    if a.below_scale and b.below_scale:
        return JndDistance(None, None, a, b)
    se = None
    if se_a is not None and se_b is not None:
        exponent, floor = scale.power_law[1], scale.floor
        se_ln = math.hypot(se_a / max(v_a, floor), se_b / max(v_b, floor)) / exponent  # of ln(lambda_a / lambda_b)
        se = se_ln / math.log(1 + WEBER_FRACTION)
    return JndDistance(jnd(scale.floored_lambda(v_a), scale.floored_lambda(v_b)), se, a, b)


@lru_cache(maxsize=8)
def load_scale(fidelity: str, path: str | Path = SCALE_PATH) -> StandardScale:
    """The shipped standard scale for a FEM fidelity ("coarse", "default", "fine")."""
    tables = json.loads(Path(path).read_text())["tables"]
    if fidelity not in tables:
        raise InputError(f"no standard-scale table for fidelity {fidelity!r} in {path}; has {sorted(tables)}")
    table = tables[fidelity]
    return StandardScale(tuple(table["lambda_mm"]), tuple(table["V_mean"]), fidelity)


def measure(fidelity: str, seeds: range) -> dict:
    """Run the FEM (or, for ``spectral``, the spectral engine) on every standard texture and seed; mean and
    spread of V per lambda (the FEM's mean estimated discretization error too)."""
    from roughness.dataset.textures import STANDARD_LAMBDAS_MM, standard_texture
    from roughness.simulate import SimConfig, Simulator

    if fidelity == "spectral":
        from roughness.simulate.spectral.engine import SpectralSimulator

        sim = SpectralSimulator()
    else:
        sim = Simulator(SimConfig(fidelity=fidelity))
    results = [[sim.run(standard_texture(lam, seed=s)) for s in seeds] for lam in STANDARD_LAMBDAS_MM]
    values = np.array([[r.roughness for r in row] for row in results])
    out = {"lambda_mm": list(STANDARD_LAMBDAS_MM), "seeds": list(seeds), "V_mean": values.mean(1).round(6).tolist(),
           "V_std": values.std(1, ddof=1).round(6).tolist(), "V": values.round(6).tolist()}
    if fidelity != "spectral":
        errors = np.array([[r.discretization_error for r in row] for row in results], dtype=float)
        out["discretization_error_mean"] = errors.mean(1).round(4).tolist()
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(SCALE_PATH))
    parser.add_argument("--fidelities", nargs="+", default=["coarse", "default"],
                        help="FEM fidelities to tabulate; tables of others in --out are kept (default: coarse default)")
    parser.add_argument("--seeds", type=int, default=5, help="realisations per lambda (seeds 100, 101, ...)")
    args = parser.parse_args(argv)
    out = Path(args.out)
    tables = json.loads(out.read_text())["tables"] if out.exists() else {}  # other fidelities are kept
    for fidelity in args.fidelities:
        tables[fidelity] = measure(fidelity, range(100, 100 + args.seeds))
        print(fidelity, tables[fidelity]["V_mean"], flush=True)
    note = ("Mean FEM V of the 13 standard cap-topped bump textures (paper parameters, 10 N, stick) over "
            "the seeds listed; regenerate with: python -m roughness.surrogate.calibration")
    text = json.dumps({"note": note, "weber_fraction": WEBER_FRACTION, "tables": tables}, indent=1)
    atomic_write(out, lambda tmp: Path(tmp).write_text(text))


if __name__ == "__main__":
    main()
