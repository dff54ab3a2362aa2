"""
An application, declared beside it: :class:`Application` and :class:`Extension`
===============================================================================

An application answers a user's question with the instruments' readings — a certified
target, a fit, a table for a renderer, a Klems file, a comparison. Each is one folder of
:mod:`virtspec_mi.applications` and one row of :data:`virtspec_mi.applications.APPLICATIONS`
(or an entry point of the group ``virtspec_mi.applications`` in another package), as an
instrument is one folder and one row of :data:`virtspec_mi.instruments.INSTRUMENTS`.

A row declares what the rest of the package generates from it:

- its :class:`Command` s: ``virtspec`` subcommands of its own (``virtspec fit``,
  ``virtspec albedo-table``, ``virtspec klems``, ``virtspec compare``), each with its help,
  examples and flags (an :class:`~virtspec_mi.settings.Options` class: the command line's
  one flag builder makes its arguments and flags from the fields) and a ``respond``
  function that receives a :class:`Session` (the command line's services: the flags
  given, the shared report) and returns the exit status;
- its :class:`Extension` s: flags it adds to an instrument's subcommand and what that
  command does when one of them is given (``virtspec measure --target``: a certified
  target; ``virtspec gonio --klems``: the Klems matrices, an alias of ``virtspec klems``),
  with the keywords it :attr:`~Extension.takes`: the command line refuses every other flag
  given, in one message (``--klems takes none of --out, --plot``);
- its ``results``: the result kinds it returns (:class:`~virtspec_mi.results.base.ResultBase`
  kinds, registered by their format tags when their classes are defined), which
  :func:`virtspec_mi.read_result` reads (it loads the registry).

The command line is generated from these rows as from the instruments' (no
``"module:function"`` hook, no list of an application's flags elsewhere).

References
----------
Python Packaging User Guide, "Entry points specification"; xarray, "How to add a new
backend" (the ``xarray.backends`` entry-point group); Eradiate's experiment registry.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Protocol, Sequence

from virtspec_mi.instruments.command import Subcommand

__all__ = ["Application", "Command", "Extension", "Session"]


@dataclass(frozen=True)
class Command(Subcommand):
    """One ``virtspec`` subcommand of an application (see the module docstring): its help, its flags, its action."""

    flags: type
    """Its arguments and flags: an :class:`~virtspec_mi.settings.Options` class (positional fields are arguments)."""
    respond: Callable[["Session"], int]
    """``respond(session)``: what the command does; the exit status."""


class Session(Protocol):
    """What the command line gives an application's :attr:`Command.respond`."""

    args: Any
    """The parsed command line (``argparse.Namespace``)."""
    flags: Any
    """The arguments and flags given, checked: an instance of :attr:`Command.flags`."""

    def report(self, result: Any, text: str, written: Sequence[Any] = (), figures: Sequence[Any] = (),
               data: dict[str, Any] | None = None, after: str = "") -> int:
        """
        Print ``text``, the files ``written`` and the ``figures`` drawn, then ``after`` (or,
        when the flags have ``json`` and it is given, ``data``, default ``result.as_dict()``,
        as one JSON object); the exit status.
        """

    def read(self, path: Any) -> Any:
        """The result file ``path`` (any kind), at the labels of the flags' ``selections`` (``--sel``) if any."""


@dataclass(frozen=True)
class Extension:
    """An application's flags on an instrument's subcommand, and what the command does when one is given."""

    command: str
    """The instrument's subcommand it extends (``measure``, ``gonio``)."""
    flags: type
    """Its flags: an :class:`~virtspec_mi.settings.Options` class (the one flag builder reads its fields)."""
    respond: Callable[[Any, Any], int]
    """``respond(session, flags)`` when one of its flags is given: the exit status."""
    active: str
    """The flag field whose value (not ``None``/``False``) hands the command to the application."""
    takes: tuple[str, ...] = ()
    """
    The subcommand's other keywords (settings, common flags, by name: ``mu``, ``quiet``,
    ``defines``) the extension takes; every other flag given with :attr:`active` is refused
    by the command line, in one message naming them all.
    """
    reason: str = ""
    """Why it takes no others (the end of that message)."""
    example: str = ""
    """Its active flag as given (``--target colour,dE00=0.5``): named when its other flags are given alone."""

    def given(self, flags: Any) -> bool:
        """
        Whether ``flags`` (an instance of :attr:`flags`) hands the command to the
        application; its other flags given without :attr:`active` are refused by the command line.
        """

        return getattr(flags, self.active) not in (None, False)


class Application:
    """
    One application (see the module docstring): its ``name`` (a word), a one-line
    ``summary``, its :class:`Command` s and its :class:`Extension` s.
    """

    name: ClassVar[str]
    """Its name in :data:`virtspec_mi.applications.APPLICATIONS`."""
    summary: ClassVar[str]
    """What it answers, in one line."""
    commands: ClassVar[tuple[Command, ...]] = ()
    """Its own ``virtspec`` subcommands."""
    extensions: ClassVar[tuple[Extension, ...]] = ()
    """The instruments' subcommands it extends."""
    results: ClassVar[tuple[type, ...]] = ()
    """The result kinds it returns (:class:`~virtspec_mi.results.base.ResultBase` kinds)."""
    example: ClassVar[dict[str, Any]] = {}
    """
    A small run of the application, end to end (the contract test's fixture,
    ``tests/applications/test_applications.py``):

    - ``argv``: a command line of one of its commands (``"{tmp}"`` stands for a folder);
    - ``inputs``: ``inputs(folder)`` writes the files ``argv`` reads (optional);
    - ``api``: ``api(folder)``, the same run through its Python function;
    - ``counts``: ``counts(result)``, what must be identical between the two (exact
      counts, or values computed from them);
    - ``outputs``: the files ``argv`` writes in the folder; ``read``: ``read(path)`` the
      result in one of them (its ``counts`` compared); ``formats``: the suffixes its result
      is written in (``result.write``) and read back; ``printed``: with ``--json`` in
      ``argv``, ``printed(data)`` the counts of the JSON object printed;
    - ``resume``: a longer command line whose run keeps its work in ``checkpoint`` (a file
      or folder in the folder) meanwhile: interrupted there, it resumes to the same counts;
    - ``workers``: ``True`` when it traces on Dask workers (``--workers 2``: the same counts).
    """
