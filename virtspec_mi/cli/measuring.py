"""
The measuring subcommands, generated from the instrument registry
=================================================================

One subcommand per :class:`~virtspec_mi.instruments.command.Command` of every instrument
of :data:`virtspec_mi.instruments.INSTRUMENTS` (:func:`measuring`): its flags are
generated (:func:`measuring_flags`: the settings, the instrument's options, the command's
own flags and :data:`~virtspec_mi.cli.flags.COMMON_FLAGS`), checked into API keywords
before any scene is loaded (:func:`keywords_of`), and the command runs its hook or the
default (:func:`respond`) with a :class:`Session`: take the readings through the API,
draw the figures, print the report.
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

from virtspec_mi.cli.flags import (COMMON_FLAGS, SEVERAL, dest, flag_of, flagged, given, option_flags, pairs,
                                   settings_options)

__all__ = ["Measuring", "measuring_commands", "OWN_COMMANDS", "other_commands", "common_flags", "measuring_flags",
           "respond", "Session", "one_angle", "unrecognized_hint", "report", "table", "run", "drawn", "keywords_of",
           "given_flags", "refuse_others"]


@dataclass(frozen=True)
class Measuring:
    """
    A measuring subcommand: an instrument of the registry and one of its
    :class:`~virtspec_mi.instruments.command.Command`.
    """

    instrument: str
    """Its instrument's key in :data:`virtspec_mi.instruments.INSTRUMENTS` (the flags of its ``options``)."""
    command: Any
    """The :class:`~virtspec_mi.instruments.command.Command` the instrument declares."""

    @property
    def name(self) -> str:
        """The subcommand."""

        return self.command.name

    @property
    def plot(self) -> str:
        """What ``--plot`` draws."""

        return self.command.plot

    @property
    def one_reading(self) -> bool:
        return self.command.one_reading


def measuring_commands() -> dict[str, Measuring]:
    """
    The measuring subcommands, generated from the registry: one per
    :class:`~virtspec_mi.instruments.command.Command` of every instrument
    (:data:`virtspec_mi.instruments.INSTRUMENTS`, outside instruments included). A name
    two instruments declare is refused (``ValueError`` naming both).
    """

    from virtspec_mi.instruments import INSTRUMENTS

    rows: dict[str, Measuring] = {}
    for name, instrument in INSTRUMENTS.items():  # the built-in instruments first: theirs win
        for command in instrument.commands:
            if command.name in rows or command.name in other_commands():
                owner = rows[command.name].instrument if command.name in rows else "virtspec itself"
                if instrument.__module__.split(".")[0] == "virtspec_mi":
                    raise ValueError(f"instrument {name!r} declares the subcommand {command.name!r}, which {owner} "
                                     "already has: give it another name")
                warnings.warn(f"the outside instrument {name!r} ({instrument.__module__}) declares the subcommand "
                              f"{command.name!r}, which {owner} already has: that subcommand left out (give it "
                              "another name)", RuntimeWarning, stacklevel=2)
                continue
            rows[command.name] = Measuring(name, command)
    return rows


OWN_COMMANDS = ("bounds", "colour", "plot", "scenes", "llvm")
"""The subcommands of the command line itself (neither an instrument's nor an application's)."""


def other_commands() -> tuple[str, ...]:
    """The subcommands that are not an instrument's (the registry's may not take their names)."""

    from virtspec_mi.applications import commands

    return (*OWN_COMMANDS, *commands())


def given_flags(args: argparse.Namespace) -> dict[str, str]:
    """
    Every flag given on the command line of ``args`` (its value not the flag's default),
    by its destination: ``{"out": "--out", "defines": "-D"}``, in the parser's order.
    """

    parser = getattr(args, "parser", None)
    flags: dict[str, str] = {}
    for action in () if parser is None else parser._actions:
        if not action.option_strings or action.dest in flags:
            continue
        value = getattr(args, action.dest, None)
        if value is None or value is False or value == [] or value == action.default:
            continue
        flags[action.dest] = action.option_strings[-1] if action.option_strings[-1].startswith("--") else \
            action.option_strings[0]
    return flags


