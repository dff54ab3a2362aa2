"""
The subcommands that read result files: ``virtspec colour`` and ``plot``
========================================================================

Every kind of result file (a hemispherical reading or sweep, a goniophotometer reading:
its R and T, or its lobes; a sphere reading: its reading, corrected or hemispherical
value), ``--sel NAME=VALUE`` (repeatable): the label of a dim nearest VALUE (a
parameter point, θi, a wavelength). ``virtspec compare`` is the comparison application's
(:mod:`virtspec_mi.applications.comparison.command`); it reads its result file with
:func:`selected` too.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any, Callable, Sequence

from virtspec_mi.cli.flags import pairs
from virtspec_mi.exchange.measured.flags import add_measured_flags, measured_from

__all__ = ["add_file_commands", "colour", "plot", "selected"]

EXAMPLES = {
    "colour": "examples:\n  virtspec colour spectrum.csv\n"
              "  virtspec colour fig5.nc --theta-i 30 --illuminant A --quantity transmittance\n"
              "  virtspec colour lut.nc --sel specimen.thickness=1.6e-4 --sel theta_i=8\n"
              "  virtspec colour sphere.json --quantity hemispherical",
    "plot": "examples:\n  virtspec plot fig5.nc --wavelengths 400 550 700 --out fig5.png\n"
            "  virtspec plot spectrum.nc --quantity transmittance\n"
            "  virtspec plot spectrum.nc --against measured.csv --out compare.svg\n"
            "  virtspec plot brdf.nc --sel wavelength=550 --out lobes.png\n"
            "  virtspec plot lut.nc --sel specimen.thickness=1.6e-4 --sel theta_i=8",
}
"""Each file subcommand's examples (its ``--help``)."""


def add_file_commands(command: Callable[..., argparse.ArgumentParser]) -> None:
    """Add ``colour`` and ``plot`` through ``command(name, summary, description, examples)``."""

    from virtspec_mi.api import QUANTITIES

    colour_parser = command("colour", "CIE XYZ, L*a*b*, sRGB of a saved spectrum",
                     "Colorimetry (colour-science, ASTM E308) of one quantity of a result file at one theta_i, "
                     "or of a colour-science CSV spectrum.", EXAMPLES["colour"])
    colour_parser.add_argument("file", help="result file of any kind (.nc, .csv, .json, .zarr; also `measure --json` "
                                     "output) or colour-science CSV spectra")
    colour_parser.add_argument("--theta-i", type=float, help="angle of the sweep to use (needed if it has several)")
    colour_parser.add_argument("--quantity",
                        help=f"the spectrum to use: {', '.join(QUANTITIES)} of a reading or goniophotometer "
                             "file, reading, corrected or hemispherical of a sphere file, or a column of a "
                             "colour-science CSV (default: the first: reflectance, a sphere's reading)")
    selection_option(colour_parser)
    colour_parser.add_argument("--illuminant", default="D65", help="colour.SDS_ILLUMINANTS name (default D65)")
    colour_parser.add_argument("--observer", default="CIE 1931 2 Degree Standard Observer",
                        help="colour.MSDS_CMFS name (default CIE 1931 2 degree)")
    colour_parser.add_argument("--json", action="store_true",
                        help="print one JSON object: XYZ, Lab, sRGB and its hex, coverage, note")

    plot_parser = command("plot", "a figure of any result file (or against a measured one)",
                   "Plot one quantity of a result file against theta_i (a sweep over angles: one curve per "
                   "wavelength) or wavelength (one curve per theta_i), with the band of the certified tolerance; "
                   "a goniophotometer file: its lobes (f in and across the plane of incidence, at one "
                   "wavelength), or with --quantity its R, T or A; a sphere file: its reading and the "
                   "hemispherical value of the same rays over wavelength. With --against, the result over a "
                   "measured spectrum and the residuals (as compare --plot).", EXAMPLES["plot"])
    plot_parser.add_argument("file", help="result file of any kind (.nc, .csv, .json, .zarr; also `measure --json` output)")
    plot_parser.add_argument("--quantity",
                      help=f"quantity to draw: {', '.join(QUANTITIES)} (default reflectance; a goniophotometer "
                           "file: its lobes), or reading, corrected, hemispherical of a sphere file (default both "
                           "reading and hemispherical)")
    plot_parser.add_argument("--theta-i", nargs="+", help="angles of the result to draw (default all; one with --against)")
    plot_parser.add_argument("--wavelengths", nargs="+", help="wavelengths of the result to draw, e.g. 400 550 700 or "
                                                       "400:700:50 (default all)")
    plot_parser.add_argument("--against", metavar="MEASURED", help="measured spectrum to overlay (as for compare)")
    plot_parser.add_argument("--uncertainty", type=float,
                      help="measurement uncertainty of MEASURED (overrides its uncertainty column)")
    add_measured_flags(plot_parser)
    plot_parser.add_argument("--out", help="figure .png or .svg (default: FILE with the suffix .png)")
    selection_option(plot_parser)


