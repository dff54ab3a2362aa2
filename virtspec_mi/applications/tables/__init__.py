"""
Certified albedo tables of renderers, each engine's own tables and their audit
==============================================================================

- :mod:`~virtspec_mi.applications.tables.albedo` — :func:`albedo_table`: E(μ, α) and E_avg;
- :mod:`~virtspec_mi.applications.tables.table` — :class:`AlbedoTable`, its files and its
  comparison with a published table;
- :mod:`~virtspec_mi.applications.tables.engine_tables` — each engine's channels in its own files;
- :mod:`~virtspec_mi.applications.tables.audit` — an engine's published table held to a
  certified one;
- :mod:`~virtspec_mi.applications.tables.command` — ``virtspec albedo-table``, declared by the
  row :class:`TablesApplication`.
"""

from __future__ import annotations

from typing import ClassVar

from virtspec_mi.applications.base import Application, Command
from virtspec_mi.applications.tables.command import ALBEDO_TABLE

__all__ = ["TablesApplication"]


class TablesApplication(Application):
    """Certified albedo tables, engines' tables and their audit: ``vm.albedo_table``, ``virtspec albedo-table``."""

    name: ClassVar[str] = "tables"
    summary: ClassVar[str] = "certified directional-albedo tables of renderers, each engine's own tables, their audit"
    commands: ClassVar[tuple[Command, ...]] = (ALBEDO_TABLE,)
