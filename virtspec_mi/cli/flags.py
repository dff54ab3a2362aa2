"""
The flags of the command line, defined once: the common flags and the one flag builder
======================================================================================

:data:`COMMON_FLAGS` are the flags every measuring subcommand takes (added by
:func:`virtspec_mi.cli.measuring.common_flags`); :func:`option_flags` makes one flag per
field of an :class:`~virtspec_mi.settings.Options` class (the settings, an instrument's
options, a command's own flags) and :func:`given` reads them back, each checked by its
field's own check so that a bad value names its flag.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Any, Callable, Sequence

__all__ = ["Flag", "COMMON_FLAGS", "SEVERAL", "option_flags", "flag_name", "given", "pairs", "flag_of", "flagged", "dest",
           "settings_options"]


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
    Flag("--csv-plain", dict(metavar="FILE.csv",
                             help="also write the result as a plain CSV for a spreadsheet: a row of column names "
                                  "and one row per reading, without the attribute line of an --out .csv (not read "
                                  "back as a result)")),
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


SEVERAL = {"theta_i": "parse_theta_i"}
"""Settings a grid subcommand takes as several values, and the parser of :mod:`virtspec_mi.api` that reads them."""


def pairs(items: Sequence[str], flag: str) -> dict[str, str]:
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


def settings_options() -> Any:
    """The common :class:`~virtspec_mi.settings.Settings` class, imported when the parser is built."""

    from virtspec_mi.settings import Settings

    return Settings


def flag_of(name: str) -> str:
    """The command-line flag of option ``name``: ``--theta-i``."""

    return "--" + name.replace("_", "-")


def option_flags(parser: argparse.ArgumentParser, kind: Any, words: tuple[str, ...] = (),
                 scene: bool = True) -> None:
    """
    The one flag builder: one flag per option of ``kind`` (an
    :class:`~virtspec_mi.settings.Options` class: ``--theta-i`` …), in a group named by its
    ``title``, its choices, default and help from the field; a switch (a ``bool`` default)
    is a flag without a value, an option the command line writes as several words (the
    field's ``words``, or one named in ``words``) takes them all, a ``repeat`` option is
    given once per value, a ``positional`` one is an argument (an application's command).
    Values go to the options as given (they validate them: :func:`given`); with ``scene``
    a flag left out takes the scene's value, else the default.
    """

    from dataclasses import fields

    from virtspec_mi.settings import help_text, shown

    group = parser.add_argument_group(kind.title)
    for item in fields(kind):
        meta = item.metadata
        if not meta["flag"]:
            continue
        several = meta["words"] or item.name in words
        if meta.get("positional"):
            group.add_argument(item.name, nargs="+" if several else None, metavar=meta.get("metavar") or None,
                               help=help_text(item))
            continue
        value = shown(item.default) if item.default is not None else meta["unset"]
        default = f"default: the scene's, else {value}" if scene else f"default {value}"
        each = "; several values or start:stop:step ranges, one reading each" if item.name in words else ""
        text = f"{help_text(item)}{each}{'; repeatable' if meta.get('repeat') else ''} ({default})"
        keywords: dict[str, Any] = dict(dest=item.name, help=argparse.SUPPRESS if meta.get("hidden") else text)
        if meta.get("required"):
            keywords["required"] = True
        if meta.get("metavar"):
            keywords["metavar"] = meta["metavar"]
        if isinstance(item.default, bool):
            keywords.pop("metavar", None)
            group.add_argument(flag_name(item), action="store_true", default=None, **keywords)
        elif meta.get("repeat"):  # several words too: --out A B, as --out A --out B
            group.add_argument(flag_name(item), action="extend" if several else "append",
                               nargs="+" if several else None, **keywords)
        else:
            group.add_argument(flag_name(item), nargs="+" if several else None,
                               choices=list(meta["choices"]) if meta["choices"] else None, **keywords)


def flag_name(item: Any) -> str:
    """The command-line flag of the option field ``item``: its ``spelled`` name, else ``--theta-i`` from its name."""

    return item.metadata.get("spelled") or flag_of(item.name)


def given(args: argparse.Namespace, kind: Any, several: tuple[str, ...] = (), hint: str = "") -> dict[str, Any]:
    """
    The options of ``kind`` given on the command line (several words joined into one
    string), each checked here by its field's own check — or, for one named in
    ``several``, by its parser in :data:`SEVERAL` — so that a bad value names its flag
    (``--theta-i: theta_i must satisfy …``) before any scene is loaded; the API validates
    them again (the same checks). ``hint`` follows the message of a setting of
    :data:`SEVERAL` refused as one value (a one-reading subcommand given several).
    """

    from dataclasses import fields

    from virtspec_mi import api

    given = {}
    for item in fields(kind):
        value = getattr(args, item.name, None) if item.metadata["flag"] else None
        if value is None:
            continue
        if item.metadata.get("repeat"):
            value = tuple(value)
        elif isinstance(value, list):
            value = " ".join(value)
        check = getattr(api, SEVERAL[item.name]) if item.name in several else item.metadata["check"]
        try:
            check(value)
        except ValueError as error:
            shown = hint if item.name in SEVERAL and item.name not in several else ""
            raise ValueError(f"{flag_name(item) if not item.metadata.get('positional') else item.name.upper()}: "
                             f"{error}{shown}") from None
        given[item.name] = value
    return given


def flagged(flag: str, check: Callable[[Any], Any], value: Any) -> Any:
    """``check(value)``; its ``ValueError`` names ``flag`` (``--out: out must end in …``)."""

    try:
        return check(value)
    except ValueError as error:
        raise ValueError(f"{flag}: {error}") from None


def dest(flag: str) -> str:
    """The ``argparse`` destination of a flag: ``--plot-series`` → ``plot_series``."""

    return flag.lstrip("-").replace("-", "_")