def refuse_others(args: argparse.Namespace, extension: Any) -> None:
    """
    ``ValueError`` naming every flag given with ``extension``'s that it neither declares
    nor :attr:`~virtspec_mi.applications.base.Extension.takes`, in one message
    (``--klems takes none of --out, --plot: …``).
    """

    own = set(extension.flags.names()) | set(extension.takes)
    others = [flag for name, flag in given_flags(args).items() if name not in own]
    if others:
        reason = f" ({extension.reason})" if extension.reason else ""
        raise ValueError(f"{flag_of(extension.active)} takes none of {', '.join(others)}{reason}")


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
    for figure in command.command.all_figures()[1:]:  # --plot is common; a command's other figures
        group.add_argument(figure.flag, metavar="FIG", help=f"figure .png or .svg: {figure.help}")


def measuring_flags(parser: argparse.ArgumentParser, row: Measuring) -> None:
    """
    Every flag of the measuring subcommand ``row``, generated: its ``SCENE``, one flag per
    setting, per option of its instrument and per option of the command's own ``flags``
    (:func:`option_flags`), then the common flags (:func:`common_flags`, its figures among them).
    """

    parser.add_argument("scene", help=row.command.scene)
    option_flags(parser, settings_options(), words=several(row))
    for kind in (instrument_options(row), row.command.flags, *(e.flags for e in extensions_of(row))):
        if kind is not None:
            option_flags(parser, kind)
    common_flags(parser, row)


def extensions_of(row: Measuring) -> tuple[Any, ...]:
    """
    The applications' extensions of the subcommand ``row``
    (:func:`virtspec_mi.applications.extensions`): their flags are the subcommand's, and one
    given hands the command to its application.
    """

    from virtspec_mi.applications import extensions

    return extensions(row.name)


def several(command: Measuring) -> tuple[str, ...]:
    """The settings ``command`` takes as several values (:data:`SEVERAL`): none for one reading."""

    return () if command.one_reading else tuple(SEVERAL)


def instrument_options(command: Measuring) -> Any:
    """The ``Options`` class of ``command``'s instrument (:data:`virtspec_mi.instruments.INSTRUMENTS`), or ``None``."""

    from virtspec_mi.instruments import INSTRUMENTS

    return INSTRUMENTS[command.instrument].options


def one_angle(name: str) -> str:
    """
    The hint for several angles given to a one-reading subcommand ``name``: the subcommand
    of the same instrument that takes several (``measure`` → ``sweep``), if any.
    """

    rows = measuring_commands()
    row = rows.get(name)
    if row is None or not row.one_reading:
        return ""
    several = [other.name for other in rows.values() if other.instrument == row.instrument and not other.one_reading]
    if not several:
        return f"; {name} takes one angle"
    return f"; {name} takes one angle: for several, virtspec {several[0]} SCENE --theta-i 0 30 (or 0:90:10)"


def unrecognized_hint(args: argparse.Namespace, extra: list[str]) -> str:
    """What to do instead of the ``extra`` words: ``sweep`` for several angles after ``measure --theta-i``."""

    from virtspec_mi.api import parse_theta_i

    if getattr(args, "theta_i", None) is None or not one_angle(getattr(args, "command", "")):
        return ""
    try:
        parse_theta_i(" ".join(extra))
    except ValueError:
        return ""
    return one_angle(args.command)


