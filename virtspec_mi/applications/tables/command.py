"""
``virtspec albedo-table``: certified directional-albedo tables and engines' drop-in files
===========================================================================================

:data:`ALBEDO_TABLE` is the tables application's
:class:`~virtspec_mi.applications.base.Command`: its flags (:class:`TableFlags`: those of
:func:`virtspec_mi.applications.tables.albedo.albedo_table` and of an engine's channels,
:func:`virtspec_mi.applications.tables.engine_tables.engine_tables`, ``--audit``) and
:func:`respond`, which receives the command line's session.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from virtspec_mi.applications.base import Command, Session
from virtspec_mi.settings import Options, one_of, option, text, true_or_false, whole_number

__all__ = ["ALBEDO_TABLE", "TableFlags", "respond", "EXAMPLES"]

EXAMPLES: tuple[str, ...] = (
    "virtspec albedo-table --engine cycles --epsilon 1e-3 --out ggx_E.nc ggx_E.h",
    "virtspec albedo-table --model glass --engine cycles --out glass.nc --checkpoint glass.parts",
    "virtspec albedo-table --from ggx_E.nc --compare published_tables.h --rounding 5e-7",
    "virtspec albedo-table --engine filament --out dfg.inc",
    "virtspec albedo-table --engine unreal --audit PreintegratedGF.png --figure audit.png")
"""Its examples (its ``--help``)."""



def _float(name: str) -> Any:
    from virtspec_mi.base.checks import number

    return lambda value: number(name, value)


def _words(value: Any) -> tuple[str, ...]:
    return (value,) if isinstance(value, str) else tuple(value)


def _choices(*names: str) -> dict[str, str]:
    return {name: name for name in names}


_MODELS = {"conductor": "roughconductor with Fresnel = 1", "glass": "roughdielectric"}
_ENGINES = {"cycles": "Blender Cycles", "filament": "Filament", "unreal": "Unreal Engine",
            "none": "a grid of your own (--cosines, --alpha)"}


@dataclass(frozen=True)
class TableFlags(Options):
    """The flags of ``virtspec albedo-table``."""

    title: ClassVar[str] = "albedo table"

    model: str = option("conductor", one_of("model", _MODELS), "the microfacet model", _MODELS)
    distribution: str = option("ggx", one_of("distribution", _choices("ggx", "beckmann")), "microfacet distribution",
                               _choices("ggx", "beckmann"))
    shadowing: str | None = option(None, one_of("shadowing", _choices("separable", "height_correlated", "unreal")),
                                   "conductor G2", _choices("separable", "height_correlated", "unreal"),
                                   unset="the engine's own; separable on a user grid")
    g1: str = option("exact", one_of("g1", _choices("exact", "walter")), "Beckmann G1", _choices("exact", "walter"))
    fresnel: str = option("one", one_of("fresnel", _choices("one", "fc", "one_minus_fc")),
                          "conductor F: 1, Fc = (1 - wi.m)^5 or 1 - Fc", _choices("one", "fc", "one_minus_fc"))
    engine: str | None = option(None, one_of("engine", _ENGINES), "grid and memory order of that engine", _ENGINES,
                                unset="cycles, or none with --cosines/--alpha")
    mu: str | None = option(None, text("cosines"), "cosines of incidence mu: numbers or start:stop:step",
                            words=True, spelled="--cosines")
    alpha: str | None = option(None, text("alpha"), "roughness alpha: numbers or start:stop:step", words=True)
    roughness: str | None = option(None, text("roughness"), "roughness r (alpha = r^2): numbers or start:stop:step",
                                   words=True)
    eta: str | None = option(None, text("eta"), "glass indices >= 1 (inside: 1/eta): numbers or start:stop:step",
                             words=True)
    tolerance_flag: str | None = option(None, text("mu"), "--mu: one meaning per flag", words=True, spelled="--mu",
                                        hidden=True)
    epsilon: float = option(1e-3, _float("epsilon"), "tolerance of every value")
    delta: float = option(0.01, _float("delta"), "failure probability of the whole table")
    bound: str = option("two-stage", one_of("bound", _choices("two-stage", "hoeffding")), "ray budget rule",
                        _choices("two-stage", "hoeffding"))
    no_average: bool = option(False, true_or_false("no_average"), "do not measure E_avg (diffuse beam)")
    parts: bool = option(False, true_or_false("parts"), "glass: certify E_R and E_T too")
    seed: int = option(0, whole_number("seed", 0, 2**32 - 1, "0 <= seed < 2**32"), "seed of the run")
    out: tuple = option((), _words, "files to write: .nc, .npy, .h (an engine's own: .inc, .raw, .png)", words=True,
                        repeat=True, metavar="FILE")
    checkpoint: str | None = option(None, text("checkpoint"), "directory keeping finished groups (resume)",
                                    unset="OUT.parts")
    source: str | None = option(None, text("from"), "a table .nc to read instead of measuring", spelled="--from",
                                metavar="TABLE")
    compare: str | None = option(None, text("compare"), "published table (.npy, .nc, .csv, C header) to hold to the "
                                 "certified intervals", metavar="PUBLISHED")
    array: str | None = option(None, text("array"), "--compare: the array (header) or variable (.nc) to read")
    side: str = option("outside", one_of("side", _choices("outside", "inside")), "--compare, glass: the side",
                       _choices("outside", "inside"))
    average: bool = option(False, true_or_false("average"), "--compare E_avg instead of E")
    rounding: float = option(0.0, _float("rounding"), "--compare: the published values' rounding")
    audit: str | None = option(None, text("audit"), "an engine's published table in its native layout (cycles .h, "
                               "filament dfg.inc, unreal .raw/.png) to audit against certified tables of its model "
                               "(--engine cycles|filament|unreal)", metavar="PUBLISHED")
    figure: str | None = option(None, text("figure"), "--audit: write the heat map of (published - certified)/epsilon "
                                "here (--from TABLE.nc: audit against a certified engine table written before)")
    quiet: bool = option(False, true_or_false("quiet"), "no progress bar")
    overwrite: bool = option(False, true_or_false("overwrite"), "let a .npy's NAME.json and NAME_avg.npy replace "
                             "files of those names that another program wrote")


def respond(session: Session) -> int:
    """``virtspec albedo-table``: a table measured (or read), written, compared; or an engine's tables audited."""

    from virtspec_mi.applications.tables.albedo import albedo_table
    from virtspec_mi.base.checks import parse_values

    flags = session.flags
    _check_paths(flags)
    native = (".inc", ".raw", ".png")
    if flags.audit or (flags.engine in ("filament", "unreal") and any(p.lower().endswith(native) for p in flags.out)):
        return _engine_tables(session)
    if flags.source:
        table = _read_source(flags)
        for path in flags.out:
            table.check_output(path, overwrite=flags.overwrite)  # every output's companions, before any is written
        for path in flags.out:
            table.write(path, overwrite=flags.overwrite)
    else:
        if flags.tolerance_flag is not None:
            raise ValueError("--mu: the cosines of incidence are --cosines (--mu is the certified tolerance of a "
                             "reading everywhere else; a table's is --epsilon)")
        grid = {name: None if getattr(flags, name) is None else list(parse_values(name, getattr(flags, name)))
                for name in ("mu", "alpha", "roughness", "eta")}
        engine = flags.engine if flags.engine is not None else (None if grid["mu"] is not None else "cycles")
        table = albedo_table(flags.model, distribution=flags.distribution, engine=None if engine == "none" else engine,
                             shadowing=flags.shadowing, g1=flags.g1, fresnel=flags.fresnel,
                             epsilon=flags.epsilon, delta=flags.delta, bound=flags.bound,
                             average=not flags.no_average, parts=flags.parts, seed=flags.seed,
                             out=list(flags.out) or None, checkpoint=flags.checkpoint,
                             progress=False if flags.quiet else None, overwrite=flags.overwrite, **grid)
    lines = [table.statement(),
             f"rays {table.rays:,}; {table.provenance.get('seconds_wall', 0):g} s; "
             f"{'' if table.engine == 'grid' else table.engine + ' '}grid "  # "grid": the cells given, no engine's
             f"({' x '.join(f'{d} {len(getattr(table, d))}' for d in table.dims if d != 'side')})"]
    if flags.compare:
        comparison = table.compare(flags.compare, average=flags.average, side=flags.side, array=flags.array,
                                   rounding=flags.rounding)
        return session.report(table, "\n".join(lines), written=flags.out, after=comparison.summary())
    return session.report(table, "\n".join(lines), written=flags.out)


