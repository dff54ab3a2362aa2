"""
Command line: ``virtspec``
==========================

``virtspec --help`` lists the subcommands, one line each; ``virtspec COMMAND --help``
gives a subcommand's description, every flag and examples.

**Measuring** — one row each of :data:`MEASURING`, each the keyed readings of an
instrument of the registry (:data:`virtspec_mi.instruments.INSTRUMENTS`) through its API
function:

- ``virtspec measure SCENE``: one certified reading at one θi, over the scene's
  wavelengths (a spectrum) — :func:`virtspec_mi.measure`: the keyed readings of
  :func:`virtspec_mi.sweep` at that θi and one specimen parameter point, printed as one
  reading;
- ``virtspec sweep SCENE``: readings over θi × wavelength (× specimen parameters),
  :func:`virtspec_mi.sweep`; ``--densities`` (the paper's Fig. 6);
- ``virtspec gonio SCENE``: the goniophotometer, :func:`virtspec_mi.gonio` (R and T with
  their certificate and the per-θo table; ``--plot`` draws each wavelength;
  ``--plot-series``; ``--klems``: :mod:`virtspec_mi.exchange.klems_gonio`);
- ``virtspec sphere SCENE``: the integrating sphere, :func:`virtspec_mi.sphere_measure`
  (``--correct``: the reading corrected by the sphere theory, beside it).

Each takes one flag per setting of :class:`~virtspec_mi.settings.Settings` and per
option of its instrument's ``Options`` (:func:`option_flags`, the one flag builder: the
field's help, choices and default; a flag left out takes the scene's value) and the same
common flags (:data:`COMMON_FLAGS`, added by :func:`common_flags`, the one place they are
defined): ``-D NAME=VALUE`` (the XML scene's ``$NAME``, as ``mitsuba -D``),
``--param NAME=VALUES`` (repeatable; VALUES ``v1,v2,v3`` or ``start:stop:step``) and
``--points`` (:mod:`virtspec_mi.engine.parameters`), ``--out FILE`` (written atomically;
resumable: finished readings are kept in ``FILE.partial.json``,
:mod:`virtspec_mi.engine.checkpoint`), ``--plot FIG``, ``--json``, ``--quiet`` (else a
progress bar on a terminal), ``--workers N`` / ``--scheduler ADDRESS`` /
``--task-readings K`` (Dask: :mod:`virtspec_mi.scaleout`; the same counts).

**Files** — ``virtspec plot|colour|compare FILE``: every kind of result file (a
hemispherical reading or sweep, a goniophotometer reading: its R and T, or its lobes; a
sphere reading: its reading, corrected or hemispherical value), ``--sel NAME=VALUE``
(repeatable): the label of a dim nearest VALUE (a parameter point, θi, a wavelength).

**Others** — ``virtspec bounds`` (the paper's Table 1 and every ``bound=`` rule),
``virtspec albedo-table`` (:mod:`virtspec_mi.exchange.albedo`), ``virtspec scenes`` (the
shipped scenes: every ``SCENE`` argument takes their names, :mod:`virtspec_mi.scenes`),
``virtspec llvm {find,check}`` (the libLLVM Dr.Jit uses; ``make setup`` calls it).

Errors in the input (bad ranges, unreadable scenes, a bad libLLVM) print one line
``virtspec: error: …`` naming the flag (``--theta-i: theta_i must satisfy …``) and exit
with status 1; errors of the command line itself (an unknown flag, a bad choice) are
argparse's usage errors, status 2.

References
----------
Baranoski et al. (2001), eqs. (23), (24); Figs. 5 and 6.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
from pathlib import Path
import textwrap
from dataclasses import dataclass
from typing import Any, Callable, Sequence

__all__ = ["main", "build_parser", "Measuring", "MEASURING", "Flag", "COMMON_FLAGS", "common_flags", "option_flags"]


_EXAMPLES = {
    "bounds": "example: virtspec bounds --mu 0.005 --delta 0.001 0.01 0.1",
    "colour": "examples:\n  virtspec colour spectrum.csv\n"
              "  virtspec colour fig5.nc --theta-i 30 --illuminant A --quantity transmittance\n"
              "  virtspec colour lut.nc --sel specimen.thickness=1.6e-4 --sel theta_i=8\n"
              "  virtspec colour sphere.json --quantity hemispherical",
    "llvm": "example: virtspec llvm check",
    "scenes": "examples:\n  virtspec scenes\n  virtspec measure soybean_abmb --wavelengths 400:2500:5",
    "albedo-table": "examples:\n  virtspec albedo-table --engine cycles --epsilon 1e-3 --out ggx_E.nc ggx_E.h\n"
                    "  virtspec albedo-table --model glass --engine cycles --out glass.nc --checkpoint glass.parts\n"
                    "  virtspec albedo-table --from ggx_E.nc --compare published_tables.h --rounding 5e-7",
    "compare": "examples:\n  virtspec compare spectrum.nc measured.csv --plot compare.png\n"
               "  virtspec compare reading.json npsg.csv --quantity transmittance --json",
    "plot": "examples:\n  virtspec plot fig5.nc --wavelengths 400 550 700 --out fig5.png\n"
            "  virtspec plot spectrum.nc --quantity transmittance\n"
            "  virtspec plot spectrum.nc --against measured.csv --out compare.svg\n"
            "  virtspec plot brdf.nc --sel wavelength=550 --out lobes.png\n"
            "  virtspec plot lut.nc --sel specimen.thickness=1.6e-4 --sel theta_i=8",
}

_SCENE = "Mitsuba XML scene with 'emitter' and 'specimen' disks, or a shipped scene's name (virtspec scenes)"


@dataclass(frozen=True)
class Measuring:
    """A measuring subcommand: the instrument whose readings it takes and what its help says."""

    name: str
    """The subcommand."""
    instrument: str
    """Its instrument's key in :data:`virtspec_mi.instruments.INSTRUMENTS` (the flags of its ``options``)."""
    summary: str
    """One line in ``virtspec --help``."""
    description: str
    """The head of ``virtspec NAME --help``."""
    plot: str
    """What ``--plot`` draws."""
    examples: tuple[str, ...]
    """Command lines shown under ``--help`` (each runs as written from the checkout)."""
    one_reading: bool = False
    """One θi and one specimen parameter point (``measure``); else a grid of readings."""