def selection_option(parser: argparse.ArgumentParser) -> None:
    """``--sel NAME=VALUE`` (repeatable): the label of a dim nearest VALUE, before anything is read from the result."""

    parser.add_argument("--sel", dest="selections", action="append", default=[], metavar="NAME=VALUE",
                        help="keep the label of dim NAME nearest VALUE (repeatable): a parameter point "
                             "(e.g. specimen.thickness=1.6e-4, point=3), theta_i=8, wavelength=550")


def selected(path: Any, selections: Sequence[str]) -> Any:
    """The result in ``path`` (any kind) at the labels nearest each ``--sel NAME=VALUE``; says which it took."""

    import numpy as np

    from virtspec_mi.api import read_result

    result = read_result(path)
    labels = {}
    for name, text in pairs(selections, "--sel").items():
        try:
            labels[name] = float(text)
        except ValueError:
            raise ValueError(f"--sel {name} takes a number (got {text!r})") from None
    if not labels:
        return result
    chosen = result.sel(labels, method="nearest")
    for name, value in labels.items():
        taken = float(np.asarray(chosen.coords[name]))
        if not np.isclose(taken, value, rtol=1e-9, atol=1e-12):
            print(f"virtspec: note: --sel {name}={value:g} took the nearest label, {taken:g}", file=sys.stderr)
    return chosen


def colour(args: argparse.Namespace) -> int:
    from pathlib import Path

    from virtspec_mi.colorimetry.cie import colorimetry
    from virtspec_mi.results.io import is_result_csv, read_spectra_csv

    path = Path(args.file)
    result = None
    if path.suffix.lower() == ".csv" and path.is_file() and not is_result_csv(path):
        if args.selections:
            raise ValueError("--sel selects labels of a result file; a colour-science CSV holds one spectrum per "
                             "column (pick it with --quantity)")
        quantity = args.quantity or "reflectance"
        spectra = read_spectra_csv(path)
        if quantity not in spectra:
            raise ValueError(f"quantity must be one of the file's columns {sorted(spectra)} (got {quantity!r})")
        sd = spectra[quantity]
        heading = f"{quantity} of {path}"
    else:
        result = selected(path, args.selections)
        quantity = result.check_quantity(args.quantity)
        sd = result.to_sd(quantity, args.theta_i)
        heading = f"{quantity} of {path} ({sd.name})"
    # a result's colour with certified intervals where its readings allow (issue 30), a CSV spectrum's without
    colour = (colorimetry(sd, args.illuminant, args.observer) if result is None
              else result.colour(quantity, args.theta_i, illuminant=args.illuminant, observer=args.observer))
    if args.json:
        print(json.dumps({"file": str(path), "quantity": quantity, "spectrum": heading, **colour.as_dict()}))
        return 0
    print(heading)
    print(colour.summary())
    return 0


def plot(args: argparse.Namespace) -> int:
    from dataclasses import replace
    from pathlib import Path


    from virtspec_mi.api import parse_theta_i, parse_wavelengths
    from virtspec_mi.applications.comparison import compare
    from virtspec_mi.base.files import check_distinct
    from virtspec_mi.results.plot import check_figure_path, select

    path = Path(args.file)
    against = Path(args.against) if args.against else None
    default = f"{path.stem}_vs_{against.stem}.png" if against is not None else f"{path.stem}.png"
    out = check_figure_path(args.out or path.with_name(default))
    check_distinct([("--out" if args.out else "the figure", out)], [("FILE", path), ("--against", against)])
    theta_i = parse_theta_i(" ".join(args.theta_i)) if args.theta_i else None
    wavelengths = parse_wavelengths(" ".join(args.wavelengths)) if args.wavelengths else None
    result = selected(path, args.selections)
    if against is None:
        if wavelengths is not None or theta_i is not None:
            result = select(result, wavelengths, theta_i)
        result.plot(out, quantity=args.quantity, name=path.name)
        print(f"plot: {out}")
        note = result.drawn_note(args.quantity)
        if note:
            print(note)
        return 0
    if theta_i is not None and len(theta_i) != 1:
        raise ValueError(f"--theta-i must be one angle with --against (got {len(theta_i)})")
    if wavelengths is not None:
        result = select(result, wavelengths=wavelengths)
    comparison = compare(result, measured_from(args, against), quantity=args.quantity,
                         theta_i=theta_i[0] if theta_i else None,
                         measurement_uncertainty=args.uncertainty)
    comparison = replace(comparison, result_name=path.name)
    comparison.plot(out)
    print(comparison.summary())
    print(f"plot: {out}")
    return 0