_MEASURING = ("model", "distribution", "shadowing", "g1", "fresnel", "mu", "alpha", "roughness", "eta", "epsilon",
              "delta", "bound", "no_average", "parts", "seed", "checkpoint")
"""The flags (by field) that shape a measurement: meaningless beside ``--from`` (a table already measured)."""


def _check_paths(flags: TableFlags) -> None:
    """
    Before anything is measured or written: no output (``--out``, ``--figure``,
    ``--checkpoint``) is an input (``--from``, ``--audit``, ``--compare``) or another
    output (:func:`virtspec_mi.base.files.check_distinct`); no measuring flag beside ``--from``.
    """

    from virtspec_mi.base.files import check_distinct

    if flags.figure and not flags.audit:
        raise ValueError("--figure draws the heat map of --audit: give --audit PUBLISHED too")
    check_distinct([*(("--out", path) for path in flags.out), ("--figure", flags.figure),
                    ("--checkpoint", flags.checkpoint)],
                   [("--from", flags.source), ("--audit", flags.audit), ("--compare", flags.compare)])
    if flags.source:
        defaults = TableFlags()
        given = [name for name in _MEASURING if getattr(flags, name) != getattr(defaults, name)]
        if given:
            named = ", ".join("--" + name.replace("_", "-") if name != "mu" else "--cosines" for name in given)
            raise ValueError(f"--from TABLE reads a table already measured: {named} would change nothing (they shape "
                             "a new measurement); leave them out, or measure anew without --from")


