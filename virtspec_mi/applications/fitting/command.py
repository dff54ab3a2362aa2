"""
``virtspec fit``: the command line of :func:`virtspec_mi.applications.fitting.fit`
==================================================================================

:func:`add_fit_command` adds the ``fit`` subcommand to ``virtspec``'s parser and
:func:`run_fit` runs it (the CLI calls both; this module imports nothing of the CLI).

References
----------
Féret et al. (2017), RSE 193:204–215 (PROSPECT inversion).
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from virtspec_mi.exchange.measured.flags import add_measured_flags, measured_from

__all__ = ["add_fit_command", "run_fit", "EXAMPLES"]

EXAMPLES: str = (
    "examples:\n"
    "  virtspec fit leaf.csv --specimen prospect_d --free Cab=10:80 --free Cm=0.002:0.02 --quantity both\n"
    "  virtspec fit leaf_R.csv --transmittance leaf_T.csv --specimen abm_b --free chlorophyll_a=5:40 \\\n"
    "      --free mesophyll_fraction=0.3:0.9 --theta-i 8 --beam collimated --directory fit-work \\\n"
    "      --out fit.nc --plot fit.png\n"
    "  virtspec fit leaf.csv --specimen prospect_d --free Cab=10:80 --free Cm=0.002:0.02 --quantity both \\\n"
    "      --loss windows --window Cab=700:720   (Cm on its published window, 1700-2400 nm)\n"
    "  virtspec fit library.sli --measured-quantity reflectance --specimen prospect_d --free Cab=10:90 \\\n"
    "      --uncertainty 0.01 --workers 4 --out fits.csv   (every spectrum of the library: a table of fits)"
)


def _pair(text: str) -> tuple[str, str]:
    name, sep, bounds = text.partition("=")
    if not sep or not name or ":" not in bounds:
        raise argparse.ArgumentTypeError(f"--free takes NAME=LOWEST:HIGHEST (got {text!r})")
    return name.strip(), bounds.strip()


def _window(text: str) -> tuple[str, str]:
    name, sep, intervals = text.partition("=")
    if not sep or not name or ":" not in intervals:
        raise argparse.ArgumentTypeError(f"--window takes NAME=LOWEST:HIGHEST[,LOWEST:HIGHEST ...] in nm "
                                         f"(got {text!r})")
    return name.strip(), intervals.strip()


def add_fit_command(commands: Any) -> argparse.ArgumentParser:
    """Add ``fit`` to the subparsers ``commands`` (an ``add_subparsers`` object); returns its parser."""

    parser = commands.add_parser(
        "fit", help="a specimen's parameters from a measured spectrum (estimate, confidence set)",
        description="Fit the free parameters of a specimen to a measured reflectance and/or transmittance: a coarse "
                    "table, then a local refinement on certified forward readings with common random numbers whose "
                    "tolerance shrinks to a fraction of the measurement uncertainty; prints the estimate, each "
                    "parameter's interval from the confidence set, unconstrained parameters, and whether the fit is "
                    "consistent at all. Resumable with --directory.",
        epilog=EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measured", help="measured spectrum: a wavelength,value,uncertainty CSV (or a colour-science "
                                         "CSV with uncertainty columns), a NetCDF file, a result file, or an "
                                         "instrument's or library's file (.asd, .sig, .sed, .jdx/.dx, .sli, a CSV "
                                         "table of many samples: --sample; give --uncertainty)")
    from virtspec_mi.plugins import specimen_rows

    parser.add_argument("--specimen", required=True,
                        help=f"a specimen plugin ({', '.join(specimen_rows())}: the project's and the installed "
                             "packages' of the entry-point group virtspec_mi.specimens), a shipped scene or an XML "
                             "scene")
    parser.add_argument("--free", type=_pair, action="append", required=True, metavar="NAME=LOWEST:HIGHEST",
                        help="a free parameter and its bounds (repeat for several)")
    parser.add_argument("--quantity", choices=("reflectance", "transmittance", "both"), default="reflectance",
                        help="what MEASURED holds (both: its reflectance and transmittance columns)")
    parser.add_argument("--transmittance", metavar="FILE", help="a measured transmittance file besides MEASURED "
                                                                "(then MEASURED is the reflectance)")
    parser.add_argument("--uncertainty", type=float, help="measurement uncertainty (a half-width) of every point, "
                                                          "overriding the files'")
    parser.add_argument("--wavelengths", help="wavelengths to fit, e.g. 400:2500:20 (default: the measured ones)")
    parser.add_argument("--loss", help="the loss minimised: chi2, rmse, max or windows (default chi2, windows with "
                                       "--window; checked by vm.fit, which names them)")
    parser.add_argument("--window", type=_window, action="append", default=[], metavar="NAME=LOWEST:HIGHEST",
                        help="the spectral window (nm) on which a free parameter is estimated (loss windows; repeat "
                             "for several; PROSPECT-D's Cab, Car, Anth, Cw, Cm default to the published ones)")
    parser.add_argument("--delta", type=float, default=0.05, help="risk of each candidate's forward spectrum "
                                                                  "(default 0.05)")
    parser.add_argument("--mu-fraction", type=float, default=0.5,
                        help="forward tolerance at the optimum as a fraction of the smallest measurement uncertainty")
    parser.add_argument("--forward-mu", type=float, help="forward tolerance at the optimum (overrides --mu-fraction)")
    parser.add_argument("--table", help="Zarr store of the coarse table (read when it exists, else written)")
    parser.add_argument("--table-points", type=int, help="values per parameter in the table")
    parser.add_argument("--evaluations", type=int, nargs=3, metavar=("A", "B", "C"),
                        help="readings of each of the three refinement stages (default 12, 6, 3 per free parameter); "
                             "raise them when a fit says NOT CONVERGED")
    parser.add_argument("--profile-points", type=int, default=5, help="points of each profile (0: none)")
    parser.add_argument("--search-wavelengths", type=int, metavar="N",
                        help="wavelengths the search and the confirmation read when fewer than the fitted ones "
                             "(default 16; 0: all)")
    parser.add_argument("--seed", type=int, default=0, help="seed of every forward reading (default 0)")
    parser.add_argument("--directory", help="work directory: readings kept there; the same command resumes")
    parser.add_argument("--workers", type=int, metavar="N", help="Dask workers for the table")
    parser.add_argument("--theta-i", type=float, help="incidence angle of the forward readings (degrees)")
    parser.add_argument("--beam", help="beam of the forward readings (collimated, conical)")
    parser.add_argument("--bound", help="ray budget rule of the forward readings (hoeffding, two-stage ...)")
    parser.add_argument("-D", dest="defines", action="append", default=[], metavar="NAME=VALUE",
                        help="a parameter of an XML scene")
    parser.add_argument("--out", help="fit file (.json or .nc)")
    parser.add_argument("--plot", help="figure (.png, .svg): measured vs fitted, residuals, profiles")
    parser.add_argument("--json", action="store_true", help="print the fit as one JSON object")
    parser.add_argument("--progress", action="store_true", help="a line per stage on stderr")
    add_measured_flags(parser)
    return parser


def run_fit(args: argparse.Namespace) -> int:
    """Run ``virtspec fit`` (errors raise ``ValueError``: the CLI prints them as one line)."""

    from pathlib import Path

    from virtspec_mi.applications.fitting.inversion import fit
    from virtspec_mi.applications.fitting.result import FIT_SUFFIXES
    from virtspec_mi.base.checks import parse_wavelengths
    from virtspec_mi.base.files import check_distinct

    many = not args.transmittance and _many_samples(args)  # every spectrum fitted: a table (its own suffixes)
    if args.out and not many and Path(args.out).suffix.lower() not in FIT_SUFFIXES:
        raise ValueError(f"--out: a fit file is {' or '.join(FIT_SUFFIXES)} (got {args.out})")
    if args.plot and Path(args.plot).suffix.lower() not in (".png", ".svg", ".pdf"):
        raise ValueError(f"--plot: a figure is .png, .svg or .pdf (got {args.plot})")
    check_distinct([("--out", args.out), ("--plot", args.plot), ("--table", args.table),
                    ("--directory", args.directory)],
                   [("MEASURED", args.measured), ("--transmittance", args.transmittance),
                    ("--specimen", args.specimen)])
    if args.transmittance:
        measured: Any = {"reflectance": measured_from(args, args.measured),
                         "transmittance": measured_from(args, args.transmittance)}
        quantities = None
    else:
        measured = measured_from(args, args.measured)
        quantities = ("reflectance", "transmittance") if args.quantity == "both" else (args.quantity,)
    defines = {}
    for item in args.defines:
        name, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"-D takes NAME=VALUE (got {item!r})")
        defines[name] = value
    settings = {name: value for name, value in (("theta_i", args.theta_i), ("beam", args.beam),
                                                ("bound", args.bound)) if value is not None}
    search = {} if args.search_wavelengths is None else {"search_wavelengths": args.search_wavelengths or None}
    args.checkpoint = args.directory  # an interrupt's message names where the readings are kept
    options = dict(quantities=quantities, measurement_uncertainty=args.uncertainty,
                   wavelengths=None if args.wavelengths is None else parse_wavelengths(args.wavelengths),
                   loss=args.loss, windows=dict(args.window) or None, delta=args.delta,
                   mu_fraction=args.mu_fraction, forward_mu=args.forward_mu, table_points=args.table_points,
                   profile_points=args.profile_points, seed=args.seed, defines=defines or None,
                   evaluations=None if args.evaluations is None else tuple(args.evaluations),
                   progress=True if args.progress else None, **search, **settings)
    if many:
        return _run_table(args, options)
    result = fit(measured, args.specimen, dict(args.free), table=args.table, directory=args.directory,
                 workers=args.workers, **options)
    if args.out:
        result.write(args.out)
    if args.plot:
        result.plot(args.plot)
    if args.json:
        print(json.dumps(result.as_dict()))
        return 0
    print(result.summary())
    for label, path in (("fit", args.out), ("plot", args.plot)):
        if path:
            print(f"{label}: {path}")
    return 0


def _many_samples(args: argparse.Namespace) -> bool:
    """Whether MEASURED is a file of many spectra and no --sample chose one (then every one is fitted)."""

    from virtspec_mi.exchange.measured import format_for, read_samples

    if args.sample is not None or format_for(args.measured, args.measured_format) is None:
        return False
    return len(read_samples(measured_from(args, args.measured))) > 1


def _run_table(args: argparse.Namespace, options: dict[str, Any]) -> int:
    """``virtspec fit`` of every spectrum of a file of many: a table of fits (on Dask with --workers)."""

    from pathlib import Path

    from virtspec_mi.applications.fitting.samples import TABLE_SUFFIXES, fit_samples

    if args.out and Path(args.out).suffix.lower() not in TABLE_SUFFIXES:
        raise ValueError(f"--out: the fits of a file of many spectra are a table, {' or '.join(TABLE_SUFFIXES)} "
                         f"(got {args.out}); or choose one spectrum with --sample")
    if args.table or args.plot:
        raise ValueError("--table and --plot take one spectrum: choose it with --sample (the fits of every "
                         "spectrum share one table in --directory)")
    table = fit_samples(measured_from(args, args.measured), args.specimen, dict(args.free), workers=args.workers,
                        directory=args.directory, **options)
    if args.out:
        table.write(args.out)
    if args.json:
        data = table.to_dataset()
        print(json.dumps({"source": table.source, "samples": list(table.labels), "parameters": list(table.names),
                          "estimate": data["estimate"].values.tolist(),
                          "intervals": table.intervals.tolist(), "consistent": table.consistent.tolist(),
                          "statistic": table.statistic.tolist()}))
        return 0
    print(table.summary())
    if args.out:
        print(f"table: {args.out}")
    return 0
