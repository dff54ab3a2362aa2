"""
``virtspec albedo-table``: certified directional-albedo tables and engines' drop-in files
=========================================================================================

The flags of :func:`virtspec_mi.applications.tables.albedo.albedo_table` and of an engine's
channels (:func:`virtspec_mi.applications.tables.engine_tables.engine_tables`, ``--audit``).
"""

from __future__ import annotations

import argparse
from typing import Callable

__all__ = ["add_table_command", "albedo_table"]

EXAMPLES = ("examples:\n  virtspec albedo-table --engine cycles --epsilon 1e-3 --out ggx_E.nc ggx_E.h\n"
            "  virtspec albedo-table --model glass --engine cycles --out glass.nc --checkpoint glass.parts\n"
            "  virtspec albedo-table --from ggx_E.nc --compare published_tables.h --rounding 5e-7\n"
            "  virtspec albedo-table --engine filament --out dfg.inc\n"
            "  virtspec albedo-table --engine unreal --audit PreintegratedGF.png --figure audit.png")
"""Its examples (its ``--help``)."""


def add_table_command(command: Callable[..., argparse.ArgumentParser]) -> None:
    """Add ``albedo-table`` through ``command(name, summary, description, examples)``."""

    albedo = command("albedo-table", "certified directional-albedo tables E(mu, alpha)",
                     "Measure Mitsuba's rough conductor (Fresnel = 1) or rough glass on an engine's grid (or "
                     "your own): every E(mu, alpha[, eta]) and E_avg within --epsilon of the model's value, the "
                     "whole table at once with probability >= 1 - delta; NetCDF, .npy and a C header in Cycles' "
                     "layout; --compare lists every cell of a published table outside the certified interval.",
                     EXAMPLES)
    albedo_options(albedo)


def albedo_options(parser: argparse.ArgumentParser) -> None:
    """The flags of ``virtspec albedo-table`` (:func:`virtspec_mi.applications.tables.albedo.albedo_table`)."""

    parser.add_argument("--model", choices=("conductor", "glass"), default="conductor",
                        help="roughconductor with Fresnel = 1, or roughdielectric (default conductor)")
    parser.add_argument("--distribution", choices=("ggx", "beckmann"), default="ggx", help="(default ggx)")
    parser.add_argument("--shadowing", choices=("separable", "height_correlated", "unreal"), default=None,
                        help="conductor G2 (default: the engine's own; separable on a user grid)")
    parser.add_argument("--g1", choices=("exact", "walter"), default="exact", help="Beckmann G1 (default exact)")
    parser.add_argument("--fresnel", choices=("one", "fc", "one_minus_fc"), default="one",
                        help="conductor F: 1, Fc = (1 - wi.m)^5 or 1 - Fc (default one)")
    parser.add_argument("--engine", choices=("cycles", "filament", "unreal", "none"), default=None,
                        help="grid and memory order of that engine (default cycles, or none with --cosines/--alpha)")
    for flag, name, text in (("--cosines", "mu", "cosines of incidence mu"), ("--alpha", "alpha", "roughness alpha"),
                             ("--roughness", "roughness", "roughness r (alpha = r^2)"),
                             ("--eta", "eta", "glass indices >= 1 (inside: 1/eta)")):
        parser.add_argument(flag, dest=name, nargs="+", help=f"{text}: numbers or start:stop:step")
    parser.add_argument("--mu", dest="tolerance_flag", nargs="*", help=argparse.SUPPRESS)  # one meaning per flag
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
    parser.add_argument("--audit", metavar="PUBLISHED", help="an engine's published table in its native layout "
                        "(cycles .h, filament dfg.inc, unreal .raw/.png) to audit against certified tables of its "
                        "model (--engine cycles|filament|unreal)")
    parser.add_argument("--figure", help="--audit: write the heat map of (published - certified)/epsilon here "
                        "(--from TABLE.nc: audit against a certified engine table written before)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument("--overwrite", action="store_true", help="let a .npy's NAME.json and NAME_avg.npy replace "
                                                                 "files of those names that another program wrote")


