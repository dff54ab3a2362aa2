"""
Applications: what a user asks, answered with the instruments' readings
=======================================================================

Each application is one folder and one row of :data:`APPLICATIONS` (an
:class:`~virtspec_mi.applications.base.Application`), or an entry point of the group
:data:`ENTRY_POINTS` (``virtspec_mi.applications``) in another package. An application
takes its readings through the instrument seam (:mod:`virtspec_mi.runtime.reading`:
an instrument's init, process and postprocess), never through the API above it.

- :mod:`.targets` — certified derived quantities (colour, bands, indices, fAPAR, albedo):
  ``virtspec measure --target``;
- :mod:`.fitting` — specimen parameters fitted to a measured spectrum (``virtspec fit``);
- :mod:`.tables` — certified albedo tables of renderers, each engine's own tables and
  their audit (``virtspec albedo-table``);
- :mod:`.klems` — certified Klems BSDF files (``virtspec klems``; alias ``virtspec gonio --klems``);
- :mod:`.comparison` — simulated against measured spectra (``virtspec compare``);
- :mod:`.coverage` — the coverage harness of the certificates.
"""

from __future__ import annotations

from virtspec_mi.base.entry_points import discovered as entry_point_rows
from virtspec_mi.applications.base import Application, Command, Extension
from virtspec_mi.applications.comparison.command import ComparisonApplication
from virtspec_mi.applications.fitting import FittingApplication
from virtspec_mi.applications.klems import KlemsApplication
from virtspec_mi.applications.tables import TablesApplication
from virtspec_mi.applications.targets import TargetsApplication

__all__ = ["APPLICATIONS", "ENTRY_POINTS", "Application", "Command", "Extension", "discovered", "extensions",
           "commands"]

ENTRY_POINTS = "virtspec_mi.applications"
"""The entry-point group of outside applications."""


def discovered(builtin: tuple[type[Application], ...]) -> dict[str, type[Application]]:
    """
    The applications ``builtin`` and those of every installed package's entry point of
    :data:`ENTRY_POINTS`, by name (:func:`virtspec_mi.base.entry_points.discovered`).
    """

    return entry_point_rows(ENTRY_POINTS, builtin, Application)


APPLICATIONS: dict[str, type[Application]] = discovered((TargetsApplication, FittingApplication, TablesApplication,
                                                         KlemsApplication, ComparisonApplication))
"""Every application by name: the built-in ones, then the outside ones (:data:`ENTRY_POINTS`)."""


def extensions(command: str) -> tuple[Extension, ...]:
    """The extensions of the instrument subcommand ``command`` that the applications declare."""

    return tuple(e for application in APPLICATIONS.values() for e in application.extensions if e.command == command)


def commands() -> dict[str, tuple[type[Application], Command]]:
    """
    Every application's own subcommand by name, with its application; a name two
    applications declare is refused (``ValueError`` naming both).
    """

    rows: dict[str, tuple[type[Application], Command]] = {}
    for application in APPLICATIONS.values():
        for command in application.commands:
            if command.name in rows:
                raise ValueError(f"application {application.name!r} declares the subcommand {command.name!r}, which "
                                 f"application {rows[command.name][0].name!r} already has: give it another name")
            rows[command.name] = (application, command)
    return rows
