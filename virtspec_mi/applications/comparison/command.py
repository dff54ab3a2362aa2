"""
``virtspec compare``: a result against a measured spectrum, declared
======================================================================

The comparison application's row, :class:`ComparisonApplication`, and its
:class:`~virtspec_mi.applications.base.Command` :data:`COMPARE`: its arguments and flags
(:class:`CompareFlags`) and :func:`respond`, which receives the command line's session
(the result file read at the ``--sel`` labels, the shared report).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.applications.base import Application, Command, Session
from virtspec_mi.applications.comparison.flags import MeasuredFlags
from virtspec_mi.applications.comparison.result import Comparison
from virtspec_mi.base.checks import number
from virtspec_mi.colorimetry.cie import DEFAULT_ILLUMINANT, DEFAULT_OBSERVER
from virtspec_mi.kernel.counts import QUANTITIES
from virtspec_mi.settings import option, text, true_or_false

__all__ = ["ComparisonApplication", "COMPARE", "CompareFlags", "respond"]



def _selections(values: Any) -> tuple[str, ...]:
    for item in values:
        if "=" not in str(item):
            raise ValueError(f"--sel takes NAME=VALUE (got {item!r})")
    return tuple(values)


@dataclass(frozen=True)
class CompareFlags(MeasuredFlags):
    """
    The arguments and flags of ``virtspec compare`` (:func:`~virtspec_mi.applications.comparison.compare`),
    and how a measured file is read (:class:`~virtspec_mi.applications.comparison.flags.MeasuredFlags`).
    """

    title: ClassVar[str] = "comparison"

    result: str | None = option(None, text("result"), "result file of any kind (.nc, .csv, .json, .zarr; also "
                                "`measure --json` output)", positional=True)
    measured: str | None = option(None, text("measured"), "measured spectrum (.csv, .txt, .nc, a result file, .asd, "
                                  ".sig, .sed, .jdx/.dx, .sli)",
                                  positional=True)
    quantity: str | None = option(None, text("quantity"), f"quantity compared: {', '.join(QUANTITIES)} of a reading "
                                  "or goniophotometer file (the measured column of that name), or reading, corrected, "
                                  "hemispherical of a sphere file (the measured column of what the sphere measures)",
                                  unset="reflectance; a sphere file's reading")
    theta_i: float | None = option(None, lambda value: number("theta_i", value), "angle of the result to use (needed "
                                   "if it has several)")
    uncertainty: float | None = option(None, lambda value: number("uncertainty", value), "measurement uncertainty, "
                                       "added to the certified tolerance (overrides the file's uncertainty column)",
                                       unset="the file's")
    illuminant: str = option(DEFAULT_ILLUMINANT, text("illuminant"), "colour.SDS_ILLUMINANTS name for Delta E 2000")
    observer: str = option(DEFAULT_OBSERVER, text("observer"), "colour.MSDS_CMFS name")
    selections: tuple = option((), _selections, "keep the label of dim NAME nearest VALUE: a parameter point (e.g. "
                               "specimen.thickness=1.6e-4, point=3), theta_i=8, wavelength=550", repeat=True,
                               spelled="--sel", metavar="NAME=VALUE")
    plot: str | None = option(None, text("plot"), "figure .png or .svg: both spectra and the residuals")
    json: bool = option(False, true_or_false("json"), "print the comparison as one JSON object")


def respond(session: Session) -> int:
    """``virtspec compare RESULT MEASURED``: :func:`~virtspec_mi.applications.comparison.compare`, reported."""

    from dataclasses import replace
    from pathlib import Path

    from virtspec_mi.applications.comparison.result import compare
    from virtspec_mi.base.files import check_distinct
    from virtspec_mi.exchange.measured.flags import measured_from
    from virtspec_mi.results.plot import check_figure_path

    flags = session.flags
    check_figure_path(flags.plot)  # a bad suffix fails before any work
    check_distinct([("--plot", flags.plot)], [("RESULT", flags.result), ("MEASURED", flags.measured)])
    comparison = compare(session.read(flags.result), measured_from(flags, flags.measured), quantity=flags.quantity, theta_i=flags.theta_i,
                         measurement_uncertainty=flags.uncertainty, illuminant=flags.illuminant,
                         observer=flags.observer)
    comparison = replace(comparison, result_name=Path(flags.result).name)
    if flags.plot:
        comparison.plot(flags.plot)
    if flags.json:
        print(comparison.sealed_json())  # a comparison's file: vm.read_result reads it
        return 0
    return session.report(comparison, comparison.summary(), figures=[flags.plot] if flags.plot else [])


COMPARE = Command(
    "compare", "a result against a measured spectrum (residuals, Delta E)",
    "Compare one quantity of a result file at one theta_i with a measured spectrum over their common wavelengths "
    "(the measured one interpolated onto the result's, never extrapolated): residuals, RMSE, the share of points "
    "within the certified tolerance (+ the measurement uncertainty) and Delta E 2000. MEASURED: a colour-science CSV "
    "spectral file, a plain wavelength,value[,uncertainty] CSV, a NetCDF file, another result file, or an "
    "instrument's or library's file (ASD, SVC .sig, PSR .sed, JCAMP-DX, ENVI .sli, a CSV table of many samples).",
    ("virtspec compare spectrum.nc measured.csv --plot compare.png",
     "virtspec compare reading.json npsg.csv --quantity transmittance --json"), CompareFlags, respond)
"""The comparison application's command."""


def _inputs(folder: Any) -> None:
    """The example's result file (a small sweep of the shipped diamond) and a measured spectrum."""

    from pathlib import Path

    from virtspec_mi.runtime.reading import take
    from virtspec_mi.runtime.scene import loaded

    take("sweep", loaded("diamond_collimated"), wavelengths=[450.0, 550.0, 650.0], rays=4000, seed=1,
         progress=False).write(Path(folder, "r.nc"))
    Path(folder, "m.csv").write_text("wavelength,reflectance,uncertainty\n450,0.18,0.01\n550,0.17,0.01\n"
                                     "650,0.17,0.01\n")


def _api(folder: Any) -> Any:
    from pathlib import Path

    from virtspec_mi.applications.comparison.result import compare
    from virtspec_mi.runtime.reading import read_result

    return compare(read_result(Path(folder, "r.nc")), Path(folder, "m.csv"))


class ComparisonApplication(Application):
    """Simulated against measured spectra: ``vm.compare``, ``virtspec compare``."""

    name: ClassVar[str] = "comparison"
    summary: ClassVar[str] = "a result against a measured spectrum: residuals, the share within tolerance, Delta E"
    commands: ClassVar[tuple[Command, ...]] = (COMPARE,)
    results: ClassVar[tuple[type, ...]] = (Comparison,)
    example: ClassVar[dict[str, Any]] = {
        "argv": ("compare", "{tmp}/r.nc", "{tmp}/m.csv", "--json"), "inputs": _inputs, "api": _api,
        "counts": lambda comparison: np.asarray(comparison.residuals, dtype=np.float64),
        "printed": lambda data: np.asarray(data["residuals"], dtype=np.float64)}