def _read_source(flags: TableFlags) -> Any:
    """The table of ``--from``; an ``--engine`` beside it must be the table's own."""

    from virtspec_mi.applications.tables.table import read_albedo_table

    table = read_albedo_table(flags.source)
    own = table.engine if table.engine in ("cycles", "filament", "unreal") else "none"
    if flags.engine is not None and flags.engine != own:
        grid = f"{own}'s grid" if own != "none" else "a grid of its own (--engine none)"
        raise ValueError(f"--engine {flags.engine}: the table of --from {flags.source} is on {grid}; leave --engine "
                         f"out or give --engine {own}")
    return table


def _engine_tables(session: Session) -> int:
    """``--audit`` (and an engine's drop-in files): every channel of the engine's model certified at once."""

    from virtspec_mi.applications.tables.audit import audit
    from virtspec_mi.applications.tables.engine_tables import EngineTables, check_engine_sidecar, engine_tables

    flags = session.flags
    if flags.engine not in ("cycles", "filament", "unreal"):
        raise ValueError("--audit needs --engine cycles, filament or unreal (the published table's layout)")
    native = (".h", ".hpp", ".inc", ".raw", ".png", ".nc")
    for path in flags.out:
        if not path.lower().endswith(native):
            raise ValueError(f"--out {path}: an engine table is written as the engine's file or .nc")
    for path in flags.out:  # a drop-in file's PATH.json sidecar: never an input, never another program's file
        if not path.lower().endswith(".nc"):
            check_engine_sidecar(path, flags.overwrite, inputs=[p for p in (flags.source, flags.audit) if p])
    if flags.source:  # a certified engine table written before (--out TABLE.nc)
        tables = EngineTables.from_table(_read_source(flags))
    else:
        tables = engine_tables(flags.engine, epsilon=flags.epsilon, delta=flags.delta, seed=flags.seed,
                               bound=flags.bound, progress=False if flags.quiet else None,
                               checkpoint=flags.checkpoint)
    for path in flags.out:
        tables.write(path, overwrite=flags.overwrite)
    text = f"{tables.statement()}\nrays {tables.rays:,}; {tables.seconds:g} s"
    written = [path + ("" if path.lower().endswith(".nc") else f" (provenance: {path}.json)") for path in flags.out]
    if not flags.audit:
        return session.report(tables, text, written=written)
    report = audit(flags.audit, tables)
    if flags.figure:
        report.figure(flags.figure)
    return session.report(tables, text, written=written, after=report.summary() + (
        f"\nwritten: {flags.figure}" if flags.figure else ""))


ALBEDO_TABLE = Command(
    "albedo-table", "certified directional-albedo tables E(mu, alpha)",
    "Measure Mitsuba's rough conductor (Fresnel = 1) or rough glass on an engine's grid (or your own): every "
    "E(mu, alpha[, eta]) and E_avg within --epsilon of the model's value, the whole table at once with probability "
    ">= 1 - delta; NetCDF, .npy and a C header in Cycles' layout; --compare lists every cell of a published table "
    "outside the certified interval.", EXAMPLES, TableFlags, respond)
"""The tables application's command (:class:`~virtspec_mi.applications.tables.TablesApplication`)."""
