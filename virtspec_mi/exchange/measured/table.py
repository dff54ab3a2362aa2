"""
CSV tables of many spectra (EcoSIS style): one column or one row per sample
===========================================================================

Two layouts, told apart by the header row (comma-, semicolon- or tab-separated; quoted
fields; an empty field is a missing value, left out of that sample):

- **one column per sample**: the first column is the wavelength (its header
  ``wavelength``, ``wavelength (nm)``, ``wavelength_um``, ``nm`` …), every further column a
  sample, its header the sample's label — two samples at least (a file of one value
  column is the single-spectrum CSV that :func:`virtspec_mi.applications.comparison.read_measured`
  reads already), and no column named ``reflectance``, ``transmittance``,
  ``absorptance`` or ``…uncertainty`` (those are a single spectrum's columns);
- **one row per sample** (EcoSIS's own layout): every header field that is a number is a
  wavelength (three at least), the others are metadata columns; a sample's label is its
  ``sample_name``, ``sample``, ``name``, ``id`` or ``spectra`` column (else its row
  number), and a column ``quantity`` (or ``measurement``) holding ``reflectance`` or
  ``transmittance`` for every row tells the quantity.

A column layout tells no quantity (state it); the wavelength unit is told by ``(um)``,
``(µm)``, ``_um`` or ``micrometer`` in the wavelength column's name (else nm); the scale
by ``%`` or ``percent`` in that header, else untold (fractions, values above 1.5 refused
with the hint).

References
----------
EcoSIS (Ecological Spectral Information System), *Dataset submission: spectra and
metadata* (one row or one column per spectrum, metadata columns).
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from virtspec_mi.exchange.measured.base import RawSpectra, refuse

__all__ = ["read_table", "claims_table", "layout"]

_SINGLE = ("reflectance", "transmittance", "absorptance", "uncertainty")
_WAVELENGTH = ("wavelength", "wavelengths", "wl", "nm", "lambda", "wavelength_nm", "wavelength_um")
_LABELS = ("sample_name", "sample", "name", "id", "spectra", "label")
_RESULT_FILE = "# virtspec-mi result"  # the first line of a result CSV (virtspec_mi.results.io)


def _number(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _delimiter(line: str) -> str:
    return ";" if ";" in line else "\t" if "\t" in line else ","


def _header(path: Path) -> tuple[list[str], str] | None:
    try:
        with path.open(encoding="utf-8-sig", errors="replace") as handle:
            for line in handle:
                if line.startswith(_RESULT_FILE):
                    return None  # a virtspec-mi result CSV: the comparison reads it as a result
                if line.strip() and not line.lstrip().startswith("#"):
                    delimiter = _delimiter(line)
                    return [f.strip() for f in next(csv.reader([line], delimiter=delimiter))], delimiter
    except OSError:
        return None
    return None


def _is_wavelength(name: str) -> bool:
    base = name.lower().split("(")[0].strip().replace(" ", "_")
    return base in _WAVELENGTH or base.startswith("wavelength")


def layout(path: Path) -> str | None:
    """``columns``, ``rows`` or ``None`` (not a table of many spectra) from the header row alone."""

    found = _header(Path(path))
    if found is None:
        return None
    fields = found[0]
    numeric = [_number(f) for f in fields if _number(f) is not None]
    if len(numeric) >= 3 and (len(numeric) < len(fields) or (min(numeric) >= 100 and all(  # type: ignore[type-var]
            b > a for a, b in zip(numeric, numeric[1:])))):  # type: ignore[operator]
        return "rows"  # wavelengths as headers (a headerless row of numbers is no header: it is not increasing in nm)
    if len(fields) >= 3 and _is_wavelength(fields[0]) and not numeric:
        lower = [f.lower() for f in fields[1:]]
        if not any(name in _SINGLE or name.endswith("uncertainty") for name in lower):
            return "columns"
    return None


def claims_table(path: Path) -> bool:
    """Whether ``path`` is a table of many spectra (one of the two layouts)."""

    return layout(path) is not None


def _records(path: Path, delimiter: str) -> list[list[str]]:
    text = path.read_text(encoding="utf-8-sig", errors="replace")
    lines = [line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    return [[field.strip() for field in row] for row in csv.reader(io.StringIO("\n".join(lines)),
                                                                   delimiter=delimiter)]


def _value(path: Path, text: str, row: int, column: str) -> float:
    if not text:
        return math.nan
    decimal_comma = "," in text and "." not in text
    if decimal_comma:
        text = text.replace(",", ".")
    value = _number(text)
    if value is None:
        raise refuse(path, f"row {row}, column {column!r}: expected a number (got {text!r})"
                     + (" (a decimal comma?)" if decimal_comma else ""))
    return value


def read_table(path: Path, splice: bool = False) -> RawSpectra:
    """A CSV table of many spectra in either layout (see the module docstring)."""

    path = Path(path)
    kind = layout(path)
    found = _header(path)
    if kind is None or found is None:
        raise refuse(path, "not a table of many spectra (a wavelength column and two sample columns or more, or a "
                           "row per sample under numeric wavelength headers)")
    fields, delimiter = found
    records = _records(path, delimiter)[1:]
    if not records:
        raise refuse(path, "it holds a header and no rows")
    for k, record in enumerate(records, 2):
        if len(record) != len(fields):
            raise refuse(path, f"row {k} has {len(record)} fields, the header {len(fields)} (truncated or damaged?)")
    name = fields[0].lower()
    unit = "um" if any(t in name for t in ("(um)", "(µm)", "_um", "micromet", "micron")) else "nm"
    scale = "percent" if ("%" in name or "percent" in name) else None
    if kind == "columns":
        table = np.array([[_value(path, text, k, fields[j]) for j, text in enumerate(record)]
                          for k, record in enumerate(records, 2)])
        return RawSpectra(wavelengths=table[:, 0], labels=tuple(fields[1:]), values=table[:, 1:].T, unit=unit,
                          scale=scale, told="a column table tells no quantity",
                          metadata=tuple({"column": f} for f in fields[1:]))
    columns = [j for j, f in enumerate(fields) if _number(f) is not None]
    meta = [j for j in range(len(fields)) if j not in columns]
    wavelengths = np.array([float(fields[j]) for j in columns])
    values = np.array([[_value(path, record[j], k, fields[j]) for j in columns] for k, record in enumerate(records, 2)])
    lower = {fields[j].lower(): j for j in meta}
    label_column = next((lower[n] for n in _LABELS if n in lower), None)
    labels = tuple(record[label_column] if label_column is not None and record[label_column] else f"row {k}"
                   for k, record in enumerate(records, 2))
    metadata = tuple({fields[j]: record[j] for j in meta} for record in records)
    quantity, told = None, "its rows tell no quantity (no quantity column)"
    column = next((lower[n] for n in ("quantity", "measurement", "measurement_quantity") if n in lower), None)
    if column is not None:
        stated = {record[column].strip().lower() for record in records}
        if len(stated) != 1:
            raise refuse(path, f"its column {fields[column]!r} holds {sorted(stated)}: one quantity per file")
        quantity, told = stated.pop(), f"its column {fields[column]!r}"
    return RawSpectra(wavelengths=wavelengths, labels=labels, values=values, quantity=quantity, scale=None,
                      unit=None, told=told, metadata=metadata)
