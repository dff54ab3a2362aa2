"""
Command line: ``virtspec``
==========================

- ``virtspec bounds --mu 0.005 --delta 0.001 0.01 0.1``: the paper's Table 1.
- ``virtspec measure SCENE [--theta-i] [--phi-i] [--wavelengths] [--mu] [--delta]
  [--rays] [--bound] [--joint] [--pilot-rays] [--pilot-delta] [--beam] [--sampling]
  [--seed] [--json]``: one certified reading.
- ``virtspec sweep SCENE --theta-i 0:90:1 [--wavelengths 400:700:10] [--out FILE(.nc|.csv|.json)]
  [--plot FIG(.png|.svg)] [--densities 3 4 5 6] [--quiet] [measure options]``: a sweep
  (resumable when ``--out`` is given: see :mod:`virtspec_mi.checkpoint`).
- ``virtspec colour FILE [--theta-i] [--quantity] [--illuminant] [--observer]``: CIE XYZ,
  L*a*b* and sRGB of a saved spectrum (a sweep file or a colour-science CSV).

Errors in the input (bad ranges, unreadable scenes, a bad libLLVM) print one line
``virtspec: error: …`` and exit with status 2 (usage) or 1 (measurement).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Sequence

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    """The ``virtspec`` argument parser."""

    parser = argparse.ArgumentParser(
        prog="virtspec", description="Virtual spectrophotometer: certified R/T/A readings of Mitsuba BSDFs."
    )
    commands = parser.add_subparsers(dest="command", required=True)

    bounds = commands.add_parser("bounds", help="rays per reading under eq. (15) and eq. (23) (Table 1)")
    bounds.add_argument("--mu", type=float, default=0.005, help="certified tolerance (default 0.005)")
    bounds.add_argument("--delta", type=float, nargs="+", default=[0.001, 0.01, 0.1],
                        help="failure probabilities (default 0.001 0.01 0.1)")

    measure = commands.add_parser("measure", help="one certified reading of a scene")
    measure.add_argument("scene", help="Mitsuba XML scene with 'emitter' and 'specimen' disks")
    _measurement_options(measure, sweep=False)
    measure.add_argument("--json", action="store_true", help="print the reading as one JSON object")

    sweep = commands.add_parser("sweep", help="certified readings over theta_i x wavelengths (few kernel launches)")
    sweep.add_argument("scene", help="Mitsuba XML scene with 'emitter' and 'specimen' disks")
    _measurement_options(sweep, sweep=True)
    sweep.add_argument("--out", help="result file .nc, .csv or .json (finished readings are kept in "
                                     "OUT.partial.json until the sweep ends: re-run to resume)")
    sweep.add_argument("--plot", help="figure .png or .svg (readings with the certified +-mu band)")
    sweep.add_argument("--densities", type=float, nargs="+", metavar="LOG10N",
                       help="sweep at N = 10^d rays for each d; print seconds and the fluctuation of eq. (24)")
    sweep.add_argument("--quiet", action="store_true", help="no progress bar and no summary")

    colour = commands.add_parser("colour", help="CIE XYZ, L*a*b*, sRGB of a saved spectrum")
    colour.add_argument("file", help="result file (.nc, .csv, .json; also `measure --json` output) or "
                                     "colour-science CSV spectra")
    colour.add_argument("--theta-i", type=float, help="angle of the sweep to use (needed if it has several)")
    colour.add_argument("--quantity", default="reflectance", help="reflectance (default) or transmittance")
    colour.add_argument("--illuminant", default="D65", help="colour.SDS_ILLUMINANTS name (default D65)")
    colour.add_argument("--observer", default="CIE 1931 2 Degree Standard Observer",
                        help="colour.MSDS_CMFS name (default CIE 1931 2 degree)")
    return parser


def _measurement_options(parser: argparse.ArgumentParser, sweep: bool) -> None:
    """
    One flag per field of :class:`~virtspec_mi.settings.Settings` (``--theta-i`` …): the
    choices, defaults and help come from the field; values go to ``Settings`` as given
    (it validates them). A flag left out takes the scene's value, else the default.
    """

    from dataclasses import fields

    from virtspec_mi.settings import Settings, help_text, shown

    for item in fields(Settings):
        flag = "--" + item.name.replace("_", "-")
        choices = item.metadata["choices"]
        default = f"default: the scene's, else {shown(item.default)}" if item.default is not None else \
            "default: the scene's, else from the rule"
        if item.name == "joint":
            parser.add_argument(flag, action="store_true", default=None, help=f"{help_text(item)} ({default})")
            continue
        if item.name == "theta_i" and sweep:
            parser.add_argument(flag, nargs="+", help="polar incidence angles, degrees in [0, 90]: numbers and "
                                                      "start:stop:step ranges (default: the scene's, else 0)")
            continue
        parser.add_argument(flag, nargs="+" if item.name == "wavelengths" else None,
                            choices=list(choices) if choices else None, help=f"{help_text(item)} ({default})")


def _settings(args: argparse.Namespace) -> dict:
    """The settings given on the command line (lists joined into one string)."""

    from virtspec_mi.settings import SETTING_NAMES

    values = {name: getattr(args, name, None) for name in SETTING_NAMES}
    return {name: " ".join(value) if isinstance(value, list) else value for name, value in values.items()}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``virtspec``; returns the exit status."""

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        if args.command == "bounds":
            from virtspec_mi.bounds import format_table_1

            print(format_table_1(args.mu, args.delta))
            return 0
        if args.command == "sweep":
            return _sweep(args)
        if args.command == "colour":
            return _colour(args)
        return _measure(args)
    except (ValueError, RuntimeError, OSError) as error:
        print(f"virtspec: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        partial = getattr(args, "checkpoint", None)  # the checkpoint of the sweep under way (set by _sweep)
        kept = "" if partial is None else (
            f" (finished readings are kept in {partial}: re-run the same command to resume)" if partial.exists()
            else " (no reading had finished: nothing to resume)")
        print(f"virtspec: interrupted{kept}", file=sys.stderr)
        return 130


def _measure(args: argparse.Namespace) -> int:
    from virtspec_mi.api import measure

    reading = measure(args.scene, **_settings(args))
    print(json.dumps(reading.as_dict()) if args.json else reading.summary())
    return 0


def _sweep(args: argparse.Namespace) -> int:
    from pathlib import Path

    from virtspec_mi.api import fluctuation, sweep
    from virtspec_mi.checkpoint import checkpoint_for
    from virtspec_mi.plot import check_figure_path, plot_densities, plot_sweep
    from virtspec_mi.results_io import check_output, csv_text

    out = check_output(args.out) if args.out else None  # a bad suffix or directory fails before any tracing
    check_figure_path(args.plot)
    kwargs = {**_settings(args), "progress": False if args.quiet else None}
    given_rays = kwargs.pop("rays")

    def run(rays: int | None, path: Path | None) -> object:
        # the sweep writes `path` atomically, and only then removes its checkpoint PATH.partial.json
        args.checkpoint = checkpoint_for(path) if path is not None else None  # named if interrupted
        return sweep(args.scene, rays=rays, out=path, **kwargs)

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
    results, deltas = [], [float("nan")]
    print(f"{'log10 N':>8} {'N':>12} {'seconds':>9} {'Delta (eq. 24)':>15}")
    for density in args.densities:
        rays = int(round(10.0 ** density))
        path = out.with_name(f"{out.stem}_logN{density:g}{out.suffix}") if out is not None else None
        results.append(run(rays, path))
        if len(results) > 1:
            deltas.append(fluctuation(results[-2], results[-1]))
        delta_text = "" if len(results) == 1 else f"{deltas[-1]:.6f}"
        print(f"{density:>8g} {rays:>12,} {results[-1].seconds:>9.3f} {delta_text:>15}", flush=True)
    if args.plot:
        plot_densities(results, args.densities, deltas, args.plot)
    return 0


def _colour(args: argparse.Namespace) -> int:
    from pathlib import Path

    from virtspec_mi.api import read_result
    from virtspec_mi.colorimetry import colorimetry
    from virtspec_mi.results_io import is_result_csv, read_spectra_csv

    path = Path(args.file)
    if path.suffix.lower() == ".csv" and path.is_file() and not is_result_csv(path):
        spectra = read_spectra_csv(path)
        if args.quantity not in spectra:
            raise ValueError(f"quantity must be one of the file's columns {sorted(spectra)} (got {args.quantity!r})")
        sd = spectra[args.quantity]
        heading = f"{args.quantity} of {path}"
    else:
        sd = read_result(path).to_sd(args.quantity, args.theta_i)
        heading = f"{args.quantity} of {path} ({sd.name})"
    colour = colorimetry(sd, args.illuminant, args.observer)
    print(heading)
    print(colour.summary())
    return 0


if __name__ == "__main__":
    sys.exit(main())
