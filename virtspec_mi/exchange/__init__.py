"""
Exchange formats renderers and simulation tools read: certified tables and BSDF files
=====================================================================================

- :mod:`~virtspec_mi.exchange.albedo` measures certified directional-albedo tables E(μ, α)
  (:mod:`~virtspec_mi.exchange.tables`: the table, its files and its comparison),
  E_avg(α) (and E(μ, α, η) of rough glass) for energy compensation, on the grids of
  Cycles, Filament and Unreal (:mod:`~virtspec_mi.exchange.conventions`); NetCDF,
  ``.npy`` and C headers (:mod:`~virtspec_mi.exchange.header`); a comparison with a
  published table. Each engine's own model (:mod:`~virtspec_mi.exchange.engine_models`),
  its channels certified together and written as the engine's drop-in file
  (:mod:`~virtspec_mi.exchange.engine_tables`), and the audit of an engine's published
  table (:mod:`~virtspec_mi.exchange.audit`).
- :mod:`~virtspec_mi.exchange.klems`: certified Klems BSDF matrices (WINDOW 6 XML, read
  by Radiance), measured by :mod:`~virtspec_mi.exchange.klems_gonio` with the
  goniophotometer, on the bases of
  :mod:`~virtspec_mi.exchange.klems_basis`, the back side through
  :mod:`~virtspec_mi.exchange.flip`.
- :mod:`~virtspec_mi.exchange.microfacet_reference`: the independent quadrature the
  tables are tested against.

The rays of many cells at once are sized by the budgets (:mod:`virtspec_mi.budgets.binomial`),
files written by :mod:`virtspec_mi.files`. Names are imported on first use (this package imports nothing heavy).
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["albedo_table", "AlbedoTable", "TableComparison", "read_albedo_table", "klems_measure",
           "klems_from_gonio", "KlemsMeasurement", "read_klems", "read_klems_sidecar", "check_klems", "klems_basis",
           "KlemsBasis", "convention", "ENGINES", "engine_tables", "EngineTables", "audit", "Audit"]

_LAZY = {
    "albedo_table": "virtspec_mi.exchange.albedo",
    "AlbedoTable": "virtspec_mi.exchange.tables",
    "TableComparison": "virtspec_mi.exchange.tables",
    "read_albedo_table": "virtspec_mi.exchange.tables",
    "klems_measure": "virtspec_mi.exchange.klems_gonio",
    "klems_from_gonio": "virtspec_mi.exchange.klems",
    "KlemsMeasurement": "virtspec_mi.exchange.klems",
    "read_klems": "virtspec_mi.exchange.klems",
    "read_klems_sidecar": "virtspec_mi.exchange.klems",
    "check_klems": "virtspec_mi.exchange.klems",
    "klems_basis": "virtspec_mi.exchange.klems_basis",
    "KlemsBasis": "virtspec_mi.exchange.klems_basis",
    "convention": "virtspec_mi.exchange.conventions",
    "ENGINES": "virtspec_mi.exchange.conventions",
    "engine_tables": "virtspec_mi.exchange.engine_tables",
    "EngineTables": "virtspec_mi.exchange.engine_tables",
    "audit": "virtspec_mi.exchange.audit",
    "Audit": "virtspec_mi.exchange.audit",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'virtspec_mi.exchange' has no attribute {name!r}")
