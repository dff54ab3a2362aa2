"""
``virtspec fit``: the command of :func:`virtspec_mi.applications.fitting.fit`, declared
=========================================================================================

:data:`FIT` is the fitting application's :class:`~virtspec_mi.applications.base.Command`:
its help and examples, its arguments and flags (:class:`FitFlags`, an
:class:`~virtspec_mi.settings.Options` class that the command line's one flag builder turns
into ``MEASURED``, ``--specimen``, ``--free`` …) and :func:`respond`, which receives the
command line's session (the flags given, checked; the shared report). Nothing here parses
or prints by itself.

References
----------
Féret et al. (2017), RSE 193:204–215 (PROSPECT inversion).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from virtspec_mi.applications.base import Command, Session
from virtspec_mi.applications.comparison.flags import MeasuredFlags
from virtspec_mi.base.checks import check_delta, number, shown_value
from virtspec_mi.plugins import specimen_rows
from virtspec_mi.settings import one_of, option, text, true_or_false, whole_number

__all__ = ["FIT", "FitFlags", "respond", "EXAMPLES"]

EXAMPLES: tuple[str, ...] = (
    "virtspec fit leaf.csv --specimen prospect_d --free Cab=10:80 --free Cm=0.002:0.02 --quantity both",
    "virtspec fit leaf_R.csv --transmittance leaf_T.csv --specimen abm_b --free chlorophyll_a=5:40 \\\n"
    "      --free mesophyll_fraction=0.3:0.9 --theta-i 8 --beam collimated --directory fit-work \\\n"
    "      --out fit.nc --plot fit.png",
    "virtspec fit leaf.csv --specimen prospect_d --free Cab=10:80 --free Cm=0.002:0.02 --quantity both \\\n"
    "      --loss windows --window Cab=700:720   (Cm on its published window, 1700-2400 nm)",
    "virtspec fit library.sli --measured-quantity reflectance --specimen prospect_d --free Cab=10:90 \\\n"
    "      --uncertainty 0.01 --workers 4 --out fits.csv   (every spectrum of the library: a table of fits)",
)


def _pairs(flag: str, form: str) -> Any:
    """The check of a repeated ``NAME=LOW:HIGH`` flag: a tuple of (name, text) pairs."""

    def check(values: Any) -> tuple[tuple[str, str], ...]:
        pairs = []
        for item in (values,) if isinstance(values, str) else values:
            if isinstance(item, tuple):  # already checked
                pairs.append(item)
                continue
            name, sep, bounds = str(item).partition("=")
            if not sep or not name.strip() or ":" not in bounds:
                raise ValueError(f"{flag} takes {form} (got {item!r})")
            pairs.append((name.strip(), bounds.strip()))
        return tuple(pairs)
    return check



def _positive(name: str) -> Any:
    def check(value: Any) -> float:
        value = number(name, value)
        if not value > 0:
            raise ValueError(f"{name} must be > 0 (got {shown_value(value)})")
        return value
    return check


def _angle(value: Any) -> float:
    value = number("theta_i", value)
    if not 0.0 <= value <= 90.0:
        raise ValueError(f"theta_i must satisfy 0 <= theta_i <= 90 (got {shown_value(value)})")
    return value


def _evaluations(values: Any) -> tuple[int, int, int]:
    """Three whole numbers >= 0: the readings of the refinement's three stages."""

    values = values.replace(",", " ").split() if isinstance(values, str) else (
        (values,) if isinstance(values, int) else tuple(values))
    whole = whole_number("evaluations", 0, 10**6, "0 <= each <= 10**6")
    checked = tuple(whole(v) for v in values)
    if len(checked) != 3:
        raise ValueError(f"evaluations takes three whole numbers A B C (got {len(checked)})")
    return checked  # type: ignore[return-value]


def _defines(values: Any) -> tuple[str, ...]:
    for item in values:
        if "=" not in str(item):
            raise ValueError(f"-D takes NAME=VALUE (got {item!r})")
    return tuple(values)


_QUANTITIES = {"reflectance": "MEASURED is a reflectance", "transmittance": "MEASURED is a transmittance",
               "both": "MEASURED holds reflectance and transmittance columns"}


