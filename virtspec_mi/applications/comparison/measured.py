"""
Measured spectra: :class:`MeasuredSpectrum` and :func:`read_measured`
=====================================================================

What :func:`virtspec_mi.applications.comparison.compare` holds a result to: a measured
spectrum read from a file (colour-science CSV, plain CSV or text, NetCDF, a virtspec-mi
result file, an instrument's or a library's file of :mod:`virtspec_mi.exchange.measured`), a ``colour.SpectralDistribution``, arrays or another result, checked (nm,
fractions in [0, 1] up to the measurement's own uncertainty; see the package docstring).

References
----------
colour-science ``colour.io`` CSV spectral files; Baranoski et al. (2001), Sect. 5.
"""

from __future__ import annotations

import math
import re
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.base.checks import NANOMETRE_FLOOR, check_nanometres
from virtspec_mi.base.surface import spoken
from virtspec_mi.exchange.measured import MeasuredFile, Samples, format_for, read_samples, suffixes
from virtspec_mi.kernel.counts import QUANTITIES
from virtspec_mi.results.base import ResultBase

__all__ = ["MeasuredSpectrum", "read_measured", "check_quantity", "MEASURED_SUFFIXES"]

MEASURED_SUFFIXES: tuple[str, ...] = tuple(dict.fromkeys((".csv", ".txt", ".nc", ".json", *suffixes())))
"""Files :func:`read_measured` reads (``.json``: a virtspec-mi result file; the instruments' and libraries' files of
:data:`virtspec_mi.exchange.measured.FORMATS`)."""

_PERCENT = 1.5  # measured values above this are taken for percentages
_MATCH_NM = 1e-6  # wavelengths closer than this are the same


@dataclass(frozen=True, eq=False)
class MeasuredSpectrum:
    """
    A measured spectrum, sorted by wavelength.

    Attributes
    ----------
    wavelengths : ndarray
        Distinct wavelengths in nm, increasing.
    values : ndarray
        The measured quantity (a fraction) at each wavelength.
    uncertainty : ndarray or None
        Per-point measurement uncertainty (same unit), ``None`` when not known.
    quantity : str
        What was measured (``reflectance``, ``transmittance`` or ``absorptance``).
    source : str
        Where it came from (a file name, a spectrum's name).
    note : str
        Empty, or what was done while reading (points without a value skipped).
    """

    wavelengths: np.ndarray
    values: np.ndarray
    uncertainty: np.ndarray | None
    quantity: str
    source: str
    note: str = ""

    @classmethod
    def of(cls, wavelengths: Any, values: Any, uncertainty: Any = None, *, quantity: str = "reflectance",
           source: str = "measured", note: str = "", column: str = "", fractions: bool = True) -> "MeasuredSpectrum":
        """
        A checked spectrum from arrays (any order; sorted here); ``ValueError`` naming the
        problem — and, for a value a fraction cannot take (``fractions``: a measured
        reflectance, transmittance or absorptance lies in [0, 1], up to its own
        measurement uncertainty), the ``source``, the ``column`` and the wavelength.
        """

        wavelengths = np.asarray(wavelengths, dtype=np.float64).ravel()
        values = np.asarray(values, dtype=np.float64).ravel()
        if len(wavelengths) != len(values):
            raise ValueError(f"measured wavelengths and values must have one length "
                             f"(got {len(wavelengths)} and {len(values)})")
        if not len(wavelengths):
            raise ValueError(f"measured spectrum {source} holds no points")
        if not np.all(np.isfinite(wavelengths) & (wavelengths > 0)):
            raise ValueError(f"measured wavelengths must be finite and > 0 nm ({source})")
        check_nanometres(wavelengths, "measured wavelengths", source)
        if not np.all(np.isfinite(values)):
            raise ValueError(f"measured values must be finite ({source})")
        if fractions and values.max() > _PERCENT:
            raise ValueError(f"measured values must be fractions in [0, 1] (got up to {values.max():g} in {source}: "
                             "percentages? divide by 100)")
        order = np.argsort(wavelengths, kind="stable")
        wavelengths, values = wavelengths[order], values[order]
        if np.any(np.diff(wavelengths) < _MATCH_NM):
            raise ValueError(f"measured wavelengths must be distinct (repeated in {source})")
        if uncertainty is not None:
            uncertainty = _check_uncertainty(uncertainty, len(order), source)[order]
        if fractions:
            _check_fractions(wavelengths, values, uncertainty, quantity, source, column)
        return cls(wavelengths, values, uncertainty, quantity, source, note)

    def with_uncertainty(self, uncertainty: Any) -> "MeasuredSpectrum":
        """The same spectrum with ``uncertainty`` (a number, or one per point) in place of its own."""

        values = _check_uncertainty(uncertainty, len(self.wavelengths), self.source)
        return MeasuredSpectrum(self.wavelengths, self.values, values, self.quantity, self.source, self.note)


