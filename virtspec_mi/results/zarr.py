"""
Zarr result tables, written region by region
============================================

A sweep written to ``out="table.zarr"`` (:func:`virtspec_mi.sweep`) creates a Zarr store
of the result's grid when it starts — the dims of its :class:`~virtspec_mi.results.hemispherical.Result`,
``wavelength`` × ``theta_i`` and, for a parameter sweep, one dim per parameter of a grid
or the dim ``point`` of explicit points (:mod:`virtspec_mi.engine.parameters`), with their
coordinates; one variable per count (``rays``, ``reflected`` …; the two-stage pilot's as
``pilot_<count>``) plus ``done`` (bool); chunks of up to :data:`CHUNK_READINGS` readings
(whole wavelengths first, one θi, then points of the last parameter dim); its metadata
only (xarray ``to_zarr(compute=False)`` of a Dask template) — and writes the counts of
each finished batch into it as the batch finishes, as rectangular regions
(``to_zarr(region=...)``, xarray's convention; one writer: the sweep's driver; writes
spaced out as the checkpoint's are). A batch's readings are runs of consecutive reading
indices k = (i_p·n_θ + i_θ)·n_λ + i_λ (:func:`virtspec_mi.engine.readings.take_keyed_readings`);
each run is at most a few hyper-rectangles of the store (a partial row of wavelengths,
whole rows of θi, whole parameter points, …: :func:`regions`). A partial table is
readable with ``xarray.open_zarr`` meanwhile (``done`` marks the finished readings).
When the sweep completes, :func:`write_result` writes the derived variables (estimates,
parts, Clopper–Pearson bounds, ``certified_mu``) and the attributes; :func:`read` /
:meth:`virtspec_mi.Result.read` give the one result type back (the attribute
``virtspec_table`` holds the dims, settings, geometry, parameters and provenance as
JSON; the counts are the variables). A store whose ``done`` is not all true is refused as
incomplete. Unlike the ``.nc``/``.csv``/``.json`` files, a store is a directory and is
not replaced atomically; the sweep's checkpoint (``OUT.partial.json``) stays the record
for resuming.

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

from virtspec_mi.kernel.counts import Counts
from virtspec_mi.results.formats import annotate, format_parts

__all__ = ["SUFFIX", "CHUNK_READINGS", "WRITE_EVERY", "ZarrTable", "regions", "write_result", "read", "is_table",
           "as_plain"]

SUFFIX: str = ".zarr"
"""The suffix of a Zarr result store."""

CHUNK_READINGS: int = 4096
"""Readings per Zarr chunk at most: wavelengths first, by one θi (filled up with points of the last parameter dim)."""

WRITE_EVERY: float = 10.0
"""Write kept batches again once the time since the last write is this many times what it took."""

_GRID = ("wavelength", "theta_i")
_META = "virtspec_table"
_IDENTITY = "virtspec_sweep"


def _dtype(name: str) -> Any:
    return np.float64 if name == "largest_weight" else np.int64


def regions(start: int, stop: int, shape: Sequence[int]) -> Iterator[tuple[tuple[int, ...], tuple[int, ...]]]:
    """
    The consecutive flat indices [``start``, ``stop``) of a C-order array of ``shape`` as
    hyper-rectangles ``(first index, size)``, in order: a partial innermost row, whole
    rows, whole blocks of the next dim … (at most 2·ndim − 1 of them).
    """

    if start >= stop:
        return
    if len(shape) == 1:
        yield (start,), (stop - start,)
        return
    inner = int(np.prod(shape[1:], dtype=np.int64))
    first, head = divmod(start, inner)
    last, tail = divmod(stop, inner)
    if first == last:
        for at, size in regions(head, tail, shape[1:]):
            yield (first, *at), (1, *size)
        return
    if head:
        for at, size in regions(head, inner, shape[1:]):
            yield (first, *at), (1, *size)
        first += 1
    if last > first:
        yield (first, *(0,) * (len(shape) - 1)), (last - first, *shape[1:])
    if tail:
        for at, size in regions(0, tail, shape[1:]):
            yield (last, *at), (1, *size)


class ZarrTable:
    """
    The store of a sweep at ``path`` over ``wavelengths`` × ``theta_i`` (× the points of
    ``parameters``, a :class:`~virtspec_mi.engine.parameters.ParameterSpace`): kept when it
    exists with the same ``identity`` (a sweep resumed), created anew otherwise.
    """

    def __init__(self, path: str | os.PathLike, wavelengths: Sequence[float], theta_i: Sequence[float],
                 identity: dict[str, Any], pilot: bool, parameters: Any = None) -> None:
        self.path = Path(path)
        self.pilot = pilot
        extra = () if parameters is None else tuple(parameters.dims)
        self.dims = (*_GRID, *extra)
        # reading k in C order over (*parameter dims, theta_i, wavelength): the store's axes reversed for the grid
        self.keyed_shape = (*(() if parameters is None else parameters.shape), len(theta_i), len(wavelengths))
        self._kept: list[tuple[np.ndarray, Counts, Counts | None]] = []
        self._written_at, self._write_seconds = time.perf_counter(), 0.0
        identity_text = json.dumps(identity, sort_keys=True)
        if self._identity() != identity_text:
            coords = {"wavelength": np.asarray(wavelengths, np.float64), "theta_i": np.asarray(theta_i, np.float64)}
            if parameters is not None:
                coords.update({name: ((name,) if name in extra else ("point",), values)
                               for name, values in parameters.coords().items()})
            self._create(coords, identity_text)

    @property
    def shape(self) -> tuple[int, ...]:
        """The store's shape, in :attr:`dims` order."""

        n = len(self.keyed_shape)
        return (self.keyed_shape[-1], self.keyed_shape[-2], *self.keyed_shape[:n - 2])

    def _identity(self) -> str | None:
        if not (self.path / "zarr.json").is_file() and not (self.path / ".zgroup").is_file():
            return None
        import zarr

        try:
            return zarr.open_group(str(self.path), mode="r").attrs.get(_IDENTITY)
        except Exception:  # not a readable store: made anew
            return None

    def _chunks(self) -> tuple[int, ...]:
        shape = self.shape
        lam = min(shape[0], CHUNK_READINGS)
        chunks = [lam, 1, *(1 for _ in shape[2:])]
        if len(shape) > 2:  # fill a chunk with points of the last parameter dim (consecutive in k when n_theta is 1)
            chunks[-1] = max(1, min(shape[-1], CHUNK_READINGS // (lam * shape[1])))
        return tuple(chunks)

    def _create(self, coords: dict[str, Any], identity: str) -> None:
        import dask.array as da
        import xarray as xr

        chunks = self._chunks()
        names = [*Counts.names(), *(f"pilot_{n}" for n in Counts.names() if self.pilot)]
        variables = {name: (self.dims, da.zeros(self.shape, dtype=_dtype(name.removeprefix("pilot_")),
                                                chunks=chunks)) for name in names}
        variables["done"] = (self.dims, da.zeros(self.shape, dtype=bool, chunks=chunks))
        template = xr.Dataset(variables, coords=coords, attrs={_IDENTITY: identity})
        template.to_zarr(self.path, mode="w", compute=False, consolidated=False)

    def write(self, batch: np.ndarray, counts: Counts, pilot: Counts | None) -> None:
        """
        Keep the counts of readings ``batch`` (reading indices k) and write what is
        kept — unless writing is slow next to the batches: it is then written once the time
        since the last write is :data:`WRITE_EVERY` times what that write took (the
        checkpoint's rule), so the store costs the driver at most about a tenth of the run.
        :meth:`flush` writes what is left.
        """

        self._kept.append((np.asarray(batch, dtype=np.int64), counts, pilot))
        if time.perf_counter() - self._written_at >= WRITE_EVERY * self._write_seconds:
            self.flush()

    def flush(self) -> None:
        """Write every kept batch: one region per hyper-rectangle of its runs of consecutive readings."""

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
        n = len(self.keyed_shape)
        to_store = (n - 1, n - 2, *range(n - 2))  # keyed axes (*points, theta, wavelength) -> store dims
        for rows, at, size in self._regions(batch):
            def block(values: np.ndarray) -> np.ndarray:
                return np.transpose(values[rows].reshape(size), to_store)

            variables = {f"{prefix}{name}": (self.dims, block(getattr(values, name)))
                         for prefix, values in sources for name in Counts.names()}
            variables["done"] = (self.dims, np.ones(tuple(size[a] for a in to_store), dtype=bool))
            region = {dim: slice(at[a], at[a] + size[a]) for dim, a in zip(self.dims, to_store)}
            xr.Dataset(variables).to_zarr(self.path, region=region, consolidated=False)
        self._written_at = time.perf_counter()
        self._write_seconds = self._written_at - start

    def _regions(self, batch: np.ndarray) -> Iterator[tuple[np.ndarray, tuple[int, ...], tuple[int, ...]]]:
        """(positions in ``batch`` in k order, first keyed index, keyed size) of each hyper-rectangle."""

        order = np.argsort(batch, kind="stable")
        keys = batch[order]
        breaks = np.flatnonzero(np.diff(keys) != 1) + 1
        for run in np.split(np.arange(len(keys)), breaks):
            first = int(keys[run[0]])
            taken = 0
            for at, size in regions(first, first + len(run), self.keyed_shape):
                count = int(np.prod(size))
                yield order[run[taken:taken + count]], at, size
                taken += count

    def stream(self, runner: Any) -> Any:
        """A batch runner (:data:`virtspec_mi.engine.readings.BatchRunner`) that writes each batch here as it finishes."""

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
    Write ``result`` to the store ``path``. A hemispherical result: every variable of
    ``result.to_dataset()`` in full (into the sweep's store when its dims and coordinates
    are the same, else a new one), the pilot counts, ``done`` and the ``virtspec_table``
    attribute; a result over wavelength only (a reading) is written with θi as a dim of
    one. Any other kind: its dataset as it is (``result_json`` rebuilds it).
    """

    import xarray as xr

    path = Path(path)
    if format_parts(result.FORMAT)[0] != "result":  # a goniophotometer or sphere reading: written whole
        result.to_dataset().to_zarr(path, mode="w", consolidated=False)
        return path
    own_dims = result.dims
    if set(result.dims) <= {"wavelength", "theta_i"}:
        result = result.as_grid()
    dataset = result.to_dataset()
    dims = result.dims
    attrs = {k: v for k, v in dataset.attrs.items() if k != "result_json"}
    plain = result.as_dict()
    attrs[_META] = json.dumps({**{k: plain[k] for k in ("format", "dims", "settings", "geometry", "seconds", "scene",
                                                       "wavelength_independent", "version") + (
                                     ("parameters",) if "parameters" in plain else ())},
                               **({} if own_dims == dims else {"result_dims": list(own_dims)})})
    if result.pilot is not None:
        for name in Counts.names():
            dataset[f"pilot_{name}"] = (dims, np.asarray(getattr(result.pilot, name)))
    dataset["done"] = (dims, np.ones(result.shape, dtype=bool))
    annotate(dataset, result._parameter_keys())
    same = False
    if path.is_dir():
        try:
            with xr.open_zarr(path, consolidated=False) as old:
                same = (tuple(old["done"].dims) == dims
                        and all(np.array_equal(old[c].values, dataset[c].values) for c in dataset.coords)
                        and set(old.data_vars) <= set(dataset.data_vars))
                attrs[_IDENTITY] = old.attrs.get(_IDENTITY, "")
        except Exception:
            same = False
    dataset.attrs = attrs
    dataset.to_zarr(path, mode="a" if same else "w", consolidated=False)
    if same:  # written into the sweep's store: xarray keeps the attributes its arrays were made with
        import zarr

        group = zarr.open_group(str(path), mode="r+")
        for name in dataset.variables:
            group[str(name)].attrs.update({k: v for k, v in dataset[name].attrs.items() if k in ("units", "long_name")})
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
    if "result_json" in dataset.attrs and _META not in dataset.attrs:  # a result written whole (not a sweep table)
        return dataset
    if _META not in dataset.attrs or "done" not in dataset:
        raise ValueError(f"not a complete virtspec-mi Zarr result: {path} (no {_META} attribute: the sweep writing "
                         "it has not completed; re-run it to finish)")
    done = dataset["done"].values
    if not done.all():
        raise ValueError(f"Zarr result {path} is incomplete: {int(done.sum())} of {done.size} readings done")
    return dataset


def is_table(dataset: Any) -> bool:
    """True for a sweep's table (:class:`ZarrTable`, :func:`write_result` of a hemispherical result)."""

    return _META in dataset.attrs


def as_plain(dataset: Any) -> dict[str, Any]:
    """
    A complete store's dataset as the plain data of :meth:`virtspec_mi.Result.from_dict`
    (a reading stored as a grid of one θi gets its own dims back: ``result_dims``).
    """

    meta = json.loads(dataset.attrs[_META])
    dims = tuple(meta.get("dims", _GRID))  # stores written before parameter sweeps: wavelength x theta_i
    own = tuple(meta.pop("result_dims", dims))
    index = tuple(slice(None) if d in own else 0 for d in dims)
    counts = {name: dataset[name].transpose(*dims).values[index] for name in Counts.names()}
    pilot = ({name: dataset[f"pilot_{name}"].transpose(*dims).values[index] for name in Counts.names()}
             if f"pilot_{Counts.names()[0]}" in dataset else None)
    labels = {name: dataset[name].values if name in own else dataset[name].values[0] for name in _GRID}
    plain = {**meta, "dims": list(own), "wavelengths": labels["wavelength"], "theta_i": labels["theta_i"], **counts,
             "pilot": pilot}
    if meta.get("parameters") is not None:
        plain["parameter_coords"] = {name: dataset[name].values for name in (*meta["parameters"]["names"], "point")
                                     if name in dataset.coords}
    return plain
