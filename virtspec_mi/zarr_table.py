"""
Zarr result tables, written region by region
============================================

A sweep written to ``out="table.zarr"`` (:func:`virtspec_mi.sweep`) creates a Zarr store
of the result's grid when it starts — coordinates ``wavelength`` × ``theta_i`` and one
variable per count (``rays``, ``reflected`` …; the two-stage pilot's as ``pilot_<count>``)
plus ``done`` (bool), chunked :data:`CHUNK_WAVELENGTHS` wavelengths × one θi, its
metadata only (xarray ``to_zarr(compute=False)`` of a Dask template) — and writes the
counts of each finished batch into it as the batch finishes, as rectangular regions
(``to_zarr(region=...)``, xarray's convention; one writer: the sweep's driver; writes
spaced out as the checkpoint's are, whole θi rows merged into one region). A
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
import time
from pathlib import Path
from typing import Any, Iterator, Sequence

import numpy as np

from virtspec_mi.counts import Counts

__all__ = ["SUFFIX", "CHUNK_WAVELENGTHS", "WRITE_EVERY", "ZarrTable", "write_result", "read", "as_plain"]

SUFFIX: str = ".zarr"
"""The suffix of a Zarr result store."""

CHUNK_WAVELENGTHS: int = 4096
"""Wavelengths per Zarr chunk (by one θi)."""

WRITE_EVERY: float = 10.0
"""Write kept batches again once the time since the last write is this many times what it took."""

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
        self._kept: list[tuple[np.ndarray, Counts, Counts | None]] = []
        self._written_at, self._write_seconds = time.perf_counter(), 0.0
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
        """
        Keep the counts of readings ``batch`` (indices k = i_θ·n_λ + i_λ) and write what is
        kept — unless writing is slow next to the batches: it is then written once the time
        since the last write is :data:`WRITE_EVERY` times what that write took (the
        checkpoint's rule), so the store costs the driver at most about a tenth of the run.
        :meth:`flush` writes what is left.
        """

        self._kept.append((np.asarray(batch, dtype=np.int64), counts, pilot))
        if time.perf_counter() - self._written_at >= WRITE_EVERY * self._write_seconds:
            self.flush()

    def flush(self) -> None:
        """Write every kept batch: one region per run of consecutive readings (whole θi rows merged)."""

        if not self._kept:
            return
        import xarray as xr

        start = time.perf_counter()
        batch = np.concatenate([b for b, _, _ in self._kept])
        counts = _joined([c for _, c, _ in self._kept])
        pilot = (_joined([p for _, _, p in self._kept])
                 if self.pilot and all(p is not None for _, _, p in self._kept) else None)
        self._kept = []
        sources = [("", counts)] + ([("pilot_", pilot)] if pilot is not None else [])
        for rows, lam, theta, n_theta in self._regions(batch):
            variables = {f"{prefix}{name}": (_DIMS, getattr(values, name)[rows].reshape(n_theta, -1).T)
                         for prefix, values in sources for name in Counts.names()}
            variables["done"] = (_DIMS, np.ones((len(rows) // n_theta, n_theta), dtype=bool))
            xr.Dataset(variables).to_zarr(
                self.path, region={"wavelength": slice(lam, lam + len(rows) // n_theta),
                                   "theta_i": slice(theta, theta + n_theta)}, consolidated=False)
        self._written_at = time.perf_counter()
        self._write_seconds = self._written_at - start

    def _regions(self, batch: np.ndarray) -> Iterator[tuple[np.ndarray, int, int, int]]:
        """(positions in ``batch`` in k order, first i_λ, first i_θ, rows of θi) of each rectangle."""

        order = np.argsort(batch, kind="stable")
        keys = batch[order]
        breaks = np.flatnonzero((np.diff(keys) != 1) | (np.diff(keys // self.n_lam) != 0)) + 1
        runs = np.split(np.arange(len(keys)), breaks)
        i = 0
        while i < len(runs):
            first = int(keys[runs[i][0]])
            lam, theta = first % self.n_lam, first // self.n_lam
            j = i + 1
            if lam == 0 and len(runs[i]) == self.n_lam:  # whole rows in a row: one region
                while (j < len(runs) and len(runs[j]) == self.n_lam
                       and int(keys[runs[j][0]]) == (theta + j - i) * self.n_lam):
                    j += 1
            yield order[np.concatenate(runs[i:j])], lam, theta, j - i
            i = j

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
                self.flush()

        return streaming


def _joined(parts: list[Counts]) -> Counts:
    """The counts of several batches, one after the other."""

    return Counts(**{name: np.concatenate([getattr(part, name) for part in parts]) for name in Counts.names()})


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
