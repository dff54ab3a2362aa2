"""
An instrument's command line, declared beside it: :class:`Command`
==================================================================

Every instrument of the registry (:data:`virtspec_mi.instruments.INSTRUMENTS`) declares
the ``virtspec`` subcommands that take its readings (``Instrument.commands``), and the
command line is generated from them: one subcommand per :class:`Command`, with its help
(``summary``, ``description``, ``examples``), a flag per setting of
:class:`~virtspec_mi.settings.Settings`, per option of the instrument's ``options`` and per
option of the command's own ``flags`` (an :class:`~virtspec_mi.settings.Options` class
of :func:`~virtspec_mi.settings.option` fields: the one flag builder reads them), the
common flags (``-D``, ``--param``/``--points``, ``--out`` with resume, ``--plot``,
``--json``, ``--quiet``, ``--workers``/``--scheduler``/``--task-readings``) and its
figure flags (:class:`FigureFlag`: a flag, the figure of the result's ``FIGURES`` it draws,
one figure per label of a dim). A command that prints more than the result's summary declares a
``respond`` hook: it receives a :class:`Session` (the command line's services: take the
readings, draw, report) and returns the exit status.

A new instrument therefore brings its subcommand with it: one module (or folder) and one
registry row, or one entry point of the group ``virtspec_mi.instruments``.

References
----------
Python documentation, ``argparse`` (sub-commands); xarray's backend entry points
(``xarray.backends``), the model for outside instruments.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, ContextManager, Protocol, Sequence

__all__ = ["Command", "FigureFlag", "Session", "Subcommand"]


@dataclass(frozen=True)
class FigureFlag:
    """
    A figure flag of a measuring subcommand: the figure of the result's ``FIGURES``
    (:mod:`virtspec_mi.results.figures`) it draws, ``result.plot(path, figure=figure,
    **keywords, **{dim: label})``, per label of ``dim``.
    """

    flag: str
    """The flag, e.g. ``--plot``."""
    figure: str
    """The name of the figure in the result's ``FIGURES`` (``polar``, ``series``), or ``""``: its first."""
    help: str
    """What it draws (the flag's help)."""
    dim: str = ""
    """One figure per label of this dim when the result has several (``FIG_550nm.png``), or ``""``: one figure."""
    keywords: dict[str, Any] = field(default_factory=dict)
    """Keywords of the method (e.g. the quantities a spectrum figure draws)."""


@dataclass(frozen=True)
class Subcommand:
    """The help of one ``virtspec`` subcommand, an instrument's (:class:`Command`) or an application's."""

    name: str
    """The subcommand."""
    summary: str
    """One line in ``virtspec --help``."""
    description: str
    """The head of ``virtspec NAME --help``."""
    examples: tuple[str, ...]
    """Command lines shown under ``--help`` (each runs as written from anywhere: shipped scenes by name)."""


@dataclass(frozen=True)
class Command(Subcommand):
    """One ``virtspec`` subcommand of an instrument (see the module docstring)."""

    figures: tuple[FigureFlag, ...] = ()
    """Its figure flags (the first is ``--plot``); none: the result's ``plot`` as ``--plot``."""
    one_reading: bool = False
    """One θi and one specimen parameter point, printed as one reading; else a grid of readings."""
    flags: Any = None
    """An :class:`~virtspec_mi.settings.Options` class of the command's own flags beyond the instrument's options."""
    function: str | None = None
    """The API function that takes its readings (``sweep``, ``gonio`` …), or ``None``: ``take(instrument, …)``."""
    respond: Callable[["Session"], int] | None = None
    """
    What the command does with the session (:class:`Session`), or ``None``: take, print
    the summary, draw. An application extends a command from above with flags of its own
    (:class:`virtspec_mi.applications.base.Extension`), never by a hook named here.
    """
    output: str = "summary"
    """
    What it prints: ``"summary"`` the result's summary; ``"table"`` without ``--out`` or
    ``--json`` the readings as a CSV table on stdout and the summary on stderr (so that the
    table can be piped). The command line prints it; the instrument declares it.
    """
    scene: str = ("Mitsuba XML scene with 'emitter' and 'specimen' disks, or a shipped scene's name "
                  "(virtspec scenes)")
    """The help of its ``SCENE`` argument."""

    @property
    def plot(self) -> str:
        """What ``--plot`` draws."""

        return self.figures[0].help if self.figures else "the result's figure"

    def all_figures(self) -> tuple[FigureFlag, ...]:
        """Its figure flags, ``--plot`` (the result's first figure) when it declares none."""

        return self.figures or (FigureFlag("--plot", "", self.plot),)


class Session(Protocol):
    """
    What the command line gives a :attr:`Command.respond` hook: the parsed flags, the API
    keywords they make (checked), and the services every measuring subcommand shares.
    """

    args: Any
    """The parsed command line (``argparse.Namespace``)."""
    command: Command
    """The subcommand."""
    keywords: dict[str, Any]
    """The API keywords of the flags given (settings, options, common flags), checked."""
    flags: Any
    """The command's own flags given (an instance of :attr:`Command.flags`), or ``None``."""

    def take(self, **overrides: Any) -> Any:
        """The readings (the command's API function with :attr:`keywords`, ``overrides`` replacing some)."""

    def draw(self, result: Any) -> list[Any]:
        """Every figure flag given, drawn from ``result``; the paths drawn."""

    def report(self, result: Any, text: str, figures: Sequence[Any] = (), data: dict[str, Any] | None = None,
               stream: Any = None) -> int:
        """Print ``text`` (or, with ``--json``, ``data`` or the result) and the files written; the exit status."""

    def default(self) -> int:
        """What a command without a hook does: take, print the summary (one reading: squeezed), draw."""

    def cluster(self) -> ContextManager[Any]:
        """One Dask client for several takes (``--workers``/``--scheduler``), or ``None`` in this process."""
