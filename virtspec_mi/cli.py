"""
Command line: ``virtspec``
==========================

- ``virtspec bounds --mu 0.005 --delta 0.001 0.01 0.1``: the paper's Table 1.
- ``virtspec measure SCENE [--theta-i] [--phi-i] [--wavelengths] [--mu] [--delta]
  [--rays] [--bound] [--joint] [--pilot-rays] [--pilot-delta] [--beam] [--sampling]
  [--seed] [--json]``: one certified reading.

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
    measure.add_argument("--theta-i", type=float, help="polar incidence angle, degrees in [0, 90]")
    measure.add_argument("--phi-i", type=float, help="azimuthal incidence angle, degrees")
    measure.add_argument("--wavelengths", nargs="+",
                         help="wavelengths in nm: numbers and start:stop:step ranges")
    measure.add_argument("--mu", type=float, help="certified tolerance, 0 < mu < 0.5 (default 0.005)")
    measure.add_argument("--delta", type=float, help="failure probability, 0 < delta < 1 (default 0.01)")
    measure.add_argument("--rays", type=int, help="rays per wavelength (default: from the bound)")
    measure.add_argument("--bound", choices=["hoeffding", "chebyshev", "exact", "two-stage"],
                         help="ray budget rule (default hoeffding, eq. 23)")
    measure.add_argument("--joint", action="store_true", default=None,
                         help="certify reflectance and transmittance together (each at delta/2)")
    measure.add_argument("--pilot-rays", type=int, help="two-stage pilot rays (default ceil(10/mu))")
    measure.add_argument("--pilot-delta", type=float, help="two-stage pilot failure probability (default delta/10)")
    measure.add_argument("--beam", choices=["conical", "collimated"], help="beam geometry")
    measure.add_argument("--sampling", choices=["jittered", "random", "concentric"], help="disk sampling")
    measure.add_argument("--seed", type=int, help="random seed (default 0)")
    measure.add_argument("--json", action="store_true", help="print the reading as one JSON object")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``virtspec``; returns the exit status."""

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        if args.command == "bounds":
            from virtspec_mi.bounds import format_table_1

            print(format_table_1(args.mu, args.delta))
            return 0
        return _measure(args)
    except (ValueError, RuntimeError, OSError) as error:
        print(f"virtspec: error: {error}", file=sys.stderr)
        return 1


def _measure(args: argparse.Namespace) -> int:
    from virtspec_mi.reading import measure

    reading = measure(
        args.scene,
        theta_i=args.theta_i,
        phi_i=args.phi_i,
        wavelengths=" ".join(args.wavelengths) if args.wavelengths else None,
        mu=args.mu,
        delta=args.delta,
        rays=args.rays,
        beam=args.beam,
        sampling=args.sampling,
        seed=args.seed,
        bound=args.bound,
        joint=args.joint,
        pilot_rays=args.pilot_rays,
        pilot_delta=args.pilot_delta,
    )
    print(json.dumps(reading.as_dict()) if args.json else reading.summary())
    return 0


if __name__ == "__main__":
    sys.exit(main())
