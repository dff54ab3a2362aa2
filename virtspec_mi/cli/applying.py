"""
The applications' subcommands, generated from their rows
==========================================================

One subcommand per :class:`~virtspec_mi.applications.base.Command` of every application of
:data:`virtspec_mi.applications.APPLICATIONS` (outside ones included): its arguments and
flags made by the one flag builder (:func:`~virtspec_mi.cli.flags.option_flags`) from its
``flags`` class, read back checked (:func:`~virtspec_mi.cli.flags.given`: a bad value names
its flag) into an instance of that class, and its ``respond`` given an
:class:`ApplicationSession`: those flags, the shared report and the result files read at
the ``--sel`` labels.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any, Sequence

from virtspec_mi.cli.flags import given, option_flags

__all__ = ["ApplicationSession", "application_commands", "application_flags", "respond"]


def application_commands() -> dict[str, Any]:
    """Every application's subcommand by name (:func:`virtspec_mi.applications.commands`): its ``Command``."""

    from virtspec_mi.applications import commands

    return {name: command for name, (_, command) in commands().items()}


def application_flags(parser: argparse.ArgumentParser, command: Any) -> None:
    """The arguments and flags of the application's subcommand ``command``, from its ``flags`` class."""

    option_flags(parser, command.flags, scene=False)


class ApplicationSession:
    """What an application's ``respond`` is given (:class:`virtspec_mi.applications.base.Session`)."""

    def __init__(self, args: argparse.Namespace, command: Any) -> None:
        self.args, self.command = args, command
        self.flags = command.flags(**given(args, command.flags))

    def report(self, result: Any, text: str, written: Sequence[Any] = (), figures: Sequence[Any] = (),
               data: dict[str, Any] | None = None, after: str = "") -> int:
        if getattr(self.flags, "json", False):
            print(json.dumps(result.as_dict() if data is None else data))
            return 0
        lines = [text, *(f"written: {path}" for path in written), *(f"plot: {path}" for path in figures)]
        print("\n".join(lines + ([after] if after else [])), file=sys.stdout)
        return 0

    def read(self, path: Any) -> Any:
        from virtspec_mi.cli.files import selected

        return selected(path, getattr(self.flags, "selections", ()))


def respond(args: argparse.Namespace, command: Any) -> int:
    """The application's subcommand ``command``: its ``respond`` with a session of the flags given."""

    return command.respond(ApplicationSession(args, command))