MEASURING: dict[str, Measuring] = {row.name: row for row in (
    Measuring(
        "measure", "hemispherical", "one certified reading at one theta_i (a spectrum)",
        "Measure the specimen of a scene at one theta_i: reflectance, transmittance and absorptance per wavelength, "
        "each with the tolerance its rays guarantee and a Clopper-Pearson interval. Every setting defaults to the "
        "scene's spectrophotometer integrator, else to the paper's defaults. The readings are keyed as a sweep's "
        "(virtspec sweep --theta-i THETA gives the same counts): resumable with --out, the same on Dask workers.",
        "the reading over wavelength with the band of its certified tolerance",
        ("virtspec measure scenes/diamond_conical.xml --theta-i 70",
         "virtspec measure scenes/soybean_abmb.xml --wavelengths 400:2500:5 --bound two-stage --json",
         "virtspec measure soybean_abmb --wavelengths 400:700:10 --param specimen.thickness=2e-4 --plot leaf.png"),
        one_reading=True),
    Measuring(
        "sweep", "hemispherical", "certified readings over theta_i x wavelength (x parameters)",
        "Measure a grid of readings (wavelength x theta_i, and specimen parameters with --param) at one phi_i, each "
        "with its own rays and certificate. Without --out (or --json) the readings are printed as a CSV table on "
        "stdout and the summary goes to stderr.",
        "the readings against theta_i (one curve per wavelength) or wavelength, with the band of their certified "
        "tolerance (one parameter point: draw a parameter sweep with virtspec plot FILE --sel NAME=VALUE)",
        ("virtspec sweep scenes/diamond_collimated.xml --theta-i 0:90:1 --out fig5.nc --plot fig5.png",
         "virtspec sweep scenes/diamond_collimated.xml --theta-i 0:90:1 --densities 3 4 5 6",
         "virtspec sweep scenes/soybean_abmb.xml --theta-i 8 --wavelengths 450,550,650 "
         "--param specimen.thickness=1.2e-4:2e-4:4e-5 --param specimen.chlorophyll_a=2,4 --out lut.nc",
         "virtspec sweep scenes/soybean_abmb.xml -D side=abaxial --theta-i 8",
         "virtspec sweep scenes/soybean_abmb.xml --theta-i 8 --wavelengths 400:2500:5 --workers 2 --out leaf.nc")),
    Measuring(
        "gonio", "goniophotometer", "goniophotometer: certified BRDF/BTDF by outgoing direction",
        "Measure the specimen of a scene as the spectrophotometer does, and bin every escaping ray by its outgoing "
        "direction (theta_o, phi_o) in the specimen frame: exact counts, fractions and BRDF/BTDF per bin with their "
        "certificate (DKW for the CDFs, union bound for the bins, Clopper-Pearson intervals for f). Prints R and T "
        "with their certificate, the bins' certificate and a table with one row per theta_o bin (its centre) and "
        "one column per reading: the fraction of the incident rays leaving into that theta_o bin, summed over "
        "phi_o (the reflection rows add up to R, the transmission rows to T; each within 2 x the DKW tolerance of "
        "the CDF of theta_o); f per bin is in --out and --json.",
        "polar plots of f in and across the plane of incidence, one curve per theta_i with its certified band; "
        "several wavelengths: one figure per wavelength, FIG_<nm>nm.png",
        ("virtspec gonio scenes/diamond_collimated.xml --theta-i 30 --theta-o-bins 9 --phi-o-bins 12",
         "virtspec gonio scenes/diamond_collimated.xml --theta-i 0 30 --binning projected --fold-phi "
         "--out brdf.nc --plot brdf.png",
         "virtspec gonio scenes/soybean_abmb.xml --wavelengths 550 650 --theta-o-bins 9 --phi-o-bins 12 "
         "--fold-phi --mu 0.02 --plot leaf.png")),
    Measuring(
        "sphere", "sphere", "an integrating sphere's readout (sample over standard)",
        "Simulate an integrating-sphere instrument reading the scene's specimen: the detector fractions with the "
        "sample and with the reference standard, their certified ratio (the reading), the hemispherical reading of "
        "the same rays and the instrument error; with --correct also the reading corrected by the sphere theory, "
        "with its interval. The sphere comes from the scene's integrating_sphere integrator.",
        "the reading and the hemispherical value of the same rays over wavelength, with their certified bands; "
        "several theta_i: one figure per angle, FIG_<deg>deg.png",
        ("virtspec sphere scenes/sphere_150mm_8d.xml --specular SCE --rays 20000",
         "virtspec sphere scenes/sphere_150mm_8d.xml --method comparison --wavelengths 400:700:100 --rays 20000 "
         "--correct --out r.json")),
)}
"""The measuring subcommands: each takes the settings' flags, its instrument's and :data:`COMMON_FLAGS`."""


@dataclass(frozen=True)
class Flag:
    """One common flag: its name and ``argparse`` keywords (``{plot}`` in its help: what the subcommand draws)."""

    name: str
    keywords: dict[str, Any]
    exclusive: bool = False
    """True for the flags of which one at most may be given (where the readings are traced)."""


COMMON_FLAGS: tuple[Flag, ...] = (
    Flag("-D", dict(dest="defines", action="append", default=[], metavar="NAME=VALUE",
                    help="set the XML scene parameter $NAME (as `mitsuba -D`); repeatable")),
    Flag("--param", dict(dest="params", action="append", default=[], metavar="NAME=VALUES",
                         help="specimen parameter values, e.g. specimen.thickness=1e-4:2e-4:5e-5 (start:stop:step, "
                              "stop included) or specimen.alpha=0.1,0.2,0.4 (measure: one value); names: mi.traverse "
                              "keys of the specimen's BSDF or their short form specimen.NAME; repeatable (a grid: one "
                              "dim each)")),
    Flag("--points", dict(action="store_true",
                          help="the --param lists are explicit points (equal lengths; one dim 'point'), not a grid")),
    Flag("--out", dict(metavar="FILE",
                       help="result file .nc, .csv, .json or .zarr, written atomically once every reading is done; "
                            "finished readings are kept in FILE.partial.json meanwhile: re-run the same command to "
                            "resume (virtspec plot, colour and compare read the file)")),
    Flag("--plot", dict(metavar="FIG", help="figure .png or .svg: {plot}")),
    Flag("--json", dict(action="store_true",
                        help="print the result as one JSON object instead (its as_dict(): a result file that "
                             "virtspec plot, colour and compare read)")),
    Flag("--quiet", dict(action="store_true",
                         help="no progress bar and no notes on stderr; with --out nothing on stdout (default: a "
                              "progress bar on stderr when it is a terminal and the readings last more than ~2 s)")),
    Flag("--workers", dict(type=int, metavar="N",
                           help="trace on a local Dask cluster of N worker processes (default: in this process; the "
                                "same counts)"), exclusive=True),
    Flag("--scheduler", dict(metavar="ADDRESS",
                             help="trace on the Dask cluster of this scheduler, e.g. tcp://host:8786 (every worker "
                                  "needs virtspec-mi installed and the scene file at the same path)"), exclusive=True),
    Flag("--task-readings", dict(type=int, metavar="K",
                                 help="readings per Dask task (default: scaleout.TASK_SECONDS of tracing, from the "
                                      "measured ray rate)")),
)
"""The flags every measuring subcommand takes, defined once (:func:`common_flags` adds them)."""

_SEVERAL = {"theta_i": "parse_theta_i"}
"""Settings a grid subcommand takes as several values, and the parser of :mod:`virtspec_mi.checks` that reads them."""


class _Listing(argparse.HelpFormatter):
    """``virtspec --help``: every subcommand with its summary on one line (``albedo-table`` included)."""

    def __init__(self, prog: str) -> None:
        super().__init__(prog, max_help_position=30)

    def _format_action(self, action: argparse.Action) -> str:
        self._action_max_length = max(self._action_max_length, 18)  # the longest subcommand, indented
        return super()._format_action(action)


