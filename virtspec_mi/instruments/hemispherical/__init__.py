"""
The spectrophotometer: hemispherical readings
=============================================

The paper's instrument (Baranoski et al. 2001): the specimen lit from the emitter disk,
every ray's fate tallied — reflected into the upper hemisphere, transmitted into the
lower one, absorbed — giving reflectance ρ = m/N (eq. 2), transmittance τ and
absorptance α = 1 − ρ − τ per reading, with the certificate of the ray budget
(:mod:`virtspec_mi.budgets.rules`). :func:`virtspec_mi.measure` and
:func:`virtspec_mi.sweep` take their readings with :class:`Hemispherical`: no options
beside the :class:`~virtspec_mi.settings.Settings` and no exit hook (the fates are what
it tallies); the result is a :class:`~virtspec_mi.results.readings.Result` over
(wavelength, θi, parameter dims). A two-stage rule sizes each reading from its pilot's
R, T and A (or R and T together, ``joint``).

Every measurement is keyed (reading k owns the global ray indices [k·stride,
k·stride + N): its counts depend on (seed, k) only; resumable, on Dask workers):
``measure`` is a sweep's reading at one θi.

References
----------
Baranoski et al. (2001), eqs. (2), (23); Figs. 5 and 6.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.base.checks import MAX_RAYS

from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.engine.plan import Columns, Plan
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments.base import Instrument, readings_result
from virtspec_mi.instruments.command import Command, FigureFlag, Session
from virtspec_mi.results.readings import Result, fluctuation
from virtspec_mi.settings import Options, Settings, option

__all__ = ["Hemispherical", "SweepFlags"]


def _check_densities(value: Any) -> tuple[float, ...]:
    """Each log10 N of ``densities`` must give 1 <= N = 10^d <= 2**32 - 1 rays per reading."""

    highest = math.log10(MAX_RAYS)
    densities = []
    for text in (value.replace(",", " ").split() if isinstance(value, str) else np.atleast_1d(value).tolist()):
        try:
            densities.append(float(text))
        except (TypeError, ValueError):
            raise ValueError(f"densities must be numbers, log10 N each (got {text!r})") from None
    for density in densities:
        if not 0.0 <= density <= highest:
            raise ValueError(f"densities must satisfy 0 <= log10 N <= {highest:.2f} (N = 10^d rays per reading, "
                             f"at most 2**32 - 1; got {density:g})")
    return tuple(densities)


@dataclass(frozen=True)
class SweepFlags(Options):
    """``virtspec sweep``'s own flag beside the settings: the paper's Fig. 6 (a sweep per ray density)."""

    title: ClassVar[str] = "ray densities (the paper's Fig. 6)"

    densities: tuple[float, ...] | None = option(
        None, _check_densities, "sweep at N = 10^d rays for each log10 N = d; print seconds and the fluctuation of "
                                "eq. (24)", words=True)


def _respond_sweep(session: Session) -> int:
    """``virtspec sweep``: its readings (the command's declared ``table`` output), or a sweep per ``--densities``."""

    return _densities(session) if session.flags.densities else session.default()


def _densities(session: Session) -> int:
    """
    A sweep per ray density (on one cluster when workers are asked for), its seconds and
    the fluctuation Δ against the previous one (eq. 24, Fig. 6).
    """

    from virtspec_mi.results.plot import plot_densities

    args, densities = session.args, session.flags.densities
    if "rays" in session.keywords:
        raise ValueError("--rays and --densities exclude each other (densities set N = 10^d)")
    if args.json:
        raise ValueError("--json prints one result and --densities a table of seconds and Delta per density: give "
                         "one of them")
    with session.cluster() as client:
        workers = {} if client is None else {"workers": client}
        # Fig. 6b: time linear in N. The first sweep compiles the kernel (Dr.Jit caches it for every
        # N): run it once at the smallest density first, so no density's seconds include compilation.
        warm_up = session.take(rays=int(round(10.0 ** min(densities))), out=None, progress=False, **workers)
        out, results, deltas = session.keywords["out"], [], [float("nan")]
        print(f"{'log10 N':>8} {'N':>12} {'seconds':>9} {'Delta (eq. 24)':>15}")
        for density in densities:
            rays = int(round(10.0 ** density))
            path = out.with_name(f"{out.stem}_logN{density:g}{out.suffix}") if out is not None else None
            results.append(session.take(rays=rays, out=path, **workers))
            if len(results) > 1:
                deltas.append(fluctuation(results[-2], results[-1]))
            delta_text = "" if len(results) == 1 else f"{deltas[-1]:.6f}"
            print(f"{density:>8g} {rays:>12,} {results[-1].seconds:>9.3f} {delta_text:>15}", flush=True)
    print(f"(seconds after a warm-up sweep at log10 N = {min(densities):g}, {warm_up.seconds:.3f} s, "
          "which compiled the kernel" + ("; on workers: tracing seconds summed over the workers, not wall time)"
                                         if session.keywords["workers"] is not None else ")"))
    if args.plot:
        plot_densities(results, densities, deltas, args.plot)
    return 0


_MEASURE = Command(
    "measure", "one certified reading at one theta_i (a spectrum)",
    "Measure the specimen of a scene at one theta_i: reflectance, transmittance and absorptance per wavelength, "
    "each with the tolerance its rays guarantee and a Clopper-Pearson interval. Every setting defaults to the "
    "scene's spectrophotometer integrator, else to the paper's defaults. The readings are keyed as a sweep's "
    "(virtspec sweep --theta-i THETA gives the same counts): resumable with --out, the same on Dask workers.",
    ("virtspec measure diamond_conical --theta-i 70",
     "virtspec measure soybean_abmb --wavelengths 400:2500:5 --bound two-stage --json",
     "virtspec measure soybean_abmb --wavelengths 400:700:10 --param specimen.thickness=2e-4 --plot leaf.png"),
    figures=(FigureFlag("--plot", "spectra", "reflectance and transmittance over wavelength, each with the band of "
                                              "its certified tolerance",
                    keywords={"quantities": ("reflectance", "transmittance")}),),
    one_reading=True, function="sweep")

_SWEEP = Command(
    "sweep", "certified readings over theta_i x wavelength (x parameters)",
    "Measure a grid of readings (wavelength x theta_i, and specimen parameters with --param) at one phi_i, each "
    "with its own rays and certificate. Without --out (or --json) the readings are printed as a CSV table on "
    "stdout and the summary goes to stderr.",
    ("virtspec sweep diamond_collimated --theta-i 0:90:1 --out fig5.nc --plot fig5.png",
     "virtspec sweep diamond_collimated --theta-i 0:90:1 --densities 3 4 5 6",
     "virtspec sweep soybean_abmb --theta-i 8 --wavelengths 450,550,650 "
     "--param specimen.thickness=1.2e-4:2e-4:4e-5 --param specimen.chlorophyll_a=2,4 --out lut.nc",
     "virtspec sweep soybean_abmb -D side=abaxial --theta-i 8",
     "virtspec sweep soybean_abmb --theta-i 8 --wavelengths 400:2500:5 --workers 2 --out leaf.nc"),
    figures=(FigureFlag("--plot", "sweep", "the readings against theta_i (one curve per wavelength) or wavelength, with "
                                      "the band of their certified tolerance (one parameter point: draw a parameter "
                                      "sweep with virtspec plot FILE --sel NAME=VALUE)"),),
    flags=SweepFlags, function="sweep", respond=_respond_sweep, output="table")


class Hemispherical(Instrument):
    """The spectrophotometer (see the module docstring)."""

    name: ClassVar[str] = "hemispherical"
    options: ClassVar[type[Options] | None] = None
    result: ClassVar[type] = Result
    commands: ClassVar[tuple[Command, ...]] = (_MEASURE, _SWEEP)
    example: ClassVar[dict[str, Any]] = {
        "scene": "diamond_collimated", "theta_i": [0, 45], "wavelengths": [450, 650], "rays": 4000, "seed": 1,
        "long": {"scene": "soybean_abmb", "theta_i": 8, "wavelengths": "400:2500:5", "rays": 100_000,
                 "readings": 421}}

    def init(self, bench: Any, settings: Settings, options: Options | None, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        self.bench = bench
        self.plan = Plan(settings.updated(theta_i=float(theta_i[0])), theta_i, parameters,
                         columns=Columns.fates(settings.joint), scene=self.scene, instrument=self.name)
        return self.plan

    def postprocess(self, tally: Tally) -> Result:
        return readings_result(self.bench, self.plan, tally, self.scene, self.source)

    def warn_if_uncertified(self, result: Result, stacklevel: int = 2) -> None:
        result.warn_if_uncertified(stacklevel=stacklevel + 2)


