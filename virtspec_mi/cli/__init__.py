"""
Command line: ``virtspec``
==========================

``virtspec --help`` lists the subcommands, one line each; ``virtspec COMMAND --help``
gives a subcommand's description, every flag and examples.

**Measuring** (:mod:`virtspec_mi.cli.measuring`) — one subcommand per command of every
instrument of the registry (:data:`virtspec_mi.instruments.INSTRUMENTS`: each declares
its :class:`~virtspec_mi.instruments.command.Command`), each the keyed readings of the
instrument through the API (:data:`MEASURING` lists them), e.g.:

- ``virtspec measure SCENE``: one certified reading at one θi, over the scene's
  wavelengths (a spectrum) — :func:`virtspec_mi.measure`: the keyed readings of
  :func:`virtspec_mi.sweep` at that θi and one specimen parameter point, printed as one
  reading;
- ``virtspec sweep SCENE``: readings over θi × wavelength (× specimen parameters),
  :func:`virtspec_mi.sweep`; ``--densities`` (the paper's Fig. 6);
- ``virtspec gonio SCENE``: the goniophotometer, :func:`virtspec_mi.gonio` (R and T with
  their certificate and the per-θo table; ``--plot`` draws each wavelength;
  ``--plot-series``; ``--klems``: the Klems application's extension, an alias of
  ``virtspec klems``);
- ``virtspec sphere SCENE``: the integrating sphere, :func:`virtspec_mi.sphere_measure`
  (``--correct``: the reading corrected by the sphere theory, beside it);
- ``virtspec gloss SCENE``: the gloss meter, ``vm.take("gloss", …)``; an outside
  package's instrument (entry-point group ``virtspec_mi.instruments``) likewise.

Each takes one flag per setting of :class:`~virtspec_mi.settings.Settings` and per
option of its instrument's ``Options`` and of its command's own flags
(:func:`~virtspec_mi.cli.flags.option_flags`, the one flag builder: the field's help,
choices and default; a flag left out takes the scene's value) and the same common flags
(:data:`~virtspec_mi.cli.flags.COMMON_FLAGS`, added by
:func:`~virtspec_mi.cli.measuring.common_flags`, the one place they are defined): ``-D NAME=VALUE`` (the XML scene's ``$NAME``, as ``mitsuba -D``),
``--param NAME=VALUES`` (repeatable; VALUES ``v1,v2,v3`` or ``start:stop:step``) and
``--points`` (:mod:`virtspec_mi.engine.parameters`), ``--out FILE`` (written atomically;
resumable: finished readings are kept in ``FILE.partial.json``,
:mod:`virtspec_mi.engine.checkpoint`), ``--plot FIG``, ``--json``, ``--quiet`` (else a
progress bar on a terminal), ``--workers N`` / ``--scheduler ADDRESS`` /
``--task-readings K`` (Dask: :mod:`virtspec_mi.runtime.scaleout`; the same counts).

**Files** (:mod:`virtspec_mi.cli.files`) — ``virtspec plot|colour FILE``: every kind of result file (a
hemispherical reading or sweep, a goniophotometer reading: its R and T, or its lobes; a
sphere reading: its reading, corrected or hemispherical value), ``--sel NAME=VALUE``
(repeatable): the label of a dim nearest VALUE (a parameter point, θi, a wavelength).

**Applications** (:mod:`virtspec_mi.cli.applying`) — one subcommand per command of every
application of the registry (:data:`virtspec_mi.applications.APPLICATIONS`: each declares
its :class:`~virtspec_mi.applications.base.Command` s): ``virtspec fit``, ``virtspec
albedo-table``, ``virtspec klems``, ``virtspec compare``; an application's
:class:`~virtspec_mi.applications.base.Extension` adds flags to an instrument's subcommand
(``measure --target``, ``gonio --klems``), and every other flag given with them is refused
in one message (:func:`~virtspec_mi.cli.measuring.refuse_others`).

**Others** — ``virtspec bounds`` (the paper's Table 1 and every ``bound=`` rule),
``virtspec scenes`` (the shipped scenes: every ``SCENE`` argument takes their names,
:mod:`virtspec_mi.scenes`), ``virtspec llvm {find,check}`` (the libLLVM Dr.Jit uses;
``make setup`` calls it). Every subparser records what runs it: the command line
dispatches through the rows, with no chain of names.

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
import functools
import signal
import sys
import textwrap
from pathlib import Path
from typing import Any, Sequence

from virtspec_mi.cli.applying import application_commands, application_flags
from virtspec_mi.cli.applying import respond as application_respond
from virtspec_mi.cli.files import add_file_commands, colour, plot
from virtspec_mi.cli.flags import COMMON_FLAGS, Flag, option_flags
from virtspec_mi.cli.measuring import (Measuring, common_flags, measuring_commands, measuring_flags, respond,
                                      unrecognized_hint)

__all__ = ["main", "build_parser", "Measuring", "MEASURING", "measuring_commands", "Flag", "COMMON_FLAGS",
           "common_flags", "option_flags"]


_EXAMPLES = {
    "bounds": "example: virtspec bounds --mu 0.005 --delta 0.001 0.01 0.1",
    "llvm": "example: virtspec llvm check",
    "scenes": "examples:\n  virtspec scenes\n  virtspec scenes --path sphere_150mm_8d\n"
              "  virtspec scenes --copy sphere_150mm_8d my_sphere.xml\n"
              "  virtspec measure soybean_abmb --wavelengths 400:2500:5",
}
"""The examples of the subcommands defined here (the others carry their own)."""


def __getattr__(name: str) -> Any:
    if name == "MEASURING":  # the table, generated from the registry when first asked for
        return measuring_commands()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class _Listing(argparse.HelpFormatter):
    """``virtspec --help``: every subcommand with its summary on one line (``albedo-table`` included)."""

    def __init__(self, prog: str) -> None:
        super().__init__(prog, max_help_position=30)

    def _format_action(self, action: argparse.Action) -> str:
        self._action_max_length = max(self._action_max_length, 18)  # the longest subcommand, indented
        return super()._format_action(action)


def build_parser() -> argparse.ArgumentParser:
    """
    The ``virtspec`` argument parser: one subcommand per command of every instrument's and
    every application's row (their flags from the options' fields), and the command line's
    own; each subparser records what runs it (``respond``) and itself (``parser``, for the
    flags an extension refuses).
    """

    from virtspec_mi.base.version import __version__

    parser = argparse.ArgumentParser(
        prog="virtspec", description="Virtual spectrophotometer: certified reflectance, transmittance and "
                                     "absorptance readings of Mitsuba BSDFs (Baranoski, Rokne & Xu 2001).",
        epilog="virtspec COMMAND --help: its flags and examples.",
        formatter_class=_Listing)
    parser.add_argument("--version", action="version", version=f"virtspec-mi {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, summary: str, description: str, examples: str | None = None,
                run: Any = None) -> argparse.ArgumentParser:
        sub = commands.add_parser(name, help=summary, description=textwrap.fill(description, 100),
                                  epilog=_EXAMPLES[name] if examples is None else examples,
                                  formatter_class=argparse.RawDescriptionHelpFormatter)
        sub.set_defaults(respond=run or _OWN[name], parser=sub)
        return sub

    def listed(examples: Sequence[str]) -> str:
        return "examples:\n" + "\n".join(f"  {line}" for line in examples)

    bounds = command("bounds", "rays per reading under every ray budget (Table 1)",
                     "Rays per reading that certify |m/N - rho| < mu with probability >= 1 - delta: the "
                     "paper's Table 1 (eqs. 15 and 23), then every rule of bound=.")
    bounds.add_argument("--mu", type=float, default=0.005, help="certified tolerance (default 0.005)")
    bounds.add_argument("--delta", type=float, nargs="+", default=[0.001, 0.01, 0.1],
                        help="failure probabilities (default 0.001 0.01 0.1)")

    for row in measuring_commands().values():  # the instruments' rows
        measuring_flags(command(row.name, row.command.summary, row.command.description, listed(row.command.examples),
                                functools.partial(respond, row=row)), row)
    add_file_commands(command)
    for declared in application_commands().values():  # the applications' rows
        application_flags(command(declared.name, declared.summary, declared.description, listed(declared.examples),
                                  functools.partial(application_respond, command=declared)), declared)

    shipped = command("scenes", "the shipped scenes (every SCENE argument takes their names)",
                      "List the scenes shipped with virtspec-mi and their files. Every subcommand that takes a "
                      "SCENE takes a shipped scene's name as well as a file path (e.g. virtspec measure "
                      "soybean_abmb). --copy NAME [DEST] copies one as a template to edit (never over an "
                      "existing file).")
    asked = shipped.add_mutually_exclusive_group()
    asked.add_argument("--path", metavar="NAME", help="print the file of the shipped scene NAME")
    asked.add_argument("--copy", metavar="NAME", help="copy the shipped scene NAME to DEST (a file or a folder; "
                                                      "default ./NAME.xml) and print the copy's path")
    shipped.add_argument("destination", nargs="?", metavar="DEST", help="where --copy puts its copy")

    llvm = command("llvm", "find or check the libLLVM Dr.Jit uses (set-up)",
                   "find: print a libLLVM >= 17 on this machine (exit 1 if none); check: load it in Dr.Jit "
                   "and print its version, or say how to fix it.")
    llvm.add_argument("action", choices=["find", "check"])
    return parser


def _bounds(args: argparse.Namespace) -> int:
    from virtspec_mi.budgets.bounds import format_table_1
    from virtspec_mi.budgets.rules import format_budgets

    print(format_table_1(args.mu, args.delta))
    print()
    print(format_budgets(args.mu, args.delta))
    return 0


def _scenes(args: argparse.Namespace) -> int:
    from virtspec_mi.scenes import answer

    print(answer(args.path, args.copy, args.destination))
    return 0


def _llvm(args: argparse.Namespace) -> int:
    from virtspec_mi.base.llvm import main as llvm_main

    return llvm_main([args.action])


_OWN = {"bounds": _bounds, "scenes": _scenes, "llvm": _llvm, "colour": colour, "plot": plot}
"""The command line's own subcommands (:data:`~virtspec_mi.cli.measuring.OWN_COMMANDS`) and what runs each."""


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``virtspec``; returns the exit status."""

    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # a closed pipe (virtspec bounds | head) ends us quietly
    from virtspec_mi.base.interrupts import catching, exit_status

    # SIGINT and SIGTERM stop a run at its next safe point, its checkpoint saved; taken from the start, so a
    # Ctrl-C while the modules load (the parser imports numpy) is an interrupt too, never a traceback
    with catching():
        try:
            parser = build_parser()
            args, extra = parser.parse_known_args(argv)
            if extra:
                parser.error(f"unrecognized arguments: {' '.join(extra)}{unrecognized_hint(args, extra)}")
        except KeyboardInterrupt as stop:
            return _interrupted(stop, argparse.Namespace(), exit_status)
        from virtspec_mi.base.interrupts import received

        if received() is not None:  # a Ctrl-C whose KeyboardInterrupt an import swallowed (its lock's callback)
            return _interrupted(KeyboardInterrupt(received()), args, exit_status, received())
        return _command(args, exit_status)


def _command(args: argparse.Namespace, exit_status: Any) -> int:
    """Run the command of ``args``; an error or an interrupt becomes a one-line message and the exit status."""

    from virtspec_mi.base.surface import command_line

    try:
        with command_line():  # messages name flags, not Python (virtspec_mi.base.surface)
            return args.respond(args)  # the row's: an instrument's command, an application's, or the command line's own
    except KeyboardInterrupt as stop:  # Ctrl-C (SIGINT) or SIGTERM: virtspec_mi.base.interrupts.Interrupted
        return _interrupted(stop, args, exit_status)
    except Exception as error:
        from virtspec_mi.base.files import WriteError, os_error_text
        from virtspec_mi.base.interrupts import received

        if received() is not None:  # an interrupt raised inside an import or a C extension comes out as another error
            return _interrupted(KeyboardInterrupt(received()), args, exit_status, received())
        if not isinstance(error, (ValueError, RuntimeError, OSError)):
            raise
        with command_line():  # the rescue's words are the command line's too
            shown = _rescued(error)
        if isinstance(shown, OSError) and not isinstance(shown, WriteError):  # its file named, shortened if long
            shown = os_error_text(shown)
        print(f"virtspec: error: {shown}", file=sys.stderr)
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

    from virtspec_mi.base.files import IN_MEMORY

    if getattr(error, "result", None) is None or not error.kept.endswith(IN_MEMORY):  # type: ignore[attr-defined]
        return error
    from virtspec_mi.results.io import rescue

    kept = error.kept[:-len(IN_MEMORY)] + rescue(error.result, error.path)  # type: ignore[attr-defined]
    return error.keeping(kept)  # type: ignore[attr-defined]


# --- the measuring subcommands ---------------------------------------------------------------