def keywords_of(args: argparse.Namespace, command: Measuring) -> dict[str, Any]:
    """
    The API keywords of a measuring subcommand's flags — the settings and its instrument's
    options given (each checked, naming its flag: :func:`given`) and the common flags —
    checked before any scene is loaded or ray traced: the ``--out`` suffix and folder, the
    figures' suffixes, one reading for ``measure``, no parameter sweep to draw.
    """

    from virtspec_mi.base.files import check_distinct
    from virtspec_mi.results.io import check_output, check_plain_csv
    from virtspec_mi.results.plot import check_figure_path

    out = flagged("--out", check_output, args.out) if args.out else None
    if args.csv_plain:
        plain = flagged("--csv-plain", lambda path: check_output(path, "csv_plain"), args.csv_plain)
        flagged("--csv-plain", lambda path: check_plain_csv(path, "csv_plain"), plain)
        if out is not None and plain.resolve() == out.resolve():
            raise ValueError(f"--csv-plain: {plain} is also --out (the result file); give the plain CSV another name")
    figures = {figure.flag: getattr(args, dest(figure.flag), None) for figure in command.command.all_figures()}
    for flag, path in figures.items():
        flagged(flag, check_figure_path, path)
    check_distinct([("--out", out), ("--csv-plain", args.csv_plain), *figures.items()],  # none over the scene
                   [("SCENE", getattr(args, "scene", None))])
    settings = given(args, settings_options(), several=several(command), hint=one_angle(args.command))
    options = instrument_options(command)
    parameters = parsed_parameters(pairs(args.params, "--param"))
    if command.one_reading:
        check_one_reading(command, parameters)
    else:
        drawn = [flag for flag, path in figures.items() if path]
        if parameters and drawn:
            raise ValueError(f"{drawn[0]} draws a sweep over wavelength x theta_i at one parameter point: write the "
                             "parameter sweep with --out FILE, then draw a point with virtspec plot FILE --sel "
                             "NAME=VALUE")
    return {**settings, **({} if options is None else given(args, options)), "parameters": parameters,
            "points": args.points, "defines": pairs(args.defines, "-D"), "out": out,
            "progress": False if args.quiet else None,
            "workers": args.scheduler if args.scheduler is not None else args.workers,
            "task_readings": args.task_readings}


def parsed_parameters(parameters: dict[str, str]) -> dict[str, tuple[float, ...]]:
    """
    The values of each ``--param NAME=VALUES`` (:func:`virtspec_mi.api.parse_values`:
    numbers and ``start:stop:step`` ranges), parsed once here and handed to the API as
    numbers; a bad one is refused naming its flag.
    """

    from virtspec_mi.api import parse_values

    return {name: flagged(f"--param {name}", lambda text, name=name: parse_values(name, text), values)
            for name, values in parameters.items()}


def check_one_reading(command: Measuring, parameters: dict[str, tuple[float, ...]]) -> None:
    """``measure`` reads one value of each specimen parameter (``sweep`` takes several; its one θi: one flag value)."""

    for name, values in parameters.items():
        if len(values) != 1:
            raise ValueError(f"--param {name}: {command.name} takes one value per parameter (got {len(values)}; "
                             "virtspec sweep takes several)")


KEYWORD_FLAGS = {"parameters": "--param", "defines": "-D", "progress": None}
"""The API keywords whose flag is not their name with dashes (``None``: no flag)."""


def run(args: argparse.Namespace, function: Callable[..., Any], keywords: dict[str, Any]) -> Any:
    """
    ``function(args.scene, **keywords)``; the checkpoint of its ``out`` is named if it is
    interrupted (:func:`main`). A ``ValueError`` whose message starts with the name of a
    keyword given (a rule between options that needs the scene's values, e.g.
    ``pilot_delta must satisfy 0 < pilot_delta < delta``) names that keyword's flag.
    """

    from virtspec_mi.api import checkpoint_for

    out = keywords["out"]
    args.checkpoint = checkpoint_for(out) if out is not None else None
    try:
        return function(args.scene, **keywords)
    except ValueError as error:
        named = [name for name, value in keywords.items()
                 if not (value is None or value is False or value == {}) and str(error).startswith(name + " ")]
        flags = {**KEYWORD_FLAGS, "workers": "--workers" if args.scheduler is None else "--scheduler"}
        flag = flags.get(named[0], flag_of(named[0])) if named else None
        if flag is None:
            raise
        raise ValueError(f"{flag}: {error}") from error


UNITS = {"wavelength": "nm", "theta_i": "deg"}
"""The dims a figure is drawn for one label at a time, and the unit in its file name."""


def drawn(path: str | None, draw: Callable[..., Any], dim: str = "", labels: Sequence[float] = ()) -> list[Any]:
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
        each = path.with_name(f"{path.stem}_{float(label):g}{UNITS[dim]}{path.suffix}")
        draw(each, **{dim: float(label)})
        drawn.append(each)
    return drawn


