"""
Command line: ``virtspec``
==========================

- ``virtspec bounds --mu 0.005 --delta 0.001 0.01 0.1``: the paper's Table 1.
- ``virtspec measure SCENE [--theta-i] [--phi-i] [--wavelengths] [--mu] [--delta]
  [--rays] [--bound] [--joint] [--pilot-rays] [--pilot-delta] [--beam] [--sampling]
  [--seed] [--json]``: one certified reading.
- ``virtspec sweep SCENE --theta-i 0:90:1 [--wavelengths 400:700:10] [--out FILE(.nc|.csv|.json)]
  [--plot FIG(.png|.svg)] [--densities 3 4 5 6] [--quiet] [--workers N | --scheduler ADDRESS]
  [--task-readings K] [measure options]``: a sweep (resumable when ``--out`` is given: see
  :mod:`virtspec_mi.engine.checkpoint`), on Dask workers with ``--workers``/``--scheduler``
  (:mod:`virtspec_mi.scaleout`); ``--param NAME=VALUES`` (repeatable; VALUES ``v1,v2,v3``
  or ``start:stop:step``, stop included within rounding) sweeps a specimen parameter too
  (a grid; ``--points``: explicit points, equal-length lists; :mod:`virtspec_mi.engine.parameters`).
- ``measure`` and ``sweep`` take ``-D NAME=VALUE`` (repeatable): the XML scene's ``$NAME``
  parameter, as Mitsuba's own ``mitsuba -D`` (``mi.load_file(path, NAME=VALUE)``);
  ``measure --param NAME=VALUE`` sets one specimen parameter for the reading.
- ``virtspec gonio SCENE [--theta-o-bins 18] [--phi-o-bins 36] [--binning] [--fold-phi]
  [--hemispheres] [--guarantee] [--relative-tolerance] [--brdf-floor] [--out FILE] [--plot FIG]
  [--json] [measure options]``: a goniophotometer reading (BRDF/BTDF per direction bin).
- ``virtspec colour FILE [--theta-i] [--quantity] [--sel NAME=VALUE] [--illuminant] [--observer]
  [--json]``: CIE XYZ, L*a*b* and sRGB of a saved spectrum (a result file of any kind or a
  colour-science CSV).
- ``virtspec compare RESULT MEASURED [...]``: a result against a measured spectrum
  (:mod:`virtspec_mi.compare`); ``virtspec plot FILE [...]``: a figure of a result file.
  ``plot``, ``colour`` and ``compare`` read every kind of result file (a hemispherical
  reading or sweep, a goniophotometer reading: its R and T, or its lobes; a sphere
  reading: its reading and hemispherical value) and take ``--sel NAME=VALUE``
  (repeatable): the label of a dim nearest VALUE (a parameter point, θi, a wavelength).
- ``virtspec sphere SCENE [--measurement] [--specular SCI|SCE] [--method] [--standard]
  [--max-bounces] [--out FILE(.json|.nc)] [--json] [measure options]``: the readout of a
  physical integrating sphere (:mod:`virtspec_mi.instruments.sphere`).
- ``virtspec scenes``: the shipped scenes, one line each; every ``SCENE`` argument takes a
  shipped scene's name as well as a path (:mod:`virtspec_mi.scenes`).
- ``virtspec gonio SCENE --klems FILE.xml [--klems-basis full|half|quarter] [--isotropic]``: the
  Klems matrices (WINDOW 6 XML + NetCDF sidecar, :mod:`virtspec_mi.exchange.klems`).
- ``virtspec albedo-table [--model] [--distribution] [--engine] [--epsilon] [--delta] [--out FILE …]
  [--compare PUBLISHED]``: a certified energy-compensation table (:mod:`virtspec_mi.exchange.albedo`).
- ``virtspec llvm {find,check}``: the libLLVM Dr.Jit uses (``make setup`` calls it).

Errors in the input (bad ranges, unreadable scenes, a bad libLLVM) print one line
``virtspec: error: …`` and exit with status 2 (usage) or 1 (measurement).
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
from pathlib import Path
from typing import Any, Sequence

__all__ = ["main", "build_parser"]


_EXAMPLES = {
    "bounds": "example: virtspec bounds --mu 0.005 --delta 0.001 0.01 0.1",
    "measure": "examples:\n  virtspec measure scenes/diamond_conical.xml --theta-i 70\n"
               "  virtspec measure scenes/soybean_abmb.xml --wavelengths 400:2500:5 --bound two-stage --json",
    "sweep": "examples:\n  virtspec sweep scenes/diamond_collimated.xml --theta-i 0:90:1 --out fig5.nc --plot fig5.png\n"
             "  virtspec sweep scenes/diamond_collimated.xml --theta-i 0:90:1 --densities 3 4 5 6\n"
             "  virtspec sweep scenes/soybean_abmb.xml --theta-i 8 --wavelengths 450,550,650 "
             "--param specimen.thickness=1.2e-4:2e-4:4e-5 --param specimen.chlorophyll_a=2,4 --out lut.nc\n"
             "  virtspec sweep scenes/soybean_abmb.xml -D side=abaxial --theta-i 8\n"
             "  virtspec sweep scenes/soybean_abmb.xml --theta-i 8 --wavelengths 400:2500:5 --workers 2 --out leaf.nc",
    "gonio": "examples:\n  virtspec gonio scenes/diamond_collimated.xml --theta-i 30 --theta-o-bins 9 --phi-o-bins 12\n"
             "  virtspec gonio scene.xml --binning projected --fold-phi --out brdf.nc --plot brdf.png",
    "colour": "examples:\n  virtspec colour spectrum.csv\n"
              "  virtspec colour fig5.nc --theta-i 30 --illuminant A --quantity transmittance\n"
              "  virtspec colour lut.nc --sel specimen.thickness=1.6e-4 --sel theta_i=8\n"
              "  virtspec colour sphere.json --quantity hemispherical",
    "llvm": "example: virtspec llvm check",
    "scenes": "examples:\n  virtspec scenes\n  virtspec measure soybean_abmb --wavelengths 400:2500:5",
    "albedo-table": "examples:\n  virtspec albedo-table --engine cycles --epsilon 1e-3 --out ggx_E.nc ggx_E.h\n"
                    "  virtspec albedo-table --model glass --engine cycles --out glass.nc --checkpoint glass.parts\n"
                    "  virtspec albedo-table --from ggx_E.nc --compare published_tables.h --rounding 5e-7",
    "sphere": "examples:\n  virtspec sphere scenes/sphere_150mm_8d.xml --specular SCE\n"
              "  virtspec sphere scenes/sphere_150mm_8d.xml --method comparison --wavelengths 400:700:100 --out r.json",
}


def build_parser() -> argparse.ArgumentParser:
    """The ``virtspec`` argument parser (the measurement flags come from the ``Settings`` fields)."""

    from virtspec_mi import __version__
    from virtspec_mi.kernel.counts import QUANTITIES

    parser = argparse.ArgumentParser(
        prog="virtspec", description="Virtual spectrophotometer: certified reflectance, transmittance and "
                                     "absorptance readings of Mitsuba BSDFs (Baranoski, Rokne & Xu 2001).")
    parser.add_argument("--version", action="version", version=f"virtspec-mi {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, summary: str, description: str) -> argparse.ArgumentParser:
        return commands.add_parser(name, help=summary, description=description, epilog=_EXAMPLES[name],
                                   formatter_class=argparse.RawDescriptionHelpFormatter)

    bounds = command("bounds", "rays per reading under every ray budget (the paper's Table 1)",
                     "Rays per reading that certify |m/N - rho| < mu with probability >= 1 - delta: the "
                     "paper's Table 1 (eqs. 15 and 23), then every rule of bound=.")
    bounds.add_argument("--mu", type=float, default=0.005, help="certified tolerance (default 0.005)")
    bounds.add_argument("--delta", type=float, nargs="+", default=[0.001, 0.01, 0.1],
                        help="failure probabilities (default 0.001 0.01 0.1)")

    measure = command("measure", "one certified reading of a scene (over its wavelengths)",
                      "Measure the specimen of a scene: reflectance, transmittance and absorptance per "
                      "wavelength, with the tolerance the rays spent guarantee. Every setting defaults to "
                      "the scene's spectrophotometer integrator, else to the paper's defaults.")
    measure.add_argument("scene", help="Mitsuba XML scene with 'emitter' and 'specimen' disks, or a shipped scene's name (virtspec scenes)")
    _scene_options(measure, sweep=False)
    _option_flags(measure, _kind("settings"))
    measure.add_argument("--json", action="store_true",
                         help="print the reading as one JSON object (a result file: `virtspec colour` reads it)")

    sweep = command("sweep", "certified readings over theta_i x wavelengths (few kernel launches)",
                    "Measure a grid of readings (wavelengths x theta_i) at one phi_i, each with its own rays "
                    "and certificate; resumable when --out is given.")
    sweep.add_argument("scene", help="Mitsuba XML scene with 'emitter' and 'specimen' disks, or a shipped scene's name (virtspec scenes)")
    _scene_options(sweep, sweep=True)
    _option_flags(sweep, _kind("settings"), words=("theta_i",))
    sweep.add_argument("--out", help="result file .nc, .csv or .json (finished readings are kept in "
                                     "FILE.partial.json until the result file is written: re-run to resume)")
    sweep.add_argument("--plot", help="figure .png or .svg (readings with the band of their certified tolerance)")
    sweep.add_argument("--densities", type=float, nargs="+", metavar="LOG10N",
                       help="sweep at N = 10^d rays for each d; print seconds and the fluctuation of eq. (24)")
    sweep.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    where = sweep.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N",
                       help="trace on a local Dask cluster of N worker processes (default: in this process)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="trace on the Dask cluster of this scheduler, e.g. tcp://host:8786 (every worker needs "
                            "virtspec-mi installed and the scene file at the same path)")
    sweep.add_argument("--task-readings", type=int, metavar="K",
                       help="readings per Dask task (default: scaleout.TASK_SECONDS of tracing, from the measured ray rate)")

    gonio = command("gonio", "goniophotometer: certified BRDF/BTDF per outgoing-direction bin",
                    "Measure the specimen of a scene as the spectrophotometer does, and bin every escaping ray by "
                    "its outgoing direction (theta_o, phi_o) in the specimen frame: exact counts, fractions and "
                    "BRDF/BTDF per bin with their certificate (DKW for the CDFs, union bound for the bins, "
                    "Clopper-Pearson intervals for f).")
    gonio.add_argument("scene", help="Mitsuba XML scene with 'emitter' and 'specimen' disks, or a shipped scene's name (virtspec scenes)")
    _option_flags(gonio, _kind("settings"), words=("theta_i",))
    _option_flags(gonio, _kind("gonio"))
    gonio.add_argument("--out", help="result file .nc, .csv or .json (the tabulated BSDF reads the .nc)")
    gonio.add_argument("--plot", help="figure .png or .svg: polar plot of f in and across the plane of incidence")
    gonio.add_argument("--plot-series", help="figure .png or .svg: the distribution over theta_i as a series (f in "
                                             "the plane of incidence and the CDF of theta_o, certified bands)")
    gonio.add_argument("--json", action="store_true", help="print the reading as one JSON object")
    gonio.add_argument("--klems", metavar="FILE", help="measure the Klems matrices instead (incidence at every patch "
                       "centre, front and back; --mu is the certified tolerance of every patch fraction) and write "
                       "WINDOW 6 XML FILE with its NetCDF sidecar FILE.nc")
    gonio.add_argument("--klems-basis", choices=("full", "half", "quarter"), default="full",
                       help="Klems basis of --klems (145, 77 or 41 patches; default full)")
    gonio.add_argument("--isotropic", action="store_true",
                       help="--klems: one reading per ring, rotated onto its other patches (rotation-invariant specimens)")

    albedo = command("albedo-table", "certified directional-albedo tables E(mu, alpha) for energy compensation",
                     "Measure Mitsuba's rough conductor (Fresnel = 1) or rough glass on an engine's grid (or "
                     "your own): every E(mu, alpha[, eta]) and E_avg within --epsilon of the model's value, the "
                     "whole table at once with probability >= 1 - delta; NetCDF, .npy and a C header in Cycles' "
                     "layout; --compare lists every cell of a published table outside the certified interval.")
    _albedo_options(albedo)

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

    command("scenes", "the shipped scenes, one line each (any SCENE argument takes their names)",
            "List the scenes shipped with virtspec-mi. Every subcommand that takes a SCENE takes a shipped "
            "scene's name as well as a file path (e.g. virtspec measure soybean_abmb).")

    llvm = command("llvm", "find or check the libLLVM Dr.Jit uses (set-up)",
                   "find: print a libLLVM >= 17 on this machine (exit 1 if none); check: load it in Dr.Jit "
                   "and print its version, or say how to fix it.")
    llvm.add_argument("action", choices=["find", "check"])

    _EXAMPLES["compare"] = ("examples:\n  virtspec compare spectrum.nc measured.csv --plot compare.png\n"
                            "  virtspec compare reading.json npsg.csv --quantity transmittance --json")
    compare = command("compare", "a result against a measured spectrum: residuals, tolerance, Delta E 2000",
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

    _EXAMPLES["plot"] = ("examples:\n  virtspec plot fig5.nc --wavelengths 400 550 700 --out fig5.png\n"
                         "  virtspec plot spectrum.nc --quantity transmittance\n"
                         "  virtspec plot spectrum.nc --against measured.csv --out compare.svg\n"
                         "  virtspec plot brdf.nc --sel wavelength=550 --out lobes.png\n"
                         "  virtspec plot lut.nc --sel specimen.thickness=1.6e-4 --sel theta_i=8")
    plot = command("plot", "figure of a result file (a sweep, a reading, a goniophotometer or sphere reading), "
                           "optionally against a measured spectrum",
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
    sphere = command("sphere", "the readout of a physical integrating sphere (sample over standard)",
                     "Simulate an integrating-sphere instrument reading the scene's specimen: the detector "
                     "fractions with the sample and with the reference standard, their certified ratio, the "
                     "hemispherical reading of the same rays and the instrument error. The sphere comes from "
                     "the scene's integrating_sphere integrator.")
    sphere.add_argument("scene", help="Mitsuba XML scene with an integrating_sphere integrator and "
                                      "'emitter' and 'specimen' disks")
    _option_flags(sphere, _kind("settings"))
    _option_flags(sphere, _kind("sphere"))
    sphere.add_argument("--out", help="result file .json or .nc")
    sphere.add_argument("--json", action="store_true", help="print the result as one JSON object")
    return parser


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


def _scene_options(parser: argparse.ArgumentParser, sweep: bool) -> None:
    """``-D NAME=VALUE`` (XML scene parameters) and ``--param NAME=VALUES`` (specimen parameters)."""

    parser.add_argument("-D", dest="defines", action="append", default=[], metavar="NAME=VALUE",
                        help="set the XML scene parameter $NAME (as `mitsuba -D`); repeatable")
    if sweep:
        parser.add_argument("--param", dest="params", action="append", default=[], metavar="NAME=VALUES",
                            help="sweep a specimen parameter, e.g. specimen.thickness=1e-4:2e-4:5e-5 (start:stop:step, "
                                 "stop included) or specimen.alpha=0.1,0.2,0.4; names: mi.traverse keys of the "
                                 "specimen's BSDF or their short form specimen.NAME; repeatable (a grid: one dim each)")
        parser.add_argument("--points", action="store_true",
                            help="the --param lists are explicit points (equal lengths; one dim 'point'), not a grid")
    else:
        parser.add_argument("--param", dest="params", action="append", default=[], metavar="NAME=VALUE",
                            help="set a specimen parameter for this reading, e.g. specimen.thickness=2e-4; repeatable")


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


def _kind(name: str) -> Any:
    """The options class ``name`` (``settings``, ``gonio``, ``sphere``), imported when the parser is built."""

    from virtspec_mi.instruments.goniophotometer import GonioOptions
    from virtspec_mi.instruments.sphere import SphereOptions
    from virtspec_mi.settings import Settings

    return {"settings": Settings, "gonio": GonioOptions, "sphere": SphereOptions}[name]


def _option_flags(parser: argparse.ArgumentParser, kind: Any, words: tuple[str, ...] = ()) -> None:
    """
    The one flag builder: one flag per option of ``kind`` (an
    :class:`~virtspec_mi.settings.Options` class: ``--theta-i`` …), its choices, default
    and help from the field; a switch (a ``bool`` default) is a flag without a value,
    an option the command line writes as several words (the field's ``words``, or one
    named in ``words``) takes them all. Values go to the options as given (they validate
    them); a flag left out takes the scene's value, else the default.
    """

    from dataclasses import fields

    from virtspec_mi.settings import help_text, shown

    for item in fields(kind):
        meta = item.metadata
        if not meta["flag"]:
            continue
        flag = "--" + item.name.replace("_", "-")
        default = f"default: the scene's, else {shown(item.default) if item.default is not None else meta['unset']}"
        text = f"{help_text(item)} ({default})"
        if isinstance(item.default, bool):
            parser.add_argument(flag, action="store_true", default=None, help=text)
        else:
            parser.add_argument(flag, nargs="+" if meta["words"] or item.name in words else None,
                                choices=list(meta["choices"]) if meta["choices"] else None, help=text)


def _given(args: argparse.Namespace, kind: Any) -> dict[str, Any]:
    """The options of ``kind`` given on the command line (several words joined into one string)."""

    values = {name: getattr(args, name, None) for name in kind.names()}
    return {name: " ".join(value) if isinstance(value, list) else value for name, value in values.items()}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``virtspec``; returns the exit status."""

    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # a closed pipe (virtspec bounds | head) ends us quietly
    parser = build_parser()
    args = parser.parse_args(argv)
    from virtspec_mi.engine.interrupts import catching, exit_status

    with catching():  # SIGINT and SIGTERM stop a run at its next safe point, its checkpoint saved
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
    except (ValueError, RuntimeError, OSError) as error:
        print(f"virtspec: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as stop:  # Ctrl-C (SIGINT) or SIGTERM: virtspec_mi.engine.interrupts.Interrupted
        signum = getattr(stop, "signum", signal.SIGINT)
        # the checkpoint of the run under way: named by the run, else the one the command set (_sweep)
        partial = getattr(stop, "checkpoint", None) or getattr(args, "checkpoint", None)
        kept = "" if partial is None else (
            f" (finished readings are kept in {partial}: re-run the same command to resume)" if Path(partial).exists()
            else " (no reading had finished: nothing to resume)")
        word = "interrupted" if signum == signal.SIGINT else f"terminated by {signal.Signals(signum).name}"
        print(f"virtspec: {word}{kept}", file=sys.stderr)
        return exit_status(signum)


def _measure(args: argparse.Namespace) -> int:
    from virtspec_mi.api import measure

    reading = measure(args.scene, parameters=_pairs(args.params, "--param"), defines=_pairs(args.defines, "-D"),
                      **_given(args, _kind("settings")))
    print(json.dumps(reading.as_dict()) if args.json else reading.summary())
    return 0


def _sphere(args: argparse.Namespace) -> int:
    from virtspec_mi.api import sphere_measure

    # with --out: written by the run, resumable from OUT.partial.json when interrupted
    result = sphere_measure(args.scene, out=args.out, **_given(args, _kind("settings")),
                            **_given(args, _kind("sphere")))
    print(json.dumps(result.as_dict()) if args.json else result.summary())
    return 0


def _sweep(args: argparse.Namespace) -> int:
    from pathlib import Path

    from virtspec_mi.api import sweep
    from virtspec_mi.engine.checkpoint import checkpoint_for
    from virtspec_mi.results.plot import check_figure_path, plot_sweep
    from virtspec_mi.results.io import check_output, csv_text

    out = check_output(args.out) if args.out else None  # a bad suffix or directory fails before any tracing
    check_figure_path(args.plot)
    parameters = _pairs(args.params, "--param")
    if parameters and args.plot:
        raise ValueError("--plot draws a sweep over wavelength x theta_i; a parameter sweep is plotted by selecting "
                         "one parameter point first (Result.sel in Python)")
    kwargs = {**_given(args, _kind("settings")), "progress": False if args.quiet else None, "parameters": parameters,
              "points": args.points, "defines": _pairs(args.defines, "-D"),
              "workers": args.scheduler if args.scheduler is not None else args.workers,
              "task_readings": args.task_readings}
    given_rays = kwargs.pop("rays")

    def run(rays: int | None, path: Path | None, options: dict = kwargs) -> object:
        # the sweep writes `path` atomically, and only then removes its checkpoint PATH.partial.json
        args.checkpoint = checkpoint_for(path) if path is not None else None  # named if interrupted
        return sweep(args.scene, rays=rays, out=path, **options)

    if not args.densities:
        result = run(given_rays, out)
        if args.plot:
            plot_sweep(result, args.plot)
        # no file: the CSV table on stdout and the summary on stderr, so the table can be piped
        report = sys.stdout if out is not None else sys.stderr
        if not args.quiet:
            print(result.summary(), file=report)
            for label, path in (("written", out), ("plot", args.plot)):
                if path:
                    print(f"{label}: {path}", file=report)
        if out is None:
            print(csv_text(result.to_dataset()), end="")
        return 0

    if given_rays is not None:
        raise ValueError("--rays and --densities exclude each other (densities set N = 10^d)")
    _check_densities(args.densities)
    if kwargs["workers"] is None:
        return _densities(args, kwargs, run, out)
    from virtspec_mi.scaleout import connect

    with connect(kwargs["workers"]) as client:  # one cluster (or connection) for every density
        return _densities(args, {**kwargs, "workers": client}, run, out)


def _densities(args: argparse.Namespace, kwargs: dict, run: Any, out: Any) -> int:
    """``--densities``: a sweep per ray density, its seconds and the fluctuation Δ against the previous one."""

    from virtspec_mi.api import fluctuation, sweep
    from virtspec_mi.results.plot import plot_densities

    # Fig. 6b: time linear in N. The first sweep compiles the kernel (Dr.Jit caches it for every
    # N): run it once at the smallest density first, so no density's seconds include compilation.
    warm_up = sweep(args.scene, rays=int(round(10.0 ** min(args.densities))), **{**kwargs, "progress": False})
    results, deltas = [], [float("nan")]
    print(f"{'log10 N':>8} {'N':>12} {'seconds':>9} {'Delta (eq. 24)':>15}")
    for density in args.densities:
        rays = int(round(10.0 ** density))
        path = out.with_name(f"{out.stem}_logN{density:g}{out.suffix}") if out is not None else None
        results.append(run(rays, path, kwargs))
        if len(results) > 1:
            deltas.append(fluctuation(results[-2], results[-1]))
        delta_text = "" if len(results) == 1 else f"{deltas[-1]:.6f}"
        print(f"{density:>8g} {rays:>12,} {results[-1].seconds:>9.3f} {delta_text:>15}", flush=True)
    print(f"(seconds after a warm-up sweep at log10 N = {min(args.densities):g}, {warm_up.seconds:.3f} s, "
          "which compiled the kernel" + ("; on workers: tracing seconds summed over the workers, not wall time)"
                                         if kwargs["workers"] is not None else ")"))
    if args.plot:
        plot_densities(results, args.densities, deltas, args.plot)
    return 0


def _gonio(args: argparse.Namespace) -> int:
    from virtspec_mi.api import gonio
    from virtspec_mi.results.plot import check_figure_path

    check_figure_path(args.plot)  # a bad suffix fails before any tracing
    check_figure_path(args.plot_series)
    if args.klems:
        return _klems(args)
    options = _given(args, _kind("gonio"))
    settings = _given(args, _kind("settings"))
    theta_i = settings.pop("theta_i")
    reading = gonio(args.scene, theta_i=theta_i, out=args.out, **options, **settings)
    if args.plot:
        reading.plot(args.plot)
    if args.plot_series:
        reading.plot_series(args.plot_series)
    if args.json:
        print(json.dumps(reading.as_dict()))
        return 0
    print(reading.summary())
    for label, path in (("written", args.out), ("plot", args.plot), ("plot", args.plot_series)):
        if path:
            print(f"{label}: {path}")
    return 0


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

    from virtspec_mi.compare import compare
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
    from virtspec_mi.compare import compare
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

    settings = {k: v for k, v in _given(args, _kind("settings")).items() if v is not None}
    measured = klems_measure(args.scene, basis=args.klems_basis, wavelengths=settings.get("wavelengths", 551.0),
                             epsilon=float(settings.get("mu", 0.01)), delta=float(settings.get("delta", 0.01)),
                             rays=None if "rays" not in settings else int(settings["rays"]),
                             seed=int(settings.get("seed", 0)), isotropic=args.isotropic, out=args.klems)
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


def _albedo_table(args: argparse.Namespace) -> int:
    from virtspec_mi.checks import parse_values
    from virtspec_mi.exchange.albedo import albedo_table, read_albedo_table

    if args.source:
        table = read_albedo_table(args.source)
        for path in args.out:
            table.write(path)
    else:
        grid = {name: None if getattr(args, name) is None else list(parse_values(name, " ".join(getattr(args, name))))
                for name in ("mu", "alpha", "roughness", "eta")}
        engine = args.engine if args.engine is not None else (None if grid["mu"] is not None else "cycles")
        table = albedo_table(args.model, distribution=args.distribution, engine=None if engine == "none" else engine,
                             epsilon=args.epsilon, delta=args.delta, bound=args.bound, average=not args.no_average,
                             parts=args.parts, seed=args.seed, out=args.out or None, checkpoint=args.checkpoint,
                             progress=False if args.quiet else None, **grid)
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


if __name__ == "__main__":
    sys.exit(main())