@dataclass(frozen=True)
class FitFlags(MeasuredFlags):
    """
    The arguments and flags of ``virtspec fit`` (:func:`virtspec_mi.applications.fitting.fit`'s keywords),
    and how a measured file is read (:class:`~virtspec_mi.applications.comparison.flags.MeasuredFlags`).
    """

    title: ClassVar[str] = "fit"

    measured: str | None = option(None, text("measured"), "measured spectrum: a wavelength,value,uncertainty CSV "
                                  "(or a colour-science CSV with uncertainty columns), a NetCDF file, a result file, "
                                  "or an instrument's or library's file (.asd, .sig, .sed, .jdx/.dx, .sli, a CSV "
                                  "table of many samples: --sample; give --uncertainty)",
                                  positional=True, metavar="MEASURED")
    specimen: str | None = option(None, text("specimen"), f"a specimen plugin ({', '.join(specimen_rows())}: the "
                                  "project's and the installed packages' of the entry-point group "
                                  "virtspec_mi.specimens), a shipped scene or an XML scene", required=True)
    free: tuple | None = option(None, _pairs("--free", "NAME=LOWEST:HIGHEST"), "a free parameter and its bounds",
                                repeat=True, required=True, metavar="NAME=LOWEST:HIGHEST")
    quantity: str = option("reflectance", one_of("quantity", _QUANTITIES), "what MEASURED holds", _QUANTITIES)
    transmittance: str | None = option(None, text("transmittance"), "a measured transmittance file besides MEASURED "
                                       "(then MEASURED is the reflectance)", metavar="FILE")
    uncertainty: float | None = option(None, _positive("uncertainty"), "measurement uncertainty (a half-width) of "
                                       "every point, overriding the files'")
    wavelengths: str | None = option(None, text("wavelengths"), "wavelengths to fit, e.g. 400:2500:20", unset="the "
                                     "measured ones")
    loss: str | None = option(None, text("loss"), "the loss minimised: chi2, rmse, max or windows (checked by vm.fit, "
                              "which names them)", unset="chi2, windows with --window")
    window: tuple = option((), _pairs("--window", "NAME=LOWEST:HIGHEST[,LOWEST:HIGHEST ...] in nm"),
                           "the spectral window (nm) on which a free parameter is estimated (loss windows; PROSPECT-D's "
                           "Cab, Car, Anth, Cw, Cm default to the published ones)", repeat=True,
                           metavar="NAME=LOWEST:HIGHEST")
    delta: float = option(0.05, check_delta, "risk of each candidate's forward spectrum")
    mu_fraction: float = option(0.5, _positive("mu_fraction"), "forward tolerance at the optimum as a fraction of the "
                                "smallest measurement uncertainty")
    forward_mu: float | None = option(None, _positive("forward_mu"), "forward tolerance at the optimum (overrides "
                                      "--mu-fraction)")
    table: str | None = option(None, text("table"), "Zarr store of the coarse table (read when it exists, else "
                               "written)")
    table_points: int | None = option(None, whole_number("table_points", 1, 10**6, "1 <= table_points"),
                                      "values per parameter in the table", unset="from the free parameters")
    evaluations: tuple[int, int, int] | None = option(
        None, _evaluations, "readings of each of the three refinement stages; raise them when a fit says NOT "
        "CONVERGED", words=True, metavar="A B C", unset="12, 6, 3 per free parameter")
    profile_points: int = option(5, whole_number("profile_points", 0, 10**6, "0 <= profile_points"),
                                 "points of each profile (0: none)")
    search_wavelengths: int | None = option(None, whole_number("search_wavelengths", 0, 10**9,
                                                               "0 <= search_wavelengths"),
                                            "wavelengths the search and the confirmation read when fewer than the "
                                            "fitted ones (0: all)", metavar="N", unset="16")
    seed: int = option(0, whole_number("seed", 0, 2**32 - 1, "0 <= seed < 2**32"), "seed of every forward reading")
    directory: str | None = option(None, text("directory"), "work directory: readings kept there; the same command "
                                   "resumes")
    workers: int | None = option(None, whole_number("workers", 1, 4096, "1 <= workers"), "Dask workers for the table",
                                 metavar="N", unset="in this process")
    theta_i: float | None = option(None, _angle, "incidence angle of the forward readings (degrees)",
                                   unset="the specimen scene's")
    beam: str | None = option(None, text("beam"), "beam of the forward readings (collimated, conical)",
                              unset="the specimen scene's")
    bound: str | None = option(None, text("bound"), "ray budget rule of the forward readings (hoeffding, "
                               "two-stage ...)", unset="the specimen scene's")
    defines: tuple = option((), _defines, "a parameter of an XML scene", repeat=True, spelled="-D",
                            metavar="NAME=VALUE")
    out: str | None = option(None, text("out"), "fit file (.json or .nc); the fits of a file of many spectra: a "
                             "table (.csv or .nc)")
    plot: str | None = option(None, text("plot"), "figure (.png, .svg): measured vs fitted, residuals, profiles")
    json: bool = option(False, true_or_false("json"), "print the fit as one JSON object")
    progress: bool = option(False, true_or_false("progress"), "a progress bar and a line per stage on stderr "
                            "(default: when stderr is a terminal)")
    quiet: bool = option(False, true_or_false("quiet"), "no progress bar and no lines on stderr")