def _check_fractions(wavelengths: np.ndarray, values: np.ndarray, uncertainty: np.ndarray | None, quantity: str,
                     source: str, column: str) -> None:
    """
    A measured fraction lies in [0, 1] up to its own uncertainty (none given: exactly);
    ``ValueError`` naming the source, the column and the first wavelength beyond.
    """

    slack = np.zeros_like(values) if uncertainty is None else uncertainty
    for bad, side in ((values < -slack, "below 0"), (values > 1 + slack, "above 1")):
        if np.any(bad):
            k = int(np.flatnonzero(bad)[0])
            where = f"{source}, column {column!r}" if column else source
            allowed = "" if uncertainty is None else f" by more than its uncertainty {uncertainty[k]:g}"
            raise ValueError(
                f"measured {quantity} must lie in [0, 1] ({where}: {values[k]:g} at {wavelengths[k]:g} nm is {side}"
                f"{allowed}; {int(bad.sum())} such point{'s' if bad.sum() > 1 else ''}): a {quantity} is a fraction — "
                "give the measurement's uncertainty if these are measurement noise, or correct the data")


def _check_uncertainty(uncertainty: Any, size: int, source: str) -> np.ndarray:
    refusal = f"measurement_uncertainty must be a number or one value per measured point (got {uncertainty!r})"
    if isinstance(uncertainty, (bool, np.bool_, str)):
        raise ValueError(refusal)
    try:
        values = np.asarray(uncertainty, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(refusal) from None
    if values.ndim == 0:
        values = np.full(size, float(values))
    if values.shape != (size,):
        raise ValueError(f"measurement_uncertainty must be a number or one value per measured point "
                         f"({size} in {source}; got shape {values.shape})")
    if not np.all(np.isfinite(values) & (values >= 0)):
        raise ValueError(f"measurement_uncertainty must be finite and >= 0 ({source})")
    return values


# -- reading measured spectra --------------------------------------------------------


def read_measured(source: Any, quantity: str = "reflectance", theta_i: float | None = None) -> MeasuredSpectrum:
    """
    A measured spectrum of ``quantity`` from a file (see the module docstring for the
    formats), a :class:`~virtspec_mi.exchange.measured.base.MeasuredFile` (a file and how
    to read it: its ``sample``, its ``quantity`` or ``scale`` when it does not tell them,
    ASD's ``splice`` correction), a ``colour.SpectralDistribution``, a ``(wavelengths,
    values[, uncertainty])`` tuple, a :class:`MeasuredSpectrum` or a result of any kind (at
    ``theta_i``; its certified tolerance becomes the uncertainty).
    """

    check_quantity(quantity)
    if isinstance(source, MeasuredSpectrum):
        return source
    if isinstance(source, ResultBase) and source.QUANTITIES:
        return _from_result(source, quantity, theta_i, "result")
    if isinstance(source, MeasuredFile):
        return _from_samples(read_samples(source), quantity, source.sample)
    if isinstance(source, (str, os.PathLike)):
        return _read_file(Path(source), quantity, theta_i)
    if hasattr(source, "wavelengths") and hasattr(source, "values"):  # colour.SpectralDistribution
        name = str(getattr(source, "name", "") or "measured")
        return MeasuredSpectrum.of(source.wavelengths, source.values, quantity=quantity, source=name)
    if isinstance(source, (tuple, list)) and len(source) in (2, 3):
        return MeasuredSpectrum.of(*source, quantity=quantity)
    raise ValueError("measured must be a file path, a colour.SpectralDistribution, a (wavelengths, values"
                     f"[, uncertainty]) tuple or a result (got {type(source).__name__})")


def _read_file(path: Path, quantity: str, theta_i: float | None) -> MeasuredSpectrum:
    suffix = path.suffix.lower()
    if suffix not in MEASURED_SUFFIXES and format_for(path) is None:  # an outside format's suffix reads too
        known = dict.fromkeys((*MEASURED_SUFFIXES, *suffixes()))
        raise ValueError(f"measured must end in one of {', '.join(known)} (got {path.name!r})")
    if not path.is_file():
        raise ValueError(f"measured file not found: {path}")
    if format_for(path) is not None:  # an instrument's or a library's file (exchange.measured)
        return _from_samples(read_samples(path), quantity, None)
    if suffix == ".json" or (suffix == ".csv" and _is_result_csv(path)):
        from virtspec_mi.runtime.reading import read_result

        return _from_result(read_result(path), quantity, theta_i, path.name)
    if suffix == ".nc":
        return _read_netcdf(path, quantity, theta_i)
    return _read_table(path, quantity)


def _from_samples(samples: Samples, quantity: str, sample: str | int | None) -> MeasuredSpectrum:
    """One sample of a measured file (``sample``: its label or index; ``None``: the only one) as a spectrum."""

    if samples.quantity != quantity:
        raise ValueError(f"measured file {samples.source} holds {samples.quantity}, not the {quantity} compared or "
                         f"fitted ({spoken('measured_quantity=', '--measured-quantity')} states what a file that does "
                         "not tell holds)")
    wavelengths, values, label = samples.spectrum(sample)
    source = samples.source if len(samples) == 1 else f"{samples.source} [{label}]"
    return MeasuredSpectrum.of(wavelengths, values, quantity=quantity, source=source, note=samples.note)


def _is_result_csv(path: Path) -> bool:
    from virtspec_mi.results.io import is_result_csv

    return is_result_csv(path)


def _from_result(result: ResultBase, quantity: str, theta_i: float | None, source: str) -> MeasuredSpectrum:
    """The spectrum of another result of what ``quantity`` names (its first quantity that measures it)."""

    mine = [q for q in result.QUANTITIES if result.spectrum_measures(q) == quantity]
    if not mine:
        raise ValueError(f"measured result {source} holds no {quantity} (a {result.KIND} of "
                         f"{result.spectrum_measures(result.QUANTITIES[0])})")
    spectrum = result.spectrum(mine[0], theta_i)
    if np.any(np.isnan(spectrum.tolerance)):
        raise ValueError(f"measured result {source} is not certified (NaN certified_mu): no uncertainty to use")
    return MeasuredSpectrum.of(spectrum.wavelengths, spectrum.values, spectrum.tolerance, quantity=quantity,
                               source=source, fractions=False)  # a reading (a sphere's ratio may pass 1): its rules


_QUANTITY_NAMES = ("reflectance", "transmittance", "absorptance")
"""Column names that say which quantity a column holds (never read as another)."""

_DECIMAL_COMMA = re.compile(r"[-+]?\d*,\d+(?:[eE][-+]?\d+)?")


def _split(line: str) -> list[str]:
    """
    A row's fields: separated by ``;`` or a tab where the row has one (then a decimal comma,
    ``0,52``, is read as the number it writes: the CSV of a spreadsheet in many locales),
    else by ``,``, else by white space.
    """

    separator = ";" if ";" in line else "\t" if "\t" in line else "," if "," in line else None
    fields = [field.strip().strip('"').strip("'") for field in line.split(separator)]
    if separator in (";", "\t"):
        fields = [field.replace(",", ".") if _DECIMAL_COMMA.fullmatch(field) else field for field in fields]
    return fields


def _check_rows(path: Path, lines: list[int], texts: list[list[str]], table: np.ndarray, header: bool) -> None:
    """
    Refuse rows read as something else: numbers written with decimal commas in a comma-separated file (``400,0,52``:
    three fields, none with a point, the second 0 or 1), and a first row of numbers that is a header (its
    wavelength not in nm like the others').
    """

    if not header and all("." not in field for row in texts for field in row) \
            and all(len(row) == 3 and row[1] in ("0", "1") for row in texts):
        raise ValueError(f"measured file {path.name}: its numbers look written with decimal commas in a comma-"
                         f"separated file (line {lines[0]}: {','.join(texts[0])!r}); separate the columns with ';' "
                         "or write decimal points")
    if len(table) > 1 and table.shape[1] > 1 and np.all(table[0, 1:] >= NANOMETRE_FLOOR) \
            and np.all(np.abs(table[1:, 1:]) < NANOMETRE_FLOOR):  # "400;500" above rows of fractions: a header
        raise ValueError(f"measured file {path.name}, line {lines[0]}: {','.join(texts[0])!r} holds wavelengths where "
                         f"the other rows hold values (a header row of numbers?); name the columns "
                         "(wavelength,reflectance) or comment the line out with #")
    wavelengths = table[:, 0]
    if len(wavelengths) > 1 and wavelengths.max() >= NANOMETRE_FLOOR:
        stray = np.nonzero(wavelengths < NANOMETRE_FLOOR)[0]
        if stray.size:
            k = int(stray[0])
            raise ValueError(f"measured file {path.name}, line {lines[k]}: {','.join(texts[k])!r} is not a row of "
                             f"a wavelength in nm like the others (a header row of numbers?); name the columns "
                             "(wavelength,reflectance) or comment the line out with #")


def _numbers(fields: list[str]) -> list[float] | None:
    try:
        return [float(field) if field else math.nan for field in fields]
    except ValueError:
        return None


def _read_table(path: Path, quantity: str) -> MeasuredSpectrum:
    """A colour-science CSV spectral file, or plain ``wavelength,value[,uncertainty]`` rows."""

    header: list[str] | None = None
    rows: list[list[float]] = []
    lines: list[int] = []
    texts: list[list[str]] = []
    for number, line in enumerate(path.read_text().splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = _split(line)
        values = _numbers(fields)
        if values is None and header is None and not rows:
            header = [field.lower() for field in fields]
            continue
        if values is None:
            raise ValueError(f"measured file {path.name}, line {number}: expected numbers (got {line!r})")
        rows.append(values)
        lines.append(number)
        texts.append(fields)
    width = len(header) if header is not None else (len(rows[0]) if rows else 0)
    if not rows:
        raise ValueError(f"measured file {path.name} holds no rows of numbers")
    if any(len(row) != width for row in rows):
        raise ValueError(f"measured file {path.name}: every row must have {width} columns")
    table = np.array(rows, dtype=np.float64)
    _check_rows(path, lines, texts, table, header is not None)
    value, uncertainty = _columns(header, width, quantity, path.name)
    for index, what in ((0, "wavelength"), (value, f"{quantity} value"), (uncertainty, "uncertainty")):
        missing = [] if index is None else np.nonzero(np.isnan(table[:, index]))[0]
        if len(missing):  # never dropped silently: a gap is the file's to fill or remove
            k = int(missing[0])
            more = f" and {len(missing) - 1} more such rows" if len(missing) > 1 else ""
            raise ValueError(f"measured file {path.name}, line {lines[k]}: no {what} (empty or NaN: "
                             f"{','.join(texts[k])!r}){more}; give a number or remove the row")
    return MeasuredSpectrum.of(table[:, 0], table[:, value], None if uncertainty is None else table[:, uncertainty],
                               quantity=quantity, source=path.name,
                               column=header[value] if header is not None else f"column {value + 1}")


def _columns(header: list[str] | None, width: int, quantity: str, name: str) -> tuple[int, int | None]:
    """Indices of the value column and of the uncertainty column (or ``None``)."""

    if header is None:
        if width not in (2, 3):
            raise ValueError(f"measured file {name}: plain rows must be wavelength,value[,uncertainty] "
                             f"(got {width} columns; give a header naming them)")
        return 1, 2 if width == 3 else None
    named = {field: k for k, field in enumerate(header) if k}
    uncertainty = named.get(f"{quantity}_uncertainty", named.get("uncertainty"))
    candidates = [k for field, k in named.items() if "uncertainty" not in field]
    if quantity in named:
        return named[quantity], uncertainty
    if len(candidates) == 1 and header[candidates[0]] in _QUANTITY_NAMES:  # named as another quantity: not this one
        raise ValueError(f"measured file {name} holds {header[candidates[0]]}, no {quantity} column (its columns: "
                         f"{', '.join(header[1:])}); give a {quantity} file or column")
    if len(candidates) == 1:
        return candidates[0], uncertainty
    raise ValueError(f"quantity must name a column of {name} ({', '.join(header[1:])}; got {quantity!r})")


def _read_netcdf(path: Path, quantity: str, theta_i: float | None) -> MeasuredSpectrum:
    import xarray as xr

    try:
        with xr.open_dataset(path) as dataset:
            dataset = dataset.load()
    except (OSError, ValueError) as error:
        raise ValueError(f"could not read NetCDF {path.name}: {error}") from None
    if "result_json" in dataset.attrs or "gonio_json" in dataset.attrs:  # a virtspec-mi result file: its rules
        from virtspec_mi.runtime.reading import read_result

        return _from_result(read_result(path), quantity, theta_i, path.name)
    names = [name for name in dataset.data_vars if "uncertainty" not in str(name)]
    if quantity in dataset.data_vars:
        name = quantity
    elif len(names) == 1:
        name = names[0]
    else:
        raise ValueError(f"quantity must name a variable of {path.name} ({', '.join(map(str, names))}; "
                         f"got {quantity!r})")
    values = dataset[name].squeeze()
    if values.ndim != 1 or values.dims[0] not in dataset.coords:
        raise ValueError(f"{name} of {path.name} must be one-dimensional over a wavelength coordinate "
                         f"(got dims {values.dims})")
    wavelengths = dataset[values.dims[0]].values
    uncertainty = next((dataset[u].squeeze().values for u in (f"{name}_uncertainty", "uncertainty")
                        if u in dataset.data_vars), None)
    for what, array in ((str(name), values.values), ("its uncertainty", uncertainty)):
        missing = [] if array is None else np.nonzero(np.isnan(np.asarray(array, dtype=np.float64)))[0]
        if len(missing):  # never dropped silently
            raise ValueError(f"measured file {path.name}: {what} is NaN at {len(missing)} wavelength"
                             f"{'s' if len(missing) > 1 else ''} (the first {float(wavelengths[missing[0]]):g} nm, "
                             f"index {int(missing[0])}); give a number there or leave the wavelength out")
    return MeasuredSpectrum.of(wavelengths, values.values, uncertainty, quantity=quantity,
                               source=path.name, column=str(name))


# -- the comparison ------------------------------------------------------------------


def check_quantity(quantity: str) -> None:
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)} (got {quantity!r})")
