"""
An application, declared beside it: :class:`Application` and :class:`Extension`
===============================================================================

An application answers a user's question with the instruments' readings — a certified
target, a fit, a table for a renderer, a Klems file, a comparison. Each is one folder of
:mod:`virtspec_mi.applications` and one row of :data:`virtspec_mi.applications.APPLICATIONS`
(or an entry point of the group ``virtspec_mi.applications`` in another package), as an
instrument is one folder and one row of :data:`virtspec_mi.instruments.INSTRUMENTS`.

A row declares what the rest of the package generates from it:

- its :class:`Extension` s: flags it adds to an instrument's subcommand and what that
  command does when one of them is given (``virtspec measure --target``: a certified
  target; ``virtspec gonio --klems``: the Klems matrices). The command line adds the flags
  and hands the command to the application; nothing outside the application's folder
  names it (no ``"module:function"`` hook, no list of its flags elsewhere);
- its ``results``: the result kinds it returns (:class:`~virtspec_mi.results.base.ResultBase`
  kinds, registered by their format tags when their classes are defined), which
  :func:`virtspec_mi.read_result` reads (it loads the registry).

References
----------
Python Packaging User Guide, "Entry points specification"; xarray, "How to add a new
backend" (the ``xarray.backends`` entry-point group); Eradiate's experiment registry.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, ClassVar

__all__ = ["Application", "Extension"]


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

    def given(self, flags: Any) -> bool:
        """Whether ``flags`` (an instance of :attr:`flags`) hands the command to the application."""

        return getattr(flags, self.active) not in (None, False)


class Application:
    """
    One application (see the module docstring): its ``name`` (a word), a one-line
    ``summary`` and its :class:`Extension` s.
    """

    name: ClassVar[str]
    """Its name in :data:`virtspec_mi.applications.APPLICATIONS`."""
    summary: ClassVar[str]
    """What it answers, in one line."""
    extensions: ClassVar[tuple[Extension, ...]] = ()
    """The instruments' subcommands it extends."""
    results: ClassVar[tuple[type, ...]] = ()
    """The result kinds it returns (:class:`~virtspec_mi.results.base.ResultBase` kinds)."""