def report(args: argparse.Namespace, result: Any, text: str, figures: Sequence[Any] = (),
            data: dict[str, Any] | None = None, stream: Any = None) -> int:
    """
    What a measuring subcommand prints: with ``--json`` the result as one JSON object
    (``data``, default its ``as_dict()``); else ``text`` and the files written
    (``written: FILE``, ``plot: FIG``) on ``stream`` (default stdout) — nothing with
    ``--quiet`` and ``--out`` (the file holds the result).
    """

    plain = getattr(args, "csv_plain", None)
    if plain:
        result.write(plain, plain=True)
    if args.json:
        print(result.sealed_json() if data is None else json.dumps(data))
        return 0
    if args.quiet and args.out:
        return 0
    written = [path for path in (args.out, plain) if path]
    lines = [text, *(f"written: {path}" for path in written), *(f"plot: {path}" for path in figures)]
    print("\n".join(lines), file=stream or sys.stdout)
    return 0


def table(args: argparse.Namespace, result: Any, figures: Sequence[Any] = ()) -> int:
    """
    A command's ``table`` output (:attr:`~virtspec_mi.instruments.command.Command.output`):
    the readings as a CSV table on stdout, the summary on stderr (nothing there with ``--quiet``).
    """

    from virtspec_mi.results.io import csv_text

    if not args.quiet:  # the summary on stderr, so that the table can be piped
        report(args, result, result.summary(), figures, stream=sys.stderr)
    elif args.csv_plain:  # the report writes it otherwise
        result.write(args.csv_plain, plain=True)
    print(csv_text(result.to_dataset()), end="")
    return 0


class Session:
    """
    What a measuring subcommand's hook is given (:class:`virtspec_mi.instruments.command.Session`):
    the flags checked into API keywords before any scene is loaded, and the services every
    measuring subcommand shares — take the readings, draw the figures, print the report.
    """

    def __init__(self, args: argparse.Namespace, row: Measuring) -> None:
        self.args, self.row, self.command = args, row, row.command
        self.keywords = keywords_of(args, row)
        kind = row.command.flags
        self.flags = None if kind is None else kind(**given(args, kind))

    def take(self, **overrides: Any) -> Any:
        from virtspec_mi import api

        name = self.command.function
        function = getattr(api, name) if name is not None else functools.partial(api.take, self.row.instrument)
        return run(self.args, function, {**self.keywords, **overrides})

    def draw(self, result: Any) -> list[Any]:
        import numpy as np

        paths: list[Any] = []
        for flag in self.command.all_figures():
            labels = np.atleast_1d(result.coords[flag.dim]) if flag.dim else ()
            draw = functools.partial(result.plot, figure=flag.figure or None, **flag.keywords)
            paths += drawn(getattr(self.args, dest(flag.flag), None), draw, flag.dim, labels)
        return paths

    def report(self, result: Any, text: str, figures: Sequence[Any] = (), data: dict[str, Any] | None = None,
               stream: Any = None) -> int:
        return report(self.args, result, text, figures, data, stream)

    def default(self) -> int:
        result = self.take()
        if self.command.one_reading:  # one reading over wavelength: its other labels scalar
            result = result.squeeze(*(d for d in result.dims if d not in ("wavelength", *result.KIND_DIMS)))
        figures = self.draw(result)
        if self.command.output == "table" and self.keywords["out"] is None and not self.args.json:
            return table(self.args, result, figures)
        return self.report(result, result.summary(), figures)

    @contextmanager
    def cluster(self) -> Iterator[Any]:
        workers = self.keywords["workers"]
        if workers is None:
            yield None
            return
        from virtspec_mi.runtime.scaleout import connect

        with connect(workers) as client:
            yield client


def respond(args: argparse.Namespace, row: Measuring) -> int:
    """
    A measuring subcommand: an application's, when one of its extension's flags is given
    (:func:`extensions_of`), else its hook (:attr:`~virtspec_mi.instruments.command.Command.respond`)
    or the default.
    """

    session = Session(args, row)
    for extension in extensions_of(row):  # an application's flag given: the command is the application's
        own = given(args, extension.flags)
        flags = extension.flags(**own)
        if extension.given(flags):
            refuse_others(args, extension)
            return extension.respond(session, flags)
        if own:  # its other flags act only with the one that hands the command over
            names, active = ", ".join(map(flag_of, own)), flag_of(extension.active)
            raise ValueError(f"{names} {'acts' if len(own) == 1 else 'act'} only with {active}: give {active} too "
                             f"(e.g. {extension.example}) or leave {names} out")
    respond = row.command.respond
    return session.default() if respond is None else respond(session)
