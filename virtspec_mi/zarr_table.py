"""
Zarr result tables, written region by region
============================================

A sweep written to ``out="table.zarr"`` (:func:`virtspec_mi.sweep`) creates a Zarr store
of the result's grid when it starts — coordinates ``wavelength`` × ``theta_i`` and one
variable per count (``rays``, ``reflected`` …; the two-stage pilot's as ``pilot_<count>``)
plus ``done`` (bool), chunked :data:`CHUNK_WAVELENGTHS` wavelengths × one θi, its
metadata only (xarray ``to_zarr(compute=False)`` of a Dask template) — and writes the
counts of each finished batch into it as the batch finishes, as rectangular regions
(``to_zarr(region=...)``, xarray's convention; one writer: the sweep's driver). A
partial table is readable with ``xarray.open_zarr`` meanwhile (``done`` marks the
finished readings). When the sweep completes, :func:`write_result` writes the derived
variables (estimates, parts, Clopper–Pearson bounds, ``certified_mu``) and the
attributes; :func:`read` / :meth:`virtspec_mi.Result.read` give the one result type
back (the attribute ``virtspec_table`` holds the settings, geometry and provenance as
JSON; the counts are the variables). A store whose ``done`` is not all true is refused
as incomplete. Unlike the ``.nc``/``.csv``/``.json`` files, a store is a directory and
is not replaced atomically; the sweep's checkpoint (``OUT.partial.json``) stays the
record for resuming.

References
----------
xarray documentation, "Appending to existing Zarr stores" (regions, ``compute=False``).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Iterator, Sequence

import numpy as np

from virtspec_mi.counts import Counts

__all__ = ["SUFFIX", "CHUNK_WAVELENGTHS", "ZarrTable", "write_result", "read"]

SUFFIX: str = ".zarr"
"""The suffix of a Zarr result store."""

CHUNK_WAVELENGTHS: int = 4096
"""Wavelengths per Zarr chunk (by one θi)."""

_DIMS = ("wavelength", "theta_i")
_META = "virtspec_table"
_IDENTITY = "virtspec_sweep"


def _dtype(name: str) -> Any:
    return np.float64 if name == "largest_weight" else np.int64


class ZarrTable:
    """
    The store of a sweep at ``path`` over ``wavelengths`` × ``theta_i``: kept when it
    exists with the same ``identity`` (a sweep resumed), created anew otherwise.
    """

    def __init__(self, path: str | os.PathLike, wavelengths: Sequence[float], theta_i: Sequence[float],
                 identity: dict[str, Any], pilot: bool) -> None:
        self.path = Path(path)
        self.n_lam = len(wavelengths)
        self.pilot = pilot
        identity_text = json.dumps(identity, sort_keys=True)
        if self._identity() != identity_text:
            self._create(np.asarray(wavelengths, np.float64), np.asarray(theta_i, np.float64), identity_text)

    def _identity(self) -> str | None:
        if not (self.path / "zarr.json").is_file() and not (self.path / ".zgroup").is_file():
            return None
        import zarr

        try:
            return zarr.open_group(str(self.path), mode="r").attrs.get(_IDENTITY)
        except Exception:  # not a readable store: made anew
            return None

    def _create(self, wavelengths: np.ndarray, theta_i: np.ndarray, identity: str) -> None:
        import dask.array as da
        import xarray as xr

        shape = (len(wavelengths), len(theta_i))
        chunks = (min(shape[0], CHUNK_WAVELENGTHS), 1)
        names = [*Counts.names(), *(f"pilot_{n}" for n in Counts.names() if self.pilot)]
        variables = {name: (_DIMS, da.zeros(shape, dtype=_dtype(name.removeprefix("pilot_")), chunks=chunks))
                     for name in names}
        variables["done"] = (_DIMS, da.zeros(shape, dtype=bool, chunks=chunks))
        template = xr.Dataset(variables, coords={"wavelength": wavelengths, "theta_i": theta_i},
                              attrs={_IDENTITY: identity})
        template.to_zarr(self.path, mode="w", compute=False, consolidated=False)

    def write(self, batch: np.ndarray, counts: Counts, pilot: Counts | None) -> None:
        """Write the counts of readings ``batch`` (indices k = i_θ·n_λ + i_λ) as rectangular regions."""

        import xarray as xr

        batch = np.asarray(batch, dtype=np.int64)
        order = np.lexsort((batch % self.n_lam, batch // self.n_lam))
        keys = batch[order]
        breaks = np.flatnonzero((np.diff(keys) != 1) | (np.diff(keys // self.n_lam) != 0)) + 1
        sources = [("", counts)] + ([("pilot_", pilot)] if self.pilot and pilot is not None else [])
        for run in np.split(np.arange(len(keys)), breaks):
            rows = order[run]
            first = int(keys[run[0]])
            lam, theta = first % self.n_lam, first // self.n_lam
            variables = {f"{prefix}{name}": (_DIMS, getattr(values, name)[rows].reshape(-1, 1))
                         for prefix, values in sources for name in Counts.names()}
            variables["done"] = (_DIMS, np.ones((len(rows), 1), dtype=bool))
            xr.Dataset(variables).to_zarr(self.path, region={"wavelength": slice(lam, lam + len(rows)),
                                                             "theta_i": slice(theta, theta + 1)},
                                          consolidated=False)

    def stream(self, runner: Any) -> Any:
        """A batch runner (:data:`virtspec_mi.engine.BatchRunner`) that writes each batch here as it finishes."""

        def streaming(batches: list[np.ndarray]) -> Iterator[Any]:
            finished = iter(runner(batches))
            try:
                for batch, counts, pilot, seconds in finished:
                    self.write(batch, counts, pilot)
                    yield batch, counts, pilot, seconds
            finally:
                close = getattr(finished, "close", None)
                if close is not None:
                    close()

        return streaming


def write_result(result: Any, path: str | os.PathLike) -> Path:
    """
    Write ``result`` (dims ``wavelength`` and ``theta_i``) to the store ``path``: every
    variable of ``result.to_dataset()`` in full (into the sweep's store when its grid is
    the same, else a new one), the pilot counts, ``done`` and the ``virtspec_table`` attribute.
    """

    import xarray as xr

    path = Path(path)
    result = result.as_grid()
    dataset = result.to_dataset()
    attrs = {k: v for k, v in dataset.attrs.items() if k != "result_json"}
    plain = result.as_dict()
    attrs[_META] = json.dumps({k: plain[k] for k in ("format", "settings", "geometry", "seconds", "scene",
                                                     "wavelength_independent", "version")})
    if result.pilot is not None:
        for name in Counts.names():
            dataset[f"pilot_{name}"] = (_DIMS, np.asarray(getattr(result.pilot, name)))
    dataset["done"] = (_DIMS, np.ones(result.shape, dtype=bool))
    same = False
    if path.is_dir():
        try:
            with xr.open_zarr(path, consolidated=False) as old:
                same = (all(np.array_equal(old[d].values, dataset[d].values) for d in _DIMS)
                        and set(old.data_vars) <= set(dataset.data_vars))
                attrs[_IDENTITY] = old.attrs.get(_IDENTITY, "")
        except Exception:
            same = False
    dataset.attrs = attrs
    dataset.to_zarr(path, mode="a" if same else "w", consolidated=False)
    return path


def read(path: str | os.PathLike) -> Any:
    """The dataset of a complete store written by :func:`write_result` (``ValueError`` otherwise)."""

    import xarray as xr

    path = Path(path)
    try:
        with xr.open_zarr(path, consolidated=False) as store:
            dataset = store.load()
    except Exception as error:  # zarr and xarray raise many types for a store that is not one
        raise ValueError(f"could not read Zarr result {path}: {error}") from None
    if _META not in dataset.attrs or "done" not in dataset:
        raise ValueError(f"not a complete virtspec-mi Zarr result: {path} (no {_META} attribute: the sweep writing "
                         "it has not completed; re-run it to finish)")
    done = dataset["done"].values
    if not done.all():
        raise ValueError(f"Zarr result {path} is incomplete: {int(done.sum())} of {done.size} readings done")
    return dataset


def as_plain(dataset: Any) -> dict[str, Any]:
    """A complete store's dataset as the plain data of :meth:`virtspec_mi.Result.from_dict`."""

    meta = json.loads(dataset.attrs[_META])
    counts = {name: dataset[name].transpose(*_DIMS).values for name in Counts.names()}
    pilot = ({name: dataset[f"pilot_{name}"].transpose(*_DIMS).values for name in Counts.names()}
             if f"pilot_{Counts.names()[0]}" in dataset else None)
    return {**meta, "dims": list(_DIMS), "wavelengths": dataset["wavelength"].values,
            "theta_i": dataset["theta_i"].values, **counts, "pilot": pilot}