def respond(session: Session) -> int:
    """
    ``virtspec fit``: :func:`~virtspec_mi.applications.fitting.fit` of the flags given, reported;
    every spectrum of a file of many (no ``--sample``): a table of fits (:func:`_respond_table`).
    """

    from pathlib import Path

    from virtspec_mi.applications.fitting.result import FIT_SUFFIXES
    from virtspec_mi.base.checks import parse_wavelengths
    from virtspec_mi.base.files import check_distinct
    from virtspec_mi.exchange.measured.flags import measured_from

    flags = session.flags
    many = not flags.transmittance and _many_samples(flags)  # every spectrum fitted: a table (its own suffixes)
    if flags.out and not many and Path(flags.out).suffix.lower() not in FIT_SUFFIXES:
        raise ValueError(f"--out: a fit file is {' or '.join(FIT_SUFFIXES)} (got {flags.out})")
    if flags.plot and Path(flags.plot).suffix.lower() not in (".png", ".svg", ".pdf"):
        raise ValueError(f"--plot: a figure is .png, .svg or .pdf (got {flags.plot})")
    check_distinct([("--out", flags.out), ("--plot", flags.plot), ("--table", flags.table),
                    ("--directory", flags.directory)],
                   [("MEASURED", flags.measured), ("--transmittance", flags.transmittance),
                    ("--specimen", flags.specimen)])
    if flags.transmittance:
        measured: Any = {"reflectance": measured_from(flags, flags.measured),
                         "transmittance": measured_from(flags, flags.transmittance)}
        quantities = None
    else:
        measured = measured_from(flags, flags.measured)
        quantities = ("reflectance", "transmittance") if flags.quantity == "both" else (flags.quantity,)
    defines = dict(item.partition("=")[::2] for item in flags.defines)
    settings = {name: value for name, value in (("theta_i", flags.theta_i), ("beam", flags.beam),
                                                ("bound", flags.bound)) if value is not None}
    search = {} if flags.search_wavelengths is None else {"search_wavelengths": flags.search_wavelengths or None}
    session.args.checkpoint = flags.directory  # an interrupt's message names where the readings are kept
    options = dict(quantities=quantities, measurement_uncertainty=flags.uncertainty,
                   wavelengths=None if flags.wavelengths is None else parse_wavelengths(flags.wavelengths),
                   loss=flags.loss, windows=dict(flags.window) or None, delta=flags.delta,
                   mu_fraction=flags.mu_fraction, forward_mu=flags.forward_mu, table_points=flags.table_points,
                   profile_points=flags.profile_points, seed=flags.seed, defines=defines or None,
                   evaluations=flags.evaluations,
                   progress=False if flags.quiet else True if flags.progress else None, **search, **settings)
    if many:
        return _respond_table(session, measured, options)
    from virtspec_mi.applications.fitting.inversion import fit

    result = fit(measured, flags.specimen, dict(flags.free), table=flags.table, directory=flags.directory,
                 workers=flags.workers, **options)
    if flags.out:
        result.write(flags.out)
    if flags.plot:
        result.plot(flags.plot)
    return session.report(result, result.summary(), written=[flags.out] if flags.out else [],
                          figures=[flags.plot] if flags.plot else [])


def _many_samples(flags: FitFlags) -> bool:
    """Whether MEASURED is a file of many spectra and no --sample chose one (then every one is fitted)."""

    from virtspec_mi.exchange.measured import format_for, read_samples
    from virtspec_mi.exchange.measured.flags import measured_from

    if flags.sample is not None or format_for(flags.measured, flags.measured_format) is None:
        return False
    return len(read_samples(measured_from(flags, flags.measured))) > 1


def _respond_table(session: Session, measured: Any, options: dict[str, Any]) -> int:
    """``virtspec fit`` of every spectrum of a file of many: a table of fits (on Dask with --workers)."""

    from pathlib import Path

    from virtspec_mi.applications.fitting.samples import TABLE_SUFFIXES, fit_samples

    flags = session.flags
    if flags.out and Path(flags.out).suffix.lower() not in TABLE_SUFFIXES:
        raise ValueError(f"--out: the fits of a file of many spectra are a table, {' or '.join(TABLE_SUFFIXES)} "
                         f"(got {flags.out}); or choose one spectrum with --sample")
    if flags.table or flags.plot:
        raise ValueError("--table and --plot take one spectrum: choose it with --sample (the fits of every "
                         "spectrum share one table in --directory)")
    table = fit_samples(measured, flags.specimen, dict(flags.free), workers=flags.workers,
                        directory=flags.directory, **options)
    if flags.out:
        table.write(flags.out)
    data = {"source": table.source, "samples": list(table.labels), "parameters": list(table.names),
            "estimate": table.to_dataset()["estimate"].values.tolist(), "intervals": table.intervals.tolist(),
            "consistent": table.consistent.tolist(), "statistic": table.statistic.tolist()}
    return session.report(table, table.summary(), written=[flags.out] if flags.out else [], data=data)


FIT = Command(
    "fit", "a specimen's parameters from a measured spectrum (estimate, confidence set)",
    "Fit the free parameters of a specimen to a measured reflectance and/or transmittance: a coarse table, then a "
    "local refinement on certified forward readings with common random numbers whose tolerance shrinks to a "
    "fraction of the measurement uncertainty; prints the estimate, each parameter's interval from the confidence "
    "set, unconstrained parameters, and whether the fit is consistent at all. Resumable with --directory.",
    EXAMPLES, FitFlags, respond)
"""The fitting application's command (:class:`~virtspec_mi.applications.fitting.FittingApplication`)."""