def build_parser() -> argparse.ArgumentParser:
    """The ``virtspec`` argument parser (the measurement flags come from the options' fields)."""

    from virtspec_mi import __version__
    from virtspec_mi.kernel.counts import QUANTITIES

    parser = argparse.ArgumentParser(
        prog="virtspec", description="Virtual spectrophotometer: certified reflectance, transmittance and "
                                     "absorptance readings of Mitsuba BSDFs (Baranoski, Rokne & Xu 2001).",
        epilog="virtspec COMMAND --help: its flags and examples.",
        formatter_class=_Listing)
    parser.add_argument("--version", action="version", version=f"virtspec-mi {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, summary: str, description: str, examples: str | None = None) -> argparse.ArgumentParser:
        return commands.add_parser(name, help=summary, description=textwrap.fill(description, 100),
                                   epilog=_EXAMPLES[name] if examples is None else examples,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)

    bounds = command("bounds", "rays per reading under every ray budget (Table 1)",
                     "Rays per reading that certify |m/N - rho| < mu with probability >= 1 - delta: the "
                     "paper's Table 1 (eqs. 15 and 23), then every rule of bound=.")
    bounds.add_argument("--mu", type=float, default=0.005, help="certified tolerance (default 0.005)")
    bounds.add_argument("--delta", type=float, nargs="+", default=[0.001, 0.01, 0.1],
                        help="failure probabilities (default 0.001 0.01 0.1)")

    measuring = {row.name: command(row.name, row.summary, row.description,
                                   "examples:\n" + "\n".join(f"  {line}" for line in row.examples))
                 for row in MEASURING.values()}
    for row in MEASURING.values():
        measuring[row.name].add_argument(
            "scene", help=_SCENE if row.name != "sphere" else
            "Mitsuba XML scene with an integrating_sphere integrator and 'emitter' and 'specimen' disks")
        option_flags(measuring[row.name], _settings(), words=_several(row))
        options = _instrument_options(row)
        if options is not None:
            option_flags(measuring[row.name], options)
        common_flags(measuring[row.name], row)
    measuring["sweep"].add_argument(
        "--densities", type=float, nargs="+", metavar="LOG10N",
        help="sweep at N = 10^d rays for each d; print seconds and the fluctuation of eq. (24)")
    _gonio_flags(measuring["gonio"])
    _correction_flags(measuring["sphere"])

    colour = command("colour", "CIE XYZ, L*a*b*, sRGB of a saved spectrum",
                     "Colorimetry (colour-science, ASTM E308) of one quantity of a result file at one theta_i, "
                     "or of a colour-science CSV spectrum.")
    colour.add_argument("file", help="result file of any kind (.nc, .csv, .json, .zarr; also `measure --json` "
                                     "output) or colour-science CSV spectra")
    colour.add_argument("--theta-i", type=float, help="angle of the sweep to use (needed if it has several)")
    colour.add_argument("--quantity",
                        help=f"the spectrum to use: {', '.join(QUANTITIES)} of a reading or goniophotometer "
                             "file, reading, corrected or hemispherical of a sphere file, or a column of a "
                             "colour-science CSV (default: the first: reflectance, a sphere's reading)")
    _selection_option(colour)
    colour.add_argument("--illuminant", default="D65", help="colour.SDS_ILLUMINANTS name (default D65)")
    colour.add_argument("--observer", default="CIE 1931 2 Degree Standard Observer",
                        help="colour.MSDS_CMFS name (default CIE 1931 2 degree)")
    colour.add_argument("--json", action="store_true",
                        help="print one JSON object: XYZ, Lab, sRGB and its hex, coverage, note")

    compare = command("compare", "a result against a measured spectrum (residuals, Delta E)",
                      "Compare one quantity of a result file at one theta_i with a measured spectrum over their "
                      "common wavelengths (the measured one interpolated onto the result's, never extrapolated): "
                      "residuals, RMSE, the share of points within the certified tolerance (+ the measurement "
                      "uncertainty) and Delta E 2000. MEASURED: a colour-science CSV spectral file, a plain "
                      "wavelength,value[,uncertainty] CSV, a NetCDF file or another result file.")
    compare.add_argument("result", help="result file of any kind (.nc, .csv, .json, .zarr; also `measure --json` "
                                        "output)")
    compare.add_argument("measured", help="measured spectrum (.csv, .txt, .nc, or a result file)")
    _comparison_options(compare)
    _selection_option(compare)
    compare.add_argument("--plot", help="figure .png or .svg: both spectra and the residuals")
    compare.add_argument("--json", action="store_true", help="print the comparison as one JSON object")

    plot = command("plot", "a figure of any result file (or against a measured one)",
                   "Plot one quantity of a result file against theta_i (a sweep over angles: one curve per "
                   "wavelength) or wavelength (one curve per theta_i), with the band of the certified tolerance; "
                   "a goniophotometer file: its lobes (f in and across the plane of incidence, at one "
                   "wavelength), or with --quantity its R, T or A; a sphere file: its reading and the "
                   "hemispherical value of the same rays over wavelength. With --against, the result over a "
                   "measured spectrum and the residuals (as compare --plot).")
    plot.add_argument("file", help="result file of any kind (.nc, .csv, .json, .zarr; also `measure --json` output)")
    plot.add_argument("--quantity",
                      help=f"quantity to draw: {', '.join(QUANTITIES)} (default reflectance; a goniophotometer "
                           "file: its lobes), or reading, corrected, hemispherical of a sphere file (default both "
                           "reading and hemispherical)")
    plot.add_argument("--theta-i", nargs="+", help="angles of the result to draw (default all; one with --against)")
    plot.add_argument("--wavelengths", nargs="+", help="wavelengths of the result to draw, e.g. 400 550 700 or "
                                                       "400:700:50 (default all)")
    plot.add_argument("--against", metavar="MEASURED", help="measured spectrum to overlay (as for compare)")
    plot.add_argument("--uncertainty", type=float,
                      help="measurement uncertainty of MEASURED (overrides its uncertainty column)")
    plot.add_argument("--out", help="figure .png or .svg (default: FILE with the suffix .png)")
    _selection_option(plot)

    albedo = command("albedo-table", "certified directional-albedo tables E(mu, alpha)",
                     "Measure Mitsuba's rough conductor (Fresnel = 1) or rough glass on an engine's grid (or "
                     "your own): every E(mu, alpha[, eta]) and E_avg within --epsilon of the model's value, the "
                     "whole table at once with probability >= 1 - delta; NetCDF, .npy and a C header in Cycles' "
                     "layout; --compare lists every cell of a published table outside the certified interval.")
    _albedo_options(albedo)

    command("scenes", "the shipped scenes (every SCENE argument takes their names)",
            "List the scenes shipped with virtspec-mi. Every subcommand that takes a SCENE takes a shipped "
            "scene's name as well as a file path (e.g. virtspec measure soybean_abmb).")

    llvm = command("llvm", "find or check the libLLVM Dr.Jit uses (set-up)",
                   "find: print a libLLVM >= 17 on this machine (exit 1 if none); check: load it in Dr.Jit "
                   "and print its version, or say how to fix it.")
    llvm.add_argument("action", choices=["find", "check"])
    return parser


def common_flags(parser: argparse.ArgumentParser, command: Measuring) -> None:
    """
    Add :data:`COMMON_FLAGS` to the measuring subcommand ``command`` (its ``--plot`` help
    says what it draws): the one place the common flags are added.
    """

    group = parser.add_argument_group("common flags (every measuring subcommand)")
    exclusive = group.add_mutually_exclusive_group()
    for flag in COMMON_FLAGS:
        keywords = dict(flag.keywords, help=flag.keywords["help"].format(plot=command.plot))
        (exclusive if flag.exclusive else group).add_argument(flag.name, **keywords)


def _gonio_flags(parser: argparse.ArgumentParser) -> None:
    """The goniophotometer's own flags beside its options: the series figure and the Klems matrices."""

    group = parser.add_argument_group("goniophotometer figures and Klems matrices")
    group.add_argument("--plot-series", metavar="FIG",
                       help="figure .png or .svg: the distribution over theta_i as a series (f in the plane of "
                            "incidence and the CDF of theta_o, certified bands); several wavelengths: one figure "
                            "per wavelength")
    group.add_argument("--klems", metavar="FILE", help="measure the Klems matrices instead (incidence at every patch "
                       "centre, front and back; --mu is the certified tolerance of every patch fraction) and write "
                       "WINDOW 6 XML FILE with its NetCDF sidecar FILE.nc")
    group.add_argument("--klems-basis", choices=("full", "half", "quarter"), default="full",
                       help="Klems basis of --klems (145, 77 or 41 patches; default full)")
    group.add_argument("--isotropic", action="store_true",
                       help="--klems: one reading per ring, rotated onto its other patches (rotation-invariant "
                            "specimens)")


_CORRECTION = {
    "specular_reflectance": "the specimen's specular (mirror) reflectance at the beam's angle, 0 ... 1 (reflectance "
                            "readings; default 0: a matte specimen)",
    "sample_reflectance": "the specimen's reflectance for diffuse light from inside the sphere, 0 ... 1 (required "
                          "for a transmittance reading; a reflectance reading: default the corrected value itself, "
                          "a Lambertian specimen)",
    "collimated_transmittance": "the unscattered part of a transmittance reading, 0 ... 1 (default 0)",
}
"""What the sphere theory's correction assumes: :meth:`~virtspec_mi.results.sphere.SphereResult.corrected`."""


def _correction_flags(parser: argparse.ArgumentParser) -> None:
    """``sphere --correct`` and what the correction assumes (each implies ``--correct``)."""

    group = parser.add_argument_group("correction by the sphere theory")
    group.add_argument("--correct", action="store_true",
                       help="also print the reading corrected by the sphere theory (the hemispherical value it "
                            "implies) and its interval, beside the reading (--json: corrected, corrected_interval)")
    for name, text in _CORRECTION.items():
        group.add_argument("--" + name.replace("_", "-"), metavar="VALUE", help=f"{text}; implies --correct")


def _selection_option(parser: argparse.ArgumentParser) -> None:
    """``--sel NAME=VALUE`` (repeatable): the label of a dim nearest VALUE, before anything is read from the result."""

    parser.add_argument("--sel", dest="selections", action="append", default=[], metavar="NAME=VALUE",
                        help="keep the label of dim NAME nearest VALUE (repeatable): a parameter point "
                             "(e.g. specimen.thickness=1.6e-4, point=3), theta_i=8, wavelength=550")


def _selected(path: Any, selections: Sequence[str]) -> Any:
    """The result in ``path`` (any kind) at the labels nearest each ``--sel NAME=VALUE``; says which it took."""

    import numpy as np

    from virtspec_mi.results.kinds import read_result

    result = read_result(path)
    labels = {}
    for name, text in _pairs(selections, "--sel").items():
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


def _pairs(items: Sequence[str], flag: str) -> dict[str, str]:
    """``NAME=VALUE`` strings of a repeatable flag as a dict (``ValueError`` naming the flag)."""

    pairs: dict[str, str] = {}
    for item in items:
        name, equals, value = item.partition("=")
        name, value = name.strip(), value.strip()
        if not equals or not name or not value:
            raise ValueError(f"{flag} takes NAME=VALUE (got {item!r})")
        if name in pairs:
            raise ValueError(f"{flag} {name} is given twice")
        pairs[name] = value
    return pairs


def _several(command: Measuring) -> tuple[str, ...]:
    """The settings ``command`` takes as several values (:data:`_SEVERAL`): none for one reading."""

    return () if command.one_reading else tuple(_SEVERAL)


def _settings() -> Any:
    """The common :class:`~virtspec_mi.settings.Settings` class, imported when the parser is built."""

    from virtspec_mi.settings import Settings

    return Settings


def _instrument_options(command: Measuring) -> Any:
    """The ``Options`` class of ``command``'s instrument (:data:`virtspec_mi.instruments.INSTRUMENTS`), or ``None``."""

    from virtspec_mi.instruments import INSTRUMENTS

    return INSTRUMENTS[command.instrument].options


def _flag(name: str) -> str:
    """The command-line flag of option ``name``: ``--theta-i``."""

    return "--" + name.replace("_", "-")


def option_flags(parser: argparse.ArgumentParser, kind: Any, words: tuple[str, ...] = ()) -> None:
    """
    The one flag builder: one flag per option of ``kind`` (an
    :class:`~virtspec_mi.settings.Options` class: ``--theta-i`` …), in a group named by its
    ``title``, its choices, default and help from the field; a switch (a ``bool`` default)
    is a flag without a value, an option the command line writes as several words (the
    field's ``words``, or one named in ``words``) takes them all. Values go to the options
    as given (they validate them: :func:`_given`); a flag left out takes the scene's value,
    else the default.
    """

    from dataclasses import fields

    from virtspec_mi.settings import help_text, shown

    group = parser.add_argument_group(kind.title)
    for item in fields(kind):
        meta = item.metadata
        if not meta["flag"]:
            continue
        default = f"default: the scene's, else {shown(item.default) if item.default is not None else meta['unset']}"
        several = "; several values or start:stop:step ranges, one reading each" if item.name in words else ""
        text = f"{help_text(item)}{several} ({default})"
        if isinstance(item.default, bool):
            group.add_argument(_flag(item.name), action="store_true", default=None, help=text)
        else:
            group.add_argument(_flag(item.name), nargs="+" if meta["words"] or item.name in words else None,
                               choices=list(meta["choices"]) if meta["choices"] else None, help=text)


def _given(args: argparse.Namespace, kind: Any, several: tuple[str, ...] = ()) -> dict[str, Any]:
    """
    The options of ``kind`` given on the command line (several words joined into one
    string), each checked here by its field's own check — or, for one named in
    ``several``, by its parser in :data:`_SEVERAL` — so that a bad value names its flag
    (``--theta-i: theta_i must satisfy …``) before any scene is loaded; the API validates
    them again (the same checks).
    """

    from dataclasses import fields

    from virtspec_mi import checks

    given = {}
    for item in fields(kind):
        value = getattr(args, item.name, None) if item.metadata["flag"] else None
        if value is None:
            continue
        value = " ".join(value) if isinstance(value, list) else value
        check = getattr(checks, _SEVERAL[item.name]) if item.name in several else item.metadata["check"]
        try:
            check(value)
        except ValueError as error:
            raise ValueError(f"{_flag(item.name)}: {error}") from None
        given[item.name] = value
    return given


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``virtspec``; returns the exit status."""

    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # a closed pipe (virtspec bounds | head) ends us quietly
    from virtspec_mi.engine.interrupts import catching, exit_status

    # SIGINT and SIGTERM stop a run at its next safe point, its checkpoint saved; taken from the start, so a
    # Ctrl-C while the modules load (the parser imports numpy) is an interrupt too, never a traceback
    with catching():
        try:
            args = build_parser().parse_args(argv)
        except KeyboardInterrupt as stop:
            return _interrupted(stop, argparse.Namespace(), exit_status)
        return _command(args, exit_status)


def _command(args: argparse.Namespace, exit_status: Any) -> int:
    """Run the command of ``args``; an error or an interrupt becomes a one-line message and the exit status."""

    try:
        if args.command == "bounds":
            from virtspec_mi.budgets.bounds import format_table_1
            from virtspec_mi.budgets.rules import format_budgets

            print(format_table_1(args.mu, args.delta))
            print()
            print(format_budgets(args.mu, args.delta))
            return 0
        if args.command == "scenes":
            from virtspec_mi.scenes import catalogue

            print(catalogue())
            return 0
        if args.command == "llvm":
            from virtspec_mi.llvm import main as llvm_main

            return llvm_main([args.action])
        handlers = {"measure": _measure, "sweep": _sweep, "gonio": _gonio, "sphere": _sphere, "colour": _colour,
                    "compare": _compare, "plot": _plot, "albedo-table": _albedo_table}
        return handlers[args.command](args)
    except KeyboardInterrupt as stop:  # Ctrl-C (SIGINT) or SIGTERM: virtspec_mi.engine.interrupts.Interrupted
        return _interrupted(stop, args, exit_status)
    except Exception as error:
        from virtspec_mi.engine.interrupts import received

        if received() is not None:  # an interrupt raised inside an import or a C extension comes out as another error
            return _interrupted(KeyboardInterrupt(received()), args, exit_status, received())
        if not isinstance(error, (ValueError, RuntimeError, OSError)):
            raise
        print(f"virtspec: error: {_rescued(error)}", file=sys.stderr)
        return 1


def _interrupted(stop: BaseException, args: argparse.Namespace, exit_status: Any, signum: int | None = None) -> int:
    """The one line and the exit status (130, 143) of a command stopped by a signal, naming its checkpoint."""

    signum = signum or getattr(stop, "signum", signal.SIGINT)
    # the checkpoint of the run under way: named by the run, else the one the command set (_sweep)
    partial = getattr(stop, "checkpoint", None) or getattr(args, "checkpoint", None)
    written = getattr(stop, "written", None)  # the run had finished: its file written whole, nothing to resume
    kept = f" (the run had finished: its result is written to {written})" if written is not None else \
        "" if partial is None else (
        f" (finished readings are kept in {partial}: re-run the same command to resume)" if Path(partial).exists()
        else " (no reading had finished: nothing to resume)")
    word = "interrupted" if signum == signal.SIGINT else f"terminated by {signal.Signals(signum).name}"
    print(f"virtspec: {word}{kept}", file=sys.stderr)
    return exit_status(signum)


def _rescued(error: BaseException) -> Any:
    """The error; for a result kept only in memory (its file could not be written), where it was written instead."""

    from virtspec_mi.files import IN_MEMORY

    if getattr(error, "result", None) is None or not error.kept.endswith(IN_MEMORY):  # type: ignore[attr-defined]
        return error
    from virtspec_mi.results.io import rescue

    kept = error.kept[:-len(IN_MEMORY)] + rescue(error.result, error.path)  # type: ignore[attr-defined]
    return error.keeping(kept)  # type: ignore[attr-defined]


# --- the measuring subcommands ---------------------------------------------------------------


def _keywords(args: argparse.Namespace, command: Measuring) -> dict[str, Any]:
    """
    The API keywords of a measuring subcommand's flags — the settings and its instrument's
    options given (each checked, naming its flag: :func:`_given`) and the common flags —
    checked before any scene is loaded or ray traced: the ``--out`` suffix and folder, the
    figures' suffixes, one reading for ``measure``, no parameter sweep to draw.
    """

    from virtspec_mi.results.io import check_output
    from virtspec_mi.results.plot import check_figure_path

    out = _flagged("--out", check_output, args.out) if args.out else None
    figures = {flag: getattr(args, flag.lstrip("-").replace("-", "_"), None) for flag in ("--plot", "--plot-series")}
    for flag, path in figures.items():
        _flagged(flag, check_figure_path, path)
    settings = _given(args, _settings(), several=_several(command))
    options = _instrument_options(command)
    parameters = _pairs(args.params, "--param")
    if command.one_reading:
        _check_one_reading(command, parameters)
    else:
        drawn = [flag for flag, path in figures.items() if path]
        if parameters and drawn:
            raise ValueError(f"{drawn[0]} draws a sweep over wavelength x theta_i at one parameter point: write the "
                             "parameter sweep with --out FILE, then draw a point with virtspec plot FILE --sel "
                             "NAME=VALUE")
    return {**settings, **({} if options is None else _given(args, options)), "parameters": parameters,
            "points": args.points, "defines": _pairs(args.defines, "-D"), "out": out,
            "progress": False if args.quiet else None,
            "workers": args.scheduler if args.scheduler is not None else args.workers,
            "task_readings": args.task_readings}


def _check_one_reading(command: Measuring, parameters: dict[str, str]) -> None:
    """``measure`` reads one value of each specimen parameter (``sweep`` takes several; its one θi: one flag value)."""

    from virtspec_mi.checks import parse_values

    for name, values in parameters.items():
        count = len(parse_values(name, values))
        if count != 1:
            raise ValueError(f"--param {name}: {command.name} takes one value per parameter (got {count}; virtspec "
                             "sweep takes several)")


def _flagged(flag: str, check: Callable[[Any], Any], value: Any) -> Any:
    """``check(value)``; its ``ValueError`` names ``flag`` (``--out: out must end in …``)."""

    try:
        return check(value)
    except ValueError as error:
        raise ValueError(f"{flag}: {error}") from None


_KEYWORD_FLAGS = {"parameters": "--param", "defines": "-D", "progress": None}
"""The API keywords whose flag is not their name with dashes (``None``: no flag)."""


def _run(args: argparse.Namespace, function: Callable[..., Any], keywords: dict[str, Any]) -> Any:
    """
    ``function(args.scene, **keywords)``; the checkpoint of its ``out`` is named if it is
    interrupted (:func:`main`). A ``ValueError`` whose message starts with the name of a
    keyword given (a rule between options that needs the scene's values, e.g.
    ``pilot_delta must satisfy 0 < pilot_delta < delta``) names that keyword's flag.
    """

    from virtspec_mi.engine.checkpoint import checkpoint_for

    out = keywords["out"]
    args.checkpoint = checkpoint_for(out) if out is not None else None
    try:
        return function(args.scene, **keywords)
    except ValueError as error:
        named = [name for name, value in keywords.items()
                 if not (value is None or value is False or value == {}) and str(error).startswith(name + " ")]
        flags = {**_KEYWORD_FLAGS, "workers": "--workers" if args.scheduler is None else "--scheduler"}
        flag = flags.get(named[0], _flag(named[0])) if named else None
        if flag is None:
            raise
        raise ValueError(f"{flag}: {error}") from error


_UNITS = {"wavelength": "nm", "theta_i": "deg"}
"""The dims a figure is drawn for one label at a time, and the unit in its file name."""


def _drawn(path: str | None, draw: Callable[..., Any], dim: str = "", labels: Sequence[float] = ()) -> list[Any]:
    """
    The figure ``path`` drawn by ``draw(path)`` (nothing without a path); with several
    ``labels`` of ``dim`` (a figure shows one: the goniophotometer's lobes one wavelength,
    a sphere spectrum one θi), one figure per label, ``FIG_550nm.png`` / ``FIG_8deg.png``,
    each by ``draw(path, dim=label)``. The paths drawn.
    """

    from pathlib import Path

    if not path:
        return []
    path = Path(path)
    if len(labels) <= 1:
        draw(path)
        return [path]
    drawn = []
    for label in labels:
        each = path.with_name(f"{path.stem}_{float(label):g}{_UNITS[dim]}{path.suffix}")
        draw(each, **{dim: float(label)})
        drawn.append(each)
    return drawn


def _report(args: argparse.Namespace, result: Any, text: str, figures: Sequence[Any] = (),
            data: dict[str, Any] | None = None, stream: Any = None) -> int:
    """
    What a measuring subcommand prints: with ``--json`` the result as one JSON object
    (``data``, default its ``as_dict()``); else ``text`` and the files written
    (``written: FILE``, ``plot: FIG``) on ``stream`` (default stdout) — nothing with
    ``--quiet`` and ``--out`` (the file holds the result).
    """

    if args.json:
        print(result.sealed_json() if data is None else json.dumps(data))
        return 0
    if args.quiet and args.out:
        return 0
    lines = [text, *([f"written: {args.out}"] if args.out else []), *(f"plot: {path}" for path in figures)]
    print("\n".join(lines), file=stream or sys.stdout)
    return 0


def _measure(args: argparse.Namespace) -> int:
    """``virtspec measure``: the readings of a sweep at one θi and one parameter point, as one reading."""

    from virtspec_mi.api import sweep

    result = _run(args, sweep, _keywords(args, MEASURING["measure"]))
    reading = result.squeeze(*(d for d in result.dims if d != "wavelength"))
    return _report(args, reading, reading.summary(), _drawn(args.plot, reading.plot))


def _sweep(args: argparse.Namespace) -> int:
    """``virtspec sweep``: without ``--out`` (or ``--json``) the CSV table on stdout, the summary on stderr."""

    from virtspec_mi.api import sweep
    from virtspec_mi.results.io import csv_text

    keywords = _keywords(args, MEASURING["sweep"])
    if args.densities:
        return _densities(args, keywords)
    result = _run(args, sweep, keywords)
    figures = _drawn(args.plot, result.plot)
    if keywords["out"] is not None or args.json:
        return _report(args, result, result.summary(), figures)
    if not args.quiet:  # the summary on stderr, so that the table can be piped
        _report(args, result, result.summary(), figures, stream=sys.stderr)
    print(csv_text(result.to_dataset()), end="")
    return 0


def _densities(args: argparse.Namespace, keywords: dict[str, Any]) -> int:
    """``--densities``: a sweep per ray density (on one cluster when workers are asked for)."""

    if "rays" in keywords:
        raise ValueError("--rays and --densities exclude each other (densities set N = 10^d)")
    if args.json:
        raise ValueError("--json prints one result and --densities a table of seconds and Delta per density: give "
                         "one of them")
    _check_densities(args.densities)
    if keywords["workers"] is None:
        return _each_density(args, keywords)
    from virtspec_mi.scaleout import connect

    with connect(keywords["workers"]) as client:  # one cluster (or connection) for every density
        return _each_density(args, {**keywords, "workers": client})


def _each_density(args: argparse.Namespace, keywords: dict[str, Any]) -> int:
    """A sweep per ray density, its seconds and the fluctuation Δ against the previous one (eq. 24, Fig. 6)."""

    from virtspec_mi.api import fluctuation, sweep
    from virtspec_mi.results.plot import plot_densities

    # Fig. 6b: time linear in N. The first sweep compiles the kernel (Dr.Jit caches it for every
    # N): run it once at the smallest density first, so no density's seconds include compilation.
    warm_up = sweep(args.scene, rays=int(round(10.0 ** min(args.densities))),
                    **{**keywords, "out": None, "progress": False})
    out, results, deltas = keywords["out"], [], [float("nan")]
    print(f"{'log10 N':>8} {'N':>12} {'seconds':>9} {'Delta (eq. 24)':>15}")
    for density in args.densities:
        rays = int(round(10.0 ** density))
        path = out.with_name(f"{out.stem}_logN{density:g}{out.suffix}") if out is not None else None
        results.append(_run(args, sweep, {**keywords, "rays": rays, "out": path}))
        if len(results) > 1:
            deltas.append(fluctuation(results[-2], results[-1]))
        delta_text = "" if len(results) == 1 else f"{deltas[-1]:.6f}"
        print(f"{density:>8g} {rays:>12,} {results[-1].seconds:>9.3f} {delta_text:>15}", flush=True)
    print(f"(seconds after a warm-up sweep at log10 N = {min(args.densities):g}, {warm_up.seconds:.3f} s, "
          "which compiled the kernel" + ("; on workers: tracing seconds summed over the workers, not wall time)"
                                         if keywords["workers"] is not None else ")"))
    if args.plot:
        plot_densities(results, args.densities, deltas, args.plot)
    return 0


def _gonio(args: argparse.Namespace) -> int:
    """``virtspec gonio``: the summary (R and T, the bins' certificate, the per-θo table); a figure per wavelength."""

    from virtspec_mi.api import gonio

    if args.klems:
        return _klems(args)
    reading = _run(args, gonio, _keywords(args, MEASURING["gonio"]))
    figures = (_drawn(args.plot, reading.plot, "wavelength", reading.wavelengths)
               + _drawn(args.plot_series, reading.plot_series, "wavelength", reading.wavelengths))
    return _report(args, reading, reading.summary(), figures)


def _sphere(args: argparse.Namespace) -> int:
    """``virtspec sphere``: the summary, and with ``--correct`` the corrected readings beside the readings."""

    import numpy as np

    from virtspec_mi.api import sphere_measure
    from virtspec_mi.results.base import plain_data

    assumptions = _assumptions(args)  # checked before any tracing
    result = _run(args, sphere_measure, _keywords(args, MEASURING["sphere"]))
    text, data = result.summary(), None
    if assumptions is not None:
        corrected, interval = _corrected(result, assumptions)
        text += "\n" + _correction_table(result, corrected, interval, assumptions)
        data = {**result.as_dict(), "corrected": plain_data(corrected), "corrected_interval": plain_data(interval),
                "correction": assumptions}
    angles = np.atleast_1d(result.coords["theta_i"])
    return _report(args, result, text, _drawn(args.plot, result.plot, "theta_i", angles), data)


def _assumptions(args: argparse.Namespace) -> dict[str, float] | None:
    """
    What ``sphere --correct`` assumes (the flags of :data:`_CORRECTION` given, each a
    number in [0, 1]), or ``None`` when no correction is asked for.
    """

    from virtspec_mi.checks import number

    given = {name: getattr(args, name) for name in _CORRECTION if getattr(args, name) is not None}
    if not (args.correct or given):
        return None
    assumptions = {}
    for name, text in given.items():
        try:
            value = number(name, text)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"{name} must satisfy 0 <= {name} <= 1 (got {text})")
        except ValueError as error:
            raise ValueError(f"{_flag(name)}: {error}") from None
        assumptions[name] = value
    return assumptions


def _corrected(result: Any, assumptions: dict[str, float]) -> tuple[Any, Any]:
    """
    :meth:`~virtspec_mi.results.sphere.SphereResult.corrected` and
    :meth:`~virtspec_mi.results.sphere.SphereResult.corrected_interval` of every reading
    of ``result`` (one spectrum per θi and parameter point), over its reading dims.
    """

    import numpy as np

    dims = list(result.reading_dims)
    other = [d for d in dims if d != "wavelength"]
    values, interval = np.full(np.shape(result.reading), np.nan), np.full(np.shape(result.reading_interval), np.nan)
    for index in np.ndindex(*(result.sizes[d] for d in other)):
        spectrum = result.isel(dict(zip(other, index)))
        at = tuple(index[other.index(d)] if d in other else slice(None) for d in dims)
        try:
            values[at] = spectrum.corrected(**assumptions)
            interval[at] = spectrum.corrected_interval(**assumptions)
        except ValueError as error:  # what the sphere theory needs to be told (e.g. a transmittance reading)
            raise ValueError(f"--correct: {error}") from None
    return values, interval


def _correction_table(result: Any, corrected: Any, interval: Any, assumptions: dict[str, float]) -> str:
    """Each reading with its interval, beside the corrected reading with its interval, and the hemispherical value."""

    import numpy as np

    taken = {"specular_reflectance": "0 (matte)", "sample_reflectance": "the corrected value (Lambertian)",
             "collimated_transmittance": "0"}
    if result.options["measurement"] == "reflectance":
        del taken["collimated_transmittance"]
    else:
        del taken["specular_reflectance"]
    taken.update({name: f"{value:g}" for name, value in assumptions.items()})
    labels = list(result.reading_dims)
    lines = ["corrected by the sphere theory (" + ", ".join(f"{name} = {value}" for name, value in taken.items())
             + "; the theory's sphere: flat ports, no baffle): the hemispherical value each reading implies, and",
             f"the reading interval's image: it holds the corrected expected reading with probability >= "
             f"{1 - result.delta:g} (the theory's own error is not in it)",
             " ".join(f"{'lambda/nm' if d == 'wavelength' else d:>10}" for d in labels)
             + "    reading  [interval]              corrected  [interval]              hemispherical"]
    reading, bounds = result.reading, result.reading_interval
    for index in np.ndindex(*(result.sizes[d] for d in labels)):
        at = " ".join(f"{float(np.atleast_1d(result.coords[d])[k]):>10g}" for d, k in zip(labels, index))
        lines.append(f"{at}    {reading[index]:.5f}  [{bounds[index][0]:.5f}, {bounds[index][1]:.5f}]    "
                     f"{corrected[index]:.5f}  [{interval[index][0]:.5f}, {interval[index][1]:.5f}]    "
                     f"{result.hemispherical[index]:.5f}")
    return "\n".join(lines)


def _check_densities(densities: Sequence[float]) -> None:
    """Each log10 N of ``--densities`` must give 1 <= N = 10^d <= 2**32 - 1 rays per reading."""

    import math

    from virtspec_mi.checks import MAX_RAYS

    highest = math.log10(MAX_RAYS)
    for density in densities:
        if not 0.0 <= density <= highest:
            raise ValueError(f"densities must satisfy 0 <= log10 N <= {highest:.2f} (N = 10^d rays per reading, "
                             f"at most 2**32 - 1; got {density:g})")


def _colour(args: argparse.Namespace) -> int:
    from pathlib import Path

    from virtspec_mi.results.colorimetry import colorimetry
    from virtspec_mi.results.io import is_result_csv, read_spectra_csv

    path = Path(args.file)
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
        result = _selected(path, args.selections)
        quantity = result.check_quantity(args.quantity)
        sd = result.to_sd(quantity, args.theta_i)
        heading = f"{quantity} of {path} ({sd.name})"
    colour = colorimetry(sd, args.illuminant, args.observer)
    if args.json:
        print(json.dumps({"file": str(path), "quantity": quantity, "spectrum": heading, **colour.as_dict()}))
        return 0
    print(heading)
    print(colour.summary())
    return 0


def _comparison_options(parser: argparse.ArgumentParser) -> None:
    """The flags of ``virtspec compare``: quantity, theta_i, uncertainty, illuminant, observer."""

    from virtspec_mi.kernel.counts import QUANTITIES

    parser.add_argument("--quantity",
                        help=f"quantity compared: {', '.join(QUANTITIES)} of a reading or goniophotometer file "
                             "(the measured column of that name; default reflectance), or reading, corrected, "
                             "hemispherical of a sphere file (default reading; the measured column of what the "
                             "sphere measures)")
    parser.add_argument("--theta-i", type=float, help="angle of the result to use (needed if it has several)")
    parser.add_argument("--uncertainty", type=float,
                        help="measurement uncertainty, added to the certified tolerance (overrides the file's "
                             "uncertainty column)")
    parser.add_argument("--illuminant", default="D65", help="colour.SDS_ILLUMINANTS name for Delta E 2000 "
                                                            "(default D65)")
    parser.add_argument("--observer", default="CIE 1931 2 Degree Standard Observer",
                        help="colour.MSDS_CMFS name (default CIE 1931 2 degree)")


def _compare(args: argparse.Namespace) -> int:
    from dataclasses import replace
    from pathlib import Path

    from virtspec_mi.comparison import compare
    from virtspec_mi.results.plot import check_figure_path

    check_figure_path(args.plot)  # a bad suffix fails before any work
    result = _selected(args.result, args.selections)
    comparison = compare(result, args.measured, quantity=args.quantity, theta_i=args.theta_i,
                         measurement_uncertainty=args.uncertainty, illuminant=args.illuminant,
                         observer=args.observer)
    comparison = replace(comparison, result_name=Path(args.result).name)
    if args.plot:
        comparison.plot(args.plot)
    if args.json:
        print(json.dumps(comparison.as_dict()))
        return 0
    print(comparison.summary())
    if args.plot:
        print(f"plot: {args.plot}")
    return 0


def _plot(args: argparse.Namespace) -> int:
    from dataclasses import replace
    from pathlib import Path

    import numpy as np

    from virtspec_mi.checks import parse_theta_i, parse_wavelengths
    from virtspec_mi.comparison import compare
    from virtspec_mi.results.goniophotometer import GonioResult
    from virtspec_mi.results.plot import check_figure_path, select

    path = Path(args.file)
    against = Path(args.against) if args.against else None
    default = f"{path.stem}_vs_{against.stem}.png" if against is not None else f"{path.stem}.png"
    out = check_figure_path(args.out or path.with_name(default))
    theta_i = parse_theta_i(" ".join(args.theta_i)) if args.theta_i else None
    wavelengths = parse_wavelengths(" ".join(args.wavelengths)) if args.wavelengths else None
    result = _selected(path, args.selections)
    if against is None:
        if wavelengths is not None or theta_i is not None:
            result = select(result, wavelengths, theta_i)
        result.plot(out, quantity=args.quantity, name=path.name)
        print(f"plot: {out}")
        drawn = np.atleast_1d(result.coords["wavelength"])
        if isinstance(result, GonioResult) and args.quantity in (None, "brdf") and len(drawn) > 1:
            print(f"drew the lobes at {drawn[0]:g} nm, the first of {len(drawn)} wavelengths "
                  "(another: --sel wavelength=NM)")
        return 0
    if theta_i is not None and len(theta_i) != 1:
        raise ValueError(f"--theta-i must be one angle with --against (got {len(theta_i)})")
    if wavelengths is not None:
        result = select(result, wavelengths=wavelengths)
    comparison = compare(result, against, quantity=args.quantity, theta_i=theta_i[0] if theta_i else None,
                         measurement_uncertainty=args.uncertainty)
    comparison = replace(comparison, result_name=path.name)
    comparison.plot(out)
    print(comparison.summary())
    print(f"plot: {out}")
    return 0


def _klems(args: argparse.Namespace) -> int:
    """``virtspec gonio SCENE --klems FILE``: the Klems matrices (:func:`virtspec_mi.exchange.klems_gonio.klems_measure`)."""

    from virtspec_mi.exchange.klems import sidecar_path
    from virtspec_mi.exchange.klems_gonio import klems_measure

    common = {"--out": args.out, "--plot": args.plot, "--plot-series": args.plot_series, "--json": args.json,
              "--param": args.params, "--points": args.points, "-D": args.defines, "--workers": args.workers,
              "--scheduler": args.scheduler, "--task-readings": args.task_readings}
    unused = [flag for flag, value in common.items() if value not in (None, False, [])]
    if unused:
        raise ValueError(f"--klems measures readings of its own and writes FILE and FILE.nc: it takes none of "
                         f"{', '.join(unused)}")
    settings = _given(args, _settings(), several=_several(MEASURING["gonio"]))
    measured = klems_measure(args.scene, basis=args.klems_basis, wavelengths=settings.get("wavelengths", 551.0),
                             epsilon=float(settings.get("mu", 0.01)), delta=float(settings.get("delta", 0.01)),
                             rays=None if "rays" not in settings else int(settings["rays"]),
                             seed=int(settings.get("seed", 0)), isotropic=args.isotropic, out=args.klems,
                             progress=False if args.quiet else None)
    print(measured.statement())
    print(f"written: {args.klems} (certified bounds per patch: {sidecar_path(args.klems)})")
    return 0


def _albedo_options(parser: argparse.ArgumentParser) -> None:
    """The flags of ``virtspec albedo-table`` (:func:`virtspec_mi.exchange.albedo.albedo_table`)."""

    parser.add_argument("--model", choices=("conductor", "glass"), default="conductor",
                        help="roughconductor with Fresnel = 1, or roughdielectric (default conductor)")
    parser.add_argument("--distribution", choices=("ggx", "beckmann"), default="ggx", help="(default ggx)")
    parser.add_argument("--engine", choices=("cycles", "filament", "unreal", "none"), default=None,
                        help="grid and memory order of that engine (default cycles, or none with --mu/--alpha)")
    for name, text in (("mu", "cosines of incidence"), ("alpha", "roughness alpha"),
                       ("roughness", "roughness r (alpha = r^2)"), ("eta", "glass indices >= 1 (inside: 1/eta)")):
        parser.add_argument(f"--{name}", nargs="+", help=f"{text}: numbers or start:stop:step")
    parser.add_argument("--epsilon", type=float, default=1e-3, help="tolerance of every value (default 0.001)")
    parser.add_argument("--delta", type=float, default=0.01, help="failure probability of the whole table (default 0.01)")
    parser.add_argument("--bound", choices=("two-stage", "hoeffding"), default="two-stage", help="(default two-stage)")
    parser.add_argument("--no-average", action="store_true", help="do not measure E_avg (diffuse beam)")
    parser.add_argument("--parts", action="store_true", help="glass: certify E_R and E_T too")
    parser.add_argument("--seed", type=int, default=0, help="seed of the run (default 0)")
    parser.add_argument("--out", nargs="+", default=[], help="files to write: .nc, .npy, .h")
    parser.add_argument("--checkpoint", help="directory keeping finished groups (resume; default OUT.parts)")
    parser.add_argument("--from", dest="source", metavar="TABLE", help="a table .nc to read instead of measuring")
    parser.add_argument("--compare", metavar="PUBLISHED", help="published table (.npy, .nc, .csv, C header) to hold "
                                                               "to the certified intervals")
    parser.add_argument("--array", help="--compare: the array (header) or variable (.nc) to read")
    parser.add_argument("--side", choices=("outside", "inside"), default="outside", help="--compare, glass")
    parser.add_argument("--average", action="store_true", help="--compare E_avg instead of E")
    parser.add_argument("--rounding", type=float, default=0.0, help="--compare: the published values' rounding")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument("--overwrite", action="store_true", help="let a .npy's NAME.json and NAME_avg.npy replace "
                                                                 "files of those names that another program wrote")


def _albedo_table(args: argparse.Namespace) -> int:
    from virtspec_mi.checks import parse_values
    from virtspec_mi.exchange.albedo import albedo_table, read_albedo_table

    if args.source:
        table = read_albedo_table(args.source)
        for path in args.out:
            table.check_output(path, overwrite=args.overwrite)  # every output's companions, before any is written
        for path in args.out:
            table.write(path, overwrite=args.overwrite)
    else:
        grid = {name: None if getattr(args, name) is None else list(parse_values(name, " ".join(getattr(args, name))))
                for name in ("mu", "alpha", "roughness", "eta")}
        engine = args.engine if args.engine is not None else (None if grid["mu"] is not None else "cycles")
        table = albedo_table(args.model, distribution=args.distribution, engine=None if engine == "none" else engine,
                             epsilon=args.epsilon, delta=args.delta, bound=args.bound, average=not args.no_average,
                             parts=args.parts, seed=args.seed, out=args.out or None, checkpoint=args.checkpoint,
                             progress=False if args.quiet else None, overwrite=args.overwrite, **grid)
    print(table.statement())
    print(f"rays {table.rays:,}; {table.provenance.get('seconds_wall', 0):g} s; grid {table.engine} "
          f"({' x '.join(f'{d} {len(getattr(table, d))}' for d in table.dims if d != 'side')})")
    for path in args.out:
        print(f"written: {path}")
    if args.compare:
        comparison = table.compare(args.compare, average=args.average, side=args.side, array=args.array,
                                   rounding=args.rounding)
        print(comparison.summary())
    return 0


if __name__ == "__main__":  # python -m virtspec_mi.cli: as python -m virtspec_mi (virtspec_mi.__main__.run)
    import runpy

    runpy.run_module("virtspec_mi", run_name="__main__")
