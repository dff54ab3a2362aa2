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

from typing import Any, ClassVar

import numpy as np

from virtspec_mi.applications.base import Application, Command
from virtspec_mi.applications.tables.command import ALBEDO_TABLE
from virtspec_mi.applications.tables.table import AlbedoTable, TableComparison

__all__ = ["TablesApplication"]


def _api(folder: Any) -> Any:
    from virtspec_mi.applications.tables.albedo import albedo_table

    return albedo_table("conductor", engine=None, mu=[1.0, 0.5], alpha=[0.3], epsilon=0.05, delta=0.1, average=False,
                        progress=False)


def _read(path: Any) -> Any:
    from virtspec_mi.applications.tables.table import read_albedo_table

    return read_albedo_table(path)


class TablesApplication(Application):
    """Certified albedo tables, engines' tables and their audit: ``vm.albedo_table``, ``virtspec albedo-table``."""

    name: ClassVar[str] = "tables"
    summary: ClassVar[str] = "certified directional-albedo tables of renderers, each engine's own tables, their audit"
    commands: ClassVar[tuple[Command, ...]] = (ALBEDO_TABLE,)
    results: ClassVar[tuple[type, ...]] = (AlbedoTable, TableComparison)
    example: ClassVar[dict[str, Any]] = {
        "argv": ("albedo-table", "--engine", "none", "--cosines", "1,0.5", "--alpha", "0.3", "--epsilon", "0.05",
                 "--delta", "0.1", "--no-average", "--quiet", "--out", "{tmp}/E.nc"),
        "api": _api, "counts": lambda table: np.concatenate([np.ravel(table.counts[k]) for k in sorted(table.counts)]),
        "outputs": ("E.nc",), "read": _read, "formats": (".nc",),
        "resume": {"argv": ("albedo-table", "--engine", "none", "--cosines", "0.2:1:0.2", "--alpha", "0.1:1:0.3",
                            "--epsilon", "0.01", "--no-average", "--quiet", "--out", "{tmp}/again.nc"),
                   "checkpoint": "again.nc.parts", "out": "again.nc"}}
