"""
An albedo table's exports: its ``.npy`` (with ``NAME_avg.npy`` and ``NAME.json``) and its C header
==================================================================================================

The files :meth:`AlbedoTable.write <virtspec_mi.applications.tables.table.AlbedoTable.write>`
writes for other programs (the kind's ``EXPORTS``) and the result file each accompanies (its
``COMPANIONS``): a ``.npy``'s ``NAME.json`` holds the whole table (description, certificate,
every count, sealed), so :func:`virtspec_mi.read_result` reads the table from it; a C header
holds the values alone and is refused with the reason.

References
----------
NumPy's ``.npy`` format (NEP 1); the C header in Cycles' layout: :mod:`virtspec_mi.exchange.header`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.base.files import atomic_write
from virtspec_mi.results.integrity import checksum

__all__: list[str] = []


def _save_npy(path: str, values: np.ndarray) -> None:
    with open(path, "wb") as handle:
        np.save(handle, values)


def _write_npy(table: Any, path: Path) -> Path:
    """Ê as float32 in the engine's memory order; E_avg in ``NAME_avg.npy``; the whole table in ``NAME.json``."""

    atomic_write(path, lambda tmp: _save_npy(tmp, table.layout().astype(np.float32)))
    if table.E_avg is not None:
        avg = path.with_name(path.stem + "_avg.npy")
        atomic_write(avg, lambda tmp: _save_npy(tmp, table.E_avg.astype(np.float32)))
    data = table.as_dict()
    sealed = {**data, "checksum": checksum(data)}
    atomic_write(path.with_suffix(".json"), lambda tmp: Path(tmp).write_text(json.dumps(sealed, indent=1)))
    return path


def _write_header(table: Any, path: Path) -> Path:
    from virtspec_mi.exchange.header import write_header

    atomic_write(path, lambda tmp: Path(tmp).write_text(write_header(table)))
    return path


def _sidecar(path: Path) -> Path:
    """The ``NAME.json`` of a table's ``NAME.npy`` (or of its ``NAME_avg.npy``)."""

    stem = path.stem[:-4] if path.stem.endswith("_avg") else path.stem
    return path.with_name(stem + ".json")


def _values_only(path: Path) -> Path:
    raise ValueError(f"result file {path}: a C header holds an albedo table's values, not its counts or certificate: "
                     "read the table's .nc or .json (AlbedoTable.compare holds a header to a table)")