def albedo_table(args: argparse.Namespace) -> int:
    from virtspec_mi.api import parse_values
    from virtspec_mi.applications.tables.albedo import albedo_table

    _check_paths(args)
    native = (".inc", ".raw", ".png")
    if args.audit or (args.engine in ("filament", "unreal") and any(p.lower().endswith(native) for p in args.out)):
        return engine_tables(args)
    if args.source:
        table = _read_source(args)
        for path in args.out:
            table.check_output(path, overwrite=args.overwrite)  # every output's companions, before any is written
        for path in args.out:
            table.write(path, overwrite=args.overwrite)
    else:
        if args.tolerance_flag is not None:
            raise ValueError("--mu: the cosines of incidence are --cosines (--mu is the certified tolerance of a "
                             "reading everywhere else; a table's is --epsilon)")
        grid = {name: None if getattr(args, name) is None else list(parse_values(name, " ".join(getattr(args, name))))
                for name in ("mu", "alpha", "roughness", "eta")}
        engine = args.engine if args.engine is not None else (None if grid["mu"] is not None else "cycles")
        table = albedo_table(args.model, distribution=args.distribution, engine=None if engine == "none" else engine,
                             shadowing=args.shadowing, g1=args.g1, fresnel=args.fresnel,
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


_MEASURING = ("model", "distribution", "shadowing", "g1", "fresnel", "mu", "alpha", "roughness", "eta", "epsilon",
              "delta", "bound", "no_average", "parts", "seed", "checkpoint")
"""The flags (by ``dest``) that shape a measurement: meaningless beside ``--from`` (a table already measured)."""


def _check_paths(args: argparse.Namespace) -> None:
    """
    Before anything is measured or written: no output (``--out``, ``--figure``,
    ``--checkpoint``) is an input (``--from``, ``--audit``, ``--compare``) or another
    output (:func:`virtspec_mi.base.files.check_distinct`); no measuring flag beside ``--from``.
    """

    from virtspec_mi.base.files import check_distinct

    if args.figure and not args.audit:
        raise ValueError("--figure draws the heat map of --audit: give --audit PUBLISHED too")
    check_distinct([*(("--out", path) for path in args.out), ("--figure", args.figure),
                    ("--checkpoint", args.checkpoint)],
                   [("--from", args.source), ("--audit", args.audit), ("--compare", args.compare)])
    if args.source:
        defaults = argparse.ArgumentParser()
        albedo_options(defaults)
        given = [name for name in _MEASURING if getattr(args, name) != defaults.get_default(name)]
        if given:
            flags = ", ".join("--" + name.replace("_", "-") if name not in ("mu",) else "--cosines" for name in given)
            raise ValueError(f"--from TABLE reads a table already measured: {flags} would change nothing (they shape "
                             "a new measurement); leave them out, or measure anew without --from")


def _read_source(args: argparse.Namespace):
    """The table of ``--from``; an ``--engine`` beside it must be the table's own."""

    from virtspec_mi.applications.tables.table import read_albedo_table

    table = read_albedo_table(args.source)
    own = table.engine if table.engine in ("cycles", "filament", "unreal") else "none"
    if args.engine is not None and args.engine != own:
        grid = f"{own}'s grid" if own != "none" else "a grid of its own (--engine none)"
        raise ValueError(f"--engine {args.engine}: the table of --from {args.source} is on {grid}; leave --engine out "
                         f"or give --engine {own}")
    return table


def engine_tables(args: argparse.Namespace) -> int:
    """``--audit`` (and an engine's drop-in files): every channel of the engine's model certified at once."""

    from virtspec_mi.applications.tables.audit import audit
    from virtspec_mi.applications.tables.engine_tables import engine_tables

    if args.engine not in ("cycles", "filament", "unreal"):
        raise ValueError("--audit needs --engine cycles, filament or unreal (the published table's layout)")
    native = (".h", ".hpp", ".inc", ".raw", ".png", ".nc")
    for path in args.out:
        if not path.lower().endswith(native):
            raise ValueError(f"--out {path}: an engine table is written as the engine's file or .nc")
    from virtspec_mi.applications.tables.engine_tables import check_engine_sidecar

    for path in args.out:  # a drop-in file's PATH.json sidecar: never an input, never another program's file
        if not path.lower().endswith(".nc"):
            check_engine_sidecar(path, args.overwrite, inputs=[p for p in (args.source, args.audit) if p])
    if args.source:  # a certified engine table written before (--out TABLE.nc)
        from virtspec_mi.applications.tables.engine_tables import EngineTables

        tables = EngineTables.from_table(_read_source(args))
    else:
        tables = engine_tables(args.engine, epsilon=args.epsilon, delta=args.delta, seed=args.seed, bound=args.bound,
                               progress=False if args.quiet else None, checkpoint=args.checkpoint)
    print(tables.statement())
    print(f"rays {tables.rays:,}; {tables.seconds:g} s")
    for path in args.out:
        tables.write(path, overwrite=args.overwrite)
        print(f"written: {path}" + ("" if path.lower().endswith(".nc") else f" (provenance: {path}.json)"))
    if args.audit:
        report = audit(args.audit, tables)
        print(report.summary())
        if args.figure:
            report.figure(args.figure)
            print(f"written: {args.figure}")
    return 0
