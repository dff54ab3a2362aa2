"""
Zarr result tables, written region by region
============================================

A sweep written to ``out="table.zarr"`` (:func:`virtspec_mi.sweep`) creates a Zarr store
of the result's grid when it starts — the dims of its :class:`~virtspec_mi.results.readings.Result`,
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
incomplete. A store is a directory: it is written into a new directory beside its name
and swapped in (:func:`replace_store`), and only over a new path, an empty directory or a
store this project wrote that holds nothing else (:func:`check_store`: a directory holding
a file of anyone else's is refused before any tracing, and nothing in it is removed).
While a sweep runs, the store is filled in place; if it cannot be written (a full disk)
the sweep goes on without it, with a warning, and writes it whole when it completes; the
sweep's checkpoint (``OUT.partial.json``) stays the record for resuming. A complete
table carries the checksum of its counts (:mod:`virtspec_mi.results.integrity`).

References
----------
xarray documentation, "Appending to existing Zarr stores" (regions, ``compute=False``).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import time
import warnings
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import numpy as np

from virtspec_mi.base.files import WriteError, cause_of, flush_directory, temporary_name
from virtspec_mi.kernel.counts import Counts
from virtspec_mi.results.formats import TABLE_ATTRIBUTE, annotate, format_parts
from virtspec_mi.results.integrity import CHECKSUM, checksum

__all__ = ["SUFFIX", "CHUNK_READINGS", "WRITE_EVERY", "ZarrTable", "regions", "write_result", "read", "is_table",
           "as_plain", "check_store", "replace_store", "unfinished"]

SUFFIX: str = ".zarr"
"""The suffix of a Zarr result store."""

CHUNK_READINGS: int = 4096
"""Readings per Zarr chunk at most: wavelengths first, by one θi (filled up with points of the last parameter dim)."""

WRITE_EVERY: float = 10.0
"""Write kept batches again once the time since the last write is this many times what it took."""

_GRID = ("wavelength", "theta_i")
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
        self.failure: WriteError | None = None
        """Why the store could not be written (it is then written no more), or ``None``."""
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
        replace_store(self.path, lambda target: template.to_zarr(target, mode="w", compute=False,
                                                                 consolidated=False))

    def write(self, batch: np.ndarray, counts: Counts, pilot: Counts | None) -> None:
        """
        Keep the counts of readings ``batch`` (reading indices k) and write what is
        kept — unless writing is slow next to the batches: it is then written once the time
        since the last write is :data:`WRITE_EVERY` times what that write took (the
        checkpoint's rule), so the store costs the driver at most about a tenth of the run.
        :meth:`flush` writes what is left.
        """

        if self.failure is not None:  # the store cannot be written: the run goes on without it
            return
        self._kept.append((np.asarray(batch, dtype=np.int64), counts, pilot))
        if time.perf_counter() - self._written_at >= WRITE_EVERY * self._write_seconds:
            self.flush()

    def flush(self) -> None:
        """
        Write every kept batch: one region per hyper-rectangle of its runs of consecutive
        readings. A failure (a full disk …) does not stop the sweep: it is warned about once
        (``RuntimeWarning`` naming the store and the cause), kept in :attr:`failure`, and
        the store is written no more; the readings stay in the sweep's result and checkpoint.
        """

        if not self._kept or self.failure is not None:
            return
        try:
            self._write_kept()
        except (OSError, RuntimeError, ValueError) as error:
            cause, code = cause_of(error, self.path)
            self.failure = WriteError(self.path, cause, code=code)
            self._kept = []
            warnings.warn(f"{self.failure}: the sweep goes on without its Zarr table; its readings are kept in "
                          "memory and in its checkpoint, and written when it completes", RuntimeWarning, stacklevel=2)

    def _write_kept(self) -> None:
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
                for batch, tally in finished:  # a batch's tally (virtspec_mi.engine.tally.Tally)
                    self.write(batch, tally.counts, tally.pilot)
                    yield batch, tally
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
    Write ``result`` to the store ``path`` (:func:`replace_store`: into a new store beside
    it, then swapped in; a store of this project's there is replaced, anything else is
    refused). A hemispherical result: every variable of ``result.to_dataset()`` (the
    pilot counts among them), ``done`` and the :data:`~virtspec_mi.results.formats.TABLE_ATTRIBUTE`
    (with the counts' checksum); a result without the dim ``wavelength`` or ``theta_i`` (a
    reading, a selection) is written with it as a dim of one. Any other kind: its dataset as it is (``result_json`` rebuilds it).
    """

    path = Path(path)
    whole = format_parts(result.FORMAT)[0] != "result"  # a goniophotometer or sphere reading: written whole
    dataset = result.to_dataset() if whole else _table(result, _root_attributes(path).get(_IDENTITY, ""))
    replace_store(path, lambda target: dataset.to_zarr(target, mode="w", consolidated=False))
    return path


def _table(result: Any, identity: str) -> Any:
    """The dataset of a hemispherical result's table (see :func:`write_result`)."""

    own_dims = result.dims
    for name in _GRID:  # a reading (or a parameter point's) is stored over the grid, its own dims kept in the table
        if name not in result.dims:
            result = result._expanded(name)
    dataset = result.to_dataset()
    dims = result.dims
    plain = result.as_dict()
    kept = ("format", "dims", "settings", "geometry", "seconds", "scene", "wavelength_independent", "version",
            "parameters", "source")  # the last two only when the result has them
    meta = {**{k: plain[k] for k in kept if k in plain},
            **({} if own_dims == dims else {"result_dims": list(own_dims)})}
    dataset["done"] = (dims, np.ones(result.shape, dtype=bool))
    annotate(dataset, result._parameter_keys(), result.described())
    attrs = {k: v for k, v in dataset.attrs.items() if k != "result_json"}
    dataset.attrs = {**attrs, TABLE_ATTRIBUTE: json.dumps(meta), **({_IDENTITY: identity} if identity else {})}
    dataset.attrs[TABLE_ATTRIBUTE] = json.dumps({**meta, CHECKSUM: checksum(as_plain(dataset))})
    return dataset


def read(path: str | os.PathLike) -> Any:
    """The dataset of a complete store written by :func:`write_result` (``ValueError`` otherwise)."""

    import xarray as xr

    path = Path(path)
    try:
        with xr.open_zarr(path, consolidated=False, chunks=None) as store:  # no Dask graph: read at once
            dataset = store.load()
    except Exception as error:  # zarr and xarray raise many types for a store that is not one
        raise ValueError(f"could not be read as a Zarr store ({type(error).__name__}: "
                         f"{' '.join(str(error).split())})") from None
    if "result_json" in dataset.attrs and TABLE_ATTRIBUTE not in dataset.attrs:  # a result written whole
        return dataset
    if TABLE_ATTRIBUTE not in dataset.attrs or "done" not in dataset:
        raise ValueError(f"is not a complete virtspec-mi Zarr result (no {TABLE_ATTRIBUTE} attribute: the sweep "
                         "writing it has not completed; re-run it to finish)")
    done = dataset["done"].values
    if done.dtype.kind != "b" or not done.all():
        raise ValueError(f"is incomplete: {int(np.sum(done == 1))} of {done.size} readings done")
    return dataset


def unfinished(path: str | os.PathLike) -> bool:
    """
    Whether ``path`` is a store a sweep of this project began and did not finish before
    any reading was done (interrupted then, it keeps no checkpoint): it holds attributes,
    but neither a table's nor a whole result's. Such a store is measured again, never refused.
    """

    path = Path(path)
    if not path.is_dir():
        return False
    attributes = _root_attributes(path)
    return bool(attributes) and TABLE_ATTRIBUTE not in attributes and "result_json" not in attributes


def is_table(dataset: Any) -> bool:
    """True for a sweep's table (:class:`ZarrTable`, :func:`write_result` of a hemispherical result)."""

    return TABLE_ATTRIBUTE in dataset.attrs


def as_plain(dataset: Any) -> dict[str, Any]:
    """
    A complete store's dataset as the plain data of :meth:`virtspec_mi.Result.from_dict`
    (a reading stored as a grid of one θi gets its own dims back: ``result_dims``);
    ``ValueError`` naming what is missing or misshapen.
    """

    try:
        meta = json.loads(dataset.attrs[TABLE_ATTRIBUTE])
    except (TypeError, ValueError, RecursionError) as error:
        raise ValueError(f"its {TABLE_ATTRIBUTE} attribute is not JSON ({error})") from None
    if not isinstance(meta, dict):
        raise ValueError(f"its {TABLE_ATTRIBUTE} attribute is not a JSON object")
    dims = meta.get("dims", list(_GRID))  # stores written before parameter sweeps: wavelength x theta_i
    own = meta.pop("result_dims", dims)
    if (not isinstance(dims, list) or not all(isinstance(d, str) for d in dims) or not isinstance(own, list)
            or not set(own) <= set(dims) or not set(_GRID) <= set(dims)):
        raise ValueError(f"its {TABLE_ATTRIBUTE} attribute has bad dims ({dims!r}; the reading's: {own!r})")
    dims, own = tuple(dims), tuple(own)

    def variable(name: str) -> np.ndarray:
        if name not in dataset.variables:
            raise ValueError(f"lacks the variable {name!r}")
        values = dataset[name]
        if set(values.dims) != set(dims):
            raise ValueError(f"variable {name!r} has the dims {tuple(values.dims)}, not {dims}")
        return values.transpose(*dims).values[index]

    index = tuple(slice(None) if d in own else 0 for d in dims)
    for name in _GRID:
        if name not in dataset.coords or dataset[name].dims != (name,):
            raise ValueError(f"lacks the coordinate {name!r}")
    counts = {name: variable(name) for name in Counts.names()}
    pilot = ({name: variable(f"pilot_{name}") for name in Counts.names()}
             if f"pilot_{Counts.names()[0]}" in dataset else None)
    labels = {name: dataset[name].values if name in own else dataset[name].values[0] for name in _GRID}
    plain = {**meta, "dims": list(own), "wavelengths": labels["wavelength"], "theta_i": labels["theta_i"], **counts,
             "pilot": pilot}
    parameters = meta.get("parameters")
    if parameters is not None:
        names = parameters.get("names") if isinstance(parameters, dict) else None
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise ValueError(f"its {TABLE_ATTRIBUTE} attribute has bad parameters ({parameters!r})")
        plain["parameter_coords"] = {name: dataset[name].values for name in (*names, "point") if name in dataset.coords}
    return plain


# -- stores of this project only --------------------------------------------------------

_MARKERS = ("result_json", TABLE_ATTRIBUTE, _IDENTITY)  # a group attribute only this project's stores carry
_METADATA = frozenset({"zarr.json", ".zgroup", ".zattrs", ".zarray", ".zmetadata"})
_CHUNK = re.compile(r"^\d+(\.\d+)*$")


def check_store(path: str | os.PathLike, name: str = "out") -> Path:
    """
    ``path`` as a ``Path`` when a store may be written there: nothing there, an empty
    directory, or a store this project wrote holding nothing else; else ``ValueError``
    naming ``name``, the path and the first entry that is not this project's (it is
    never removed: :func:`replace_store`).
    """

    path = Path(path)
    if path.is_symlink() or (path.exists() and not path.is_dir()):
        raise ValueError(f"{name} {path} is a file; a Zarr store is a directory")
    stranger = _stranger(path) if path.exists() else None
    if stranger is not None:
        raise ValueError(f"{name} {path} is a directory holding {stranger!r}, which virtspec-mi did not write: a Zarr "
                         "result is written only to a new path, an empty directory or a store of its own (which it "
                         "replaces); give another path")
    return path


def _stranger(path: Path) -> str | None:
    """The first entry under ``path`` that is not part of a store this project wrote, or ``None``."""

    entries = sorted(path.iterdir())
    if not entries:
        return None
    if not any(marker in _root_attributes(path) for marker in _MARKERS):
        return entries[0].name
    for entry in sorted(path.rglob("*")):
        parts = entry.relative_to(path).parts
        if entry.is_symlink() or not _store_entry(path, parts, entry.is_dir()):
            return "/".join(parts)
    return None


def _store_entry(root: Path, parts: tuple[str, ...], is_dir: bool) -> bool:
    """Whether ``root/parts`` is a Zarr store's own: metadata, an array's directory, chunks (v2 and v3 layouts)."""

    if len(parts) == 1:
        if is_dir:
            return any((root / parts[0] / meta).is_file() for meta in ("zarr.json", ".zarray"))
        return parts[0] in _METADATA
    if len(parts) == 2 and not is_dir and (parts[1] in _METADATA or _CHUNK.match(parts[1])):
        return True
    return parts[1] == "c" and all(_CHUNK.match(p) and "." not in p for p in parts[2:])


def _root_attributes(path: Path) -> dict[str, Any]:
    """The group attributes of the store at ``path`` (v3 ``zarr.json``, v2 ``.zattrs``), ``{}`` if none."""

    for name, key in (("zarr.json", "attributes"), (".zattrs", None)):
        try:
            data = json.loads((path / name).read_text(encoding="utf-8"))
        except (OSError, ValueError, RecursionError):
            continue
        data = data.get(key, {}) if key and isinstance(data, dict) else data
        return data if isinstance(data, dict) else {}
    return {}


def replace_store(path: str | os.PathLike, write: Callable[[Path], Any]) -> None:
    """
    ``write(directory)`` a store into a new directory beside ``path`` (made here, under a
    fresh name), then put it in place of whatever :func:`check_store` allows there: the old
    store (this project's) is moved aside and removed, and nothing else ever is. A failed
    write removes the new directory (its own) and raises :class:`~virtspec_mi.base.files.WriteError`
    naming ``path`` and the cause; ``path`` keeps its old store.
    """

    path = check_store(path)
    temporary = temporary_name(path, ".zarr")
    try:
        temporary.mkdir()
    except OSError as error:
        cause, code = cause_of(error, path)
        raise WriteError(path, cause, code=code) from None
    try:
        write(temporary)
        old = None
        if path.exists():
            check_store(path)  # again, just before the swap
            old = temporary_name(path, ".old.zarr")
            os.rename(path, old)
        try:
            os.rename(temporary, path)
        except BaseException:
            if old is not None:
                os.rename(old, path)
            raise
    except BaseException as error:
        shutil.rmtree(temporary, ignore_errors=True)  # ours: made above under a fresh name
        if isinstance(error, (OSError, RuntimeError)):
            cause, code = cause_of(error, path)
            raise WriteError(path, cause, code=code) from error
        raise
    flush_directory(path.parent)
    if old is not None:
        if _stranger(old) is None:
            shutil.rmtree(old, ignore_errors=True)
        else:  # something appeared in the old store meanwhile: it is left, with a word
            warnings.warn(f"the former store {path} was moved to {old}, not removed: it holds "
                          f"{_stranger(old)!r}, which virtspec-mi did not write", RuntimeWarning, stacklevel=2)
