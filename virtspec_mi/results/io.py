"""
Result files: NetCDF, CSV and JSON, and colour-science CSV spectra
==================================================================

The file formats of every result kind (:class:`~virtspec_mi.results.base.ResultBase`: a
:class:`~virtspec_mi.results.readings.Result`, a goniophotometer or a sphere
reading; each builds its dataset and its plain data, and carries its format tag; this
module only writes and reads them, by suffix):

- ``.nc`` — NetCDF-4 of ``result.to_dataset()``: an ``xarray.Dataset`` over the
  result's dims (``wavelength`` in nm, ``theta_i`` in degrees, a parameter sweep's
  parameters or ``point``, the kind's own dims, …) with the estimates, every count and
  the certificates as variables (each with ``units`` and ``long_name``) and the
  settings, geometry, provenance, ``format`` and ``result_json`` as attributes;
- ``.csv`` — one row per cell of ``result.csv_dataset()`` (a reading; a goniophotometer
  bin; a sphere configuration) with its variables as columns, after one
  ``# virtspec-mi result {…}`` line holding the attributes as JSON (``pandas.read_csv(path,
  comment="#")`` skips it); with ``plain=True`` the columns and rows alone, for a
  spreadsheet (such a file is not read back as a result: it has no settings);
- ``.json`` — ``result.as_dict()``: one object (what ``virtspec measure --json``
  prints), arrays as nested lists over the dims;
- ``.zarr`` — a Zarr store (a directory) of the same dataset, which a hemispherical
  sweep fills region by region as its batches finish (:mod:`virtspec_mi.results.zarr`).

Each round-trips exactly (the counts are the data; everything else is derived):
:func:`virtspec_mi.results.kinds.read_result` reads any kind back by its format tag.
:func:`write_spectra_csv` / :func:`read_spectra_csv` write and read R, T and A at one θi
in colour-science's CSV spectral format.

Every file (not a Zarr store) is written atomically (:func:`virtspec_mi.base.files.atomic_file`):
into a temporary file beside it (``.NAME.*.tmp``, created here), flushed to disk, then
renamed onto the name. A failed or interrupted write (a full disk, a directory of that
name, Ctrl-C) leaves the old file — or none — and no temporary; readers and concurrent
writers never see a partial file. A failed write raises
:class:`~virtspec_mi.base.files.WriteError` naming the path and the cause, with the result
attached (``error.result``); :func:`rescue` writes it elsewhere (the command line does).
A Zarr store is written beside and swapped in, never over a directory holding anything
this project did not write (:func:`virtspec_mi.results.zarr.replace_store`).
:func:`check_output` refuses, before any work, a path that cannot become a result.
:func:`read` hands what it read to :func:`virtspec_mi.results.integrity.read_file`, which
checks every rule of a result file.

References
----------
colour-science ``colour.io`` CSV spectral files; xarray / NetCDF conventions.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.base.files import IN_MEMORY, WriteError, atomic_file
from virtspec_mi.base.surface import spoken
from virtspec_mi.results.integrity import unsealed

__all__ = [
    "SUFFIXES",
    "result_format",
    "check_output",
    "check_plain_csv",
    "csv_text",
    "write",
    "warm_writer",
    "read",
    "write_spectra_csv",
    "read_spectra_csv",
    "is_result_csv",
    "rescue",
]

SUFFIXES: tuple[str, ...] = (".nc", ".csv", ".json", ".zarr")
"""Result file formats understood by :func:`write` and :func:`read`."""

_CSV_HEADER = "# virtspec-mi result "


def warm_writer() -> None:
    """
    Import now what the first NetCDF write imports (xarray, pandas, netCDF4, dask's scheduler
    lookup and distributed: a second or more), so that a run writing parts between its safe
    points (an albedo table's checkpoint) answers an interrupt within a second.
    """

    import numpy as np
    import xarray as xr

    import netCDF4  # noqa: F401

    xr.Dataset({"v": ("x", np.zeros(1))}, coords={"x": [0.0]})
    try:
        from xarray.backends.locks import get_dask_scheduler

        get_dask_scheduler()
    except Exception:  # no dask: nothing more to import
        pass


def write(result: Any, path: str | os.PathLike, *, plain: bool = False) -> Path:
    """
    Write ``result`` (any kind of :class:`~virtspec_mi.results.base.ResultBase`) to ``path``;
    the suffix picks the format, and only what it needs is built: ``result.to_dataset()``
    for ``.nc`` and ``.zarr``, ``result.csv_dataset()`` for ``.csv``, ``result.sealed_json()``
    for ``.json``. ``plain=True`` (a ``.csv`` only) leaves out the attribute line: a
    header row and the rows, for a spreadsheet. A failed write (a full disk …) raises
    :class:`~virtspec_mi.base.files.WriteError` naming the path and the cause, with the result
    attached (``error.result``): nothing traced is lost with the file.
    """

    path = Path(path)
    if not isinstance(plain, (bool, np.bool_)):
        raise ValueError(f"plain must be True or False (got {plain!r})")
    suffix = check_plain_csv(path) if plain else result_format(path)
    own = getattr(result, "SUFFIXES", SUFFIXES)
    if suffix not in own:
        raise ValueError(f"a {result.KIND} is written as {', '.join(own + tuple(result.EXPORTS))} "
                         f"(got {path.name!r})")
    try:
        if suffix == ".zarr":
            from virtspec_mi.results.zarr import write_result

            return write_result(result, path)
        with atomic_file(path) as temporary:
            if suffix == ".nc":
                result.to_dataset().to_netcdf(temporary, engine="netcdf4")
            elif suffix == ".json":
                temporary.write_text(result.sealed_json() + "\n")
            else:
                temporary.write_text(csv_text(result.csv_dataset(), plain=bool(plain)))
    except WriteError as error:
        raise error.keeping(error.kept or IN_MEMORY, result) from None
    return path


def rescue(result: Any, path: str | os.PathLike) -> str:
    """
    Write ``result`` as JSON into the system's temporary directory, after its file
    ``path`` could not be written (the command line does, before its process ends);
    where it went — or why not —, in words.
    """

    target = Path(tempfile.gettempdir()) / f"virtspec-rescued-{Path(path).stem}-{os.getpid()}.json"
    try:
        write(result, target)
    except WriteError as error:
        return f"a copy could not be written to {target} either ({error.cause}): the result is lost with this process"
    reader = spoken("virtspec_mi.read_result reads it", "virtspec plot, colour and compare read it")
    return f"the result was written to {target} instead ({reader})"


def check_output(path: str | os.PathLike, name: str = "out") -> Path:
    """
    ``path`` as a ``Path`` when a result file can be written there (a known suffix, an
    existing directory, not itself a directory; a Zarr store: nothing there, an empty
    directory or a store of this project's, :func:`virtspec_mi.results.zarr.check_store`),
    else ``ValueError`` naming ``name``.
    """

    path = Path(path)
    zarr = result_format(path) == ".zarr"
    if path.is_dir() and not zarr:
        raise ValueError(f"{name} {path} is a directory; give a file path")
    if zarr:
        from virtspec_mi.results.zarr import check_store

        check_store(path, name)
    if not path.parent.exists():
        raise ValueError(f"{name} {path} cannot be written: directory {path.parent} does not exist")
    if not path.parent.is_dir():
        raise ValueError(f"{name} {path} cannot be written: {path.parent} is not a directory")
    return path


def check_plain_csv(path: str | os.PathLike, name: str = "out") -> str:
    """``".csv"`` when ``path`` ends in it (a plain CSV is a CSV), else ``ValueError`` naming ``name``."""

    if Path(path).suffix.lower() != ".csv":
        raise ValueError(f"{name} must end in .csv: a plain CSV holds columns and rows, without the attribute line "
                         f"(got {Path(path).name!r})")
    return ".csv"


def csv_text(dataset: Any, plain: bool = False) -> str:
    """
    The CSV form of a result's dataset: the attribute header line (none when ``plain``),
    then a row of column names and one row per reading (floats in their shortest exact
    form, NaN as an empty field). Linear in the cells, and column by column (no Python
    call per cell but the float's ``repr``).
    """

    frame = dataset.to_dataframe().reset_index()
    columns = [_csv_fields(frame[name].to_numpy()) for name in frame.columns]
    header = [] if plain else [_CSV_HEADER + json.dumps(dataset.attrs)]
    lines = [*header, ",".join(map(str, frame.columns)), *map(",".join, zip(*columns))]
    return "\n".join(lines) + "\n"


def read(path: str | os.PathLike) -> tuple[str, Any]:
    """
    What a result file holds: ``("dataset", xarray.Dataset)`` for ``.nc`` and a Zarr
    store of a whole result, ``("table", xarray.Dataset)`` for a sweep's Zarr table,
    ``("rows", xarray.Dataset)`` for ``.csv`` (its attributes, and its rows over the dim
    ``row``), ``("plain", dict)`` for ``.json``; ``FileNotFoundError`` if it is missing,
    ``ValueError`` if it is not a virtspec-mi result (messages without the path:
    :func:`virtspec_mi.results.integrity.read_file` names it).
    """

    path = Path(path)
    suffix = result_format(path, "file")
    if suffix == ".zarr":
        if not path.exists():
            raise FileNotFoundError(f"Zarr result not found: {path}")
        if not path.is_dir():
            raise ValueError("is not a Zarr store (a directory)")
        from virtspec_mi.results.zarr import is_table, read as read_zarr

        dataset = read_zarr(path)
        return ("table", dataset) if is_table(dataset) else ("dataset", dataset)
    if not path.is_file():
        if path.exists():
            raise ValueError("is not a file")
        raise FileNotFoundError(f"result file not found: {path}")
    if suffix == ".nc":
        import xarray as xr

        try:
            with xr.open_dataset(path, engine="netcdf4") as dataset:
                return "dataset", dataset.load()
        except (OSError, ValueError, RuntimeError, KeyError, IndexError, TypeError) as error:
            raise ValueError(f"could not be read as NetCDF ({type(error).__name__}: {error})") from None
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"is not UTF-8 text ({error})") from None
    if suffix == ".json":
        try:
            data = json.loads(text)
        except (json.JSONDecodeError, RecursionError) as error:
            raise ValueError(f"is not valid JSON ({type(error).__name__}: {error})") from None
        if not isinstance(data, dict):
            raise ValueError(f"is not a virtspec-mi result (a JSON {type(data).__name__}, not an object)")
        return "plain", unsealed(text, data)
    first, _, body = text.partition("\n")
    if not first.startswith(_CSV_HEADER):
        raise ValueError(f"is not a virtspec-mi result CSV (its first line must start with {_CSV_HEADER.strip()!r}; "
                         "a plain CSV, written for a spreadsheet, holds no settings to read back)")
    try:
        attrs = json.loads(first[len(_CSV_HEADER):])
    except (json.JSONDecodeError, RecursionError) as error:
        raise ValueError(f"has a bad header line ({error})") from None
    if not isinstance(attrs, dict):
        raise ValueError("has a bad header line (not a JSON object)")
    return "rows", _rows(body, attrs)


def _rows(body: str, attrs: dict[str, Any]) -> Any:
    """A CSV file's rows (after the header line) as a dataset over the dim ``row``, with ``attrs``."""

    import io as text_io

    import pandas as pd
    import xarray as xr

    try:
        frame = pd.read_csv(text_io.StringIO(body), keep_default_na=False, na_values=[""])
    except (ValueError, pd.errors.ParserError, pd.errors.EmptyDataError) as error:
        raise ValueError(f"has rows that are not CSV ({' '.join(str(error).split())})") from None
    columns = {}
    for name in frame.columns:
        values = frame[name].to_numpy()
        numeric = values.dtype.kind in "iuf" and (values.dtype.kind != "u" or not len(values) or values.max() < 2**63)
        columns[str(name)] = ("row", values.astype(np.float64) if numeric else values.astype(str))
    return xr.Dataset(columns, attrs=attrs)


def is_result_csv(path: str | os.PathLike) -> bool:
    """True when ``path`` is a CSV written by :func:`write` (not colour-science spectra)."""

    path = Path(path)
    with path.open() as handle:
        return handle.readline().startswith(_CSV_HEADER)


def write_spectra_csv(result: Any, path: str | os.PathLike, theta_i: float | None = None) -> Path:
    """R, T and A at one θi in colour-science's CSV spectral format (wavelength column + one per quantity)."""

    import colour

    if len(result.wavelengths) < 6:  # colour-science's CSV writer asserts on fewer
        raise ValueError(f"colour-science CSV spectra need at least 6 wavelengths (got {len(result.wavelengths)})")
    msds = result.to_msds(theta_i)
    sds = {label: colour.SpectralDistribution(msds.values[:, k], msds.wavelengths, name=label)
           for k, label in enumerate(msds.labels)}
    with atomic_file(path) as temporary:
        colour.write_sds_to_csv_file(sds, str(temporary))
    return Path(path)


def read_spectra_csv(path: str | os.PathLike) -> dict[str, Any]:
    """The spectra of a colour-science CSV spectral file, by column name (``colour.SpectralDistribution``)."""

    import colour

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"spectra file not found: {path}")
    try:
        return dict(colour.read_sds_from_csv_file(str(path)))
    except (ValueError, KeyError, IndexError) as error:
        raise ValueError(f"could not read colour-science CSV spectra {path}: {error}") from None


def result_format(path: str | os.PathLike, name: str = "out") -> str:
    """
    The result format of ``path`` by its suffix (``.nc``, ``.csv``, ``.json``), else
    ``ValueError`` naming ``name`` (``out`` for a file to write, ``file`` for one to read).
    """

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        what = "" if name == "out" else " (a virtspec-mi result file: a sweep, a reading or `measure --json` output)"
        raise ValueError(f"{name} must end in one of {', '.join(SUFFIXES)}{what} (got {path.name!r})")
    return suffix


def _csv_fields(values: np.ndarray) -> list[str]:
    """
    One CSV column: floats as Python's shortest exact ``repr`` (NaN: empty), other values
    as ``str``. Not numpy's or pandas' formatting: it follows numpy's print options, and
    colour-science sets the legacy ones (12 significant digits) when it is imported.
    """

    if values.dtype.kind != "f":
        return list(map(str, values.tolist()))
    fields = list(map(repr, values.astype(np.float64).tolist()))
    for k in np.flatnonzero(np.isnan(values)).tolist():
        fields[k] = ""
    return fields


