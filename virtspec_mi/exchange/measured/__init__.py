"""
Measured spectra from the files users hold: one table of formats
================================================================

:data:`FORMATS` is every measured-file format the package reads, by name: the built-in
ones (one module each) and those of outside packages — an entry point of the group
:data:`ENTRY_POINTS` (``virtspec_mi.measured_formats``) whose value is a
:class:`~virtspec_mi.exchange.measured.base.MeasuredFormat` row, as xarray finds its
backends. Each row names its file suffixes, its reader and, in words, the library it uses
(with its licence) or the published layout it follows:

============  ==================  ================================================================
format        suffixes            reader
============  ==================  ================================================================
``asd``       ``.asd``            ASD FieldSpec binary, file versions 2–8 (:mod:`.asd`)
``sig``       ``.sig``            Spectra Vista text (:mod:`.sig`)
``sed``       ``.sed``            Spectral Evolution text (:mod:`.sed`)
``jcamp``     ``.jdx``, ``.dx``   JCAMP-DX 4.24, single and compound (:mod:`.jcampdx`, ``jcamp``)
``envi``      ``.sli``, ``.hdr``  ENVI spectral library (:mod:`.envi`, ``spectral``)
``table``     ``.csv``, ``.txt``  CSV of many spectra, a column or a row per sample (:mod:`.table`)
============  ==================  ================================================================

:func:`read_samples` reads a file into
:class:`~virtspec_mi.exchange.measured.base.Samples` by the common rules of
:func:`~virtspec_mi.exchange.measured.base.settle` (quantity, scale, wavelength unit, a
pair ratioed); :func:`format_for` finds a file's format (``None``: a file the comparison
module reads itself, a single-spectrum CSV or a NetCDF or result file).

References
----------
xarray, *How to add a new backend* (the ``xarray.backends`` entry-point group).
"""

from __future__ import annotations

import os
import warnings
from importlib.metadata import entry_points
from pathlib import Path

from virtspec_mi.exchange.measured.asd import read_asd
from virtspec_mi.exchange.measured.base import (MEASURED_QUANTITIES, SCALES, MeasuredFile, MeasuredFormat, RawSpectra,
                                                Samples, refuse, settle)
from virtspec_mi.exchange.measured.envi import read_envi
from virtspec_mi.exchange.measured.jcampdx import read_jcamp
from virtspec_mi.exchange.measured.sed import read_sed
from virtspec_mi.exchange.measured.sig import read_sig
from virtspec_mi.exchange.measured.table import claims_table, read_table

__all__ = ["FORMATS", "BUILTIN", "ENTRY_POINTS", "discovered", "format_for", "read_samples", "suffixes",
           "MeasuredFormat", "MeasuredFile", "RawSpectra", "Samples", "settle", "MEASURED_QUANTITIES", "SCALES"]

ENTRY_POINTS = "virtspec_mi.measured_formats"
"""The entry-point group of outside formats (each point's value: a :class:`MeasuredFormat`)."""

BUILTIN: tuple[MeasuredFormat, ...] = (
    MeasuredFormat("asd", (".asd",), read_asd, "ASD FieldSpec binary (file versions 2-8): this package's reader of "
                   "the ASD File Format v8 document", splice=True),
    MeasuredFormat("sig", (".sig",), read_sig, "Spectra Vista .sig text: this package's reader of the SVC layout"),
    MeasuredFormat("sed", (".sed",), read_sed, "Spectral Evolution .sed text: this package's reader of the PSR "
                                               "layout"),
    MeasuredFormat("jcamp", (".jdx", ".dx", ".jcamp"), read_jcamp, "JCAMP-DX 4.24 (single and compound files): "
                   "parsed by the jcamp package (MIT licence), checked here"),
    MeasuredFormat("envi", (".sli", ".hdr"), read_envi, "ENVI spectral library (.sli + .hdr): the header parsed by "
                   "the spectral package (Spectral Python, MIT licence), the data read here"),
    MeasuredFormat("table", (".csv", ".txt"), read_table, "CSV table of many spectra (EcoSIS style: a column or a "
                   "row per sample): this package's reader", claims=claims_table),
)
"""The built-in formats, rows of :data:`FORMATS`."""


def discovered(builtin: tuple[MeasuredFormat, ...]) -> dict[str, MeasuredFormat]:
    """
    The formats ``builtin`` and those of every installed package's entry point of
    :data:`ENTRY_POINTS`, by name. An entry point that cannot be loaded, is not a
    :class:`MeasuredFormat` or takes a name already taken is left out with a
    ``RuntimeWarning`` naming it (one broken package does not stop the tool).
    """

    found = {row.name: row for row in builtin}
    for point in entry_points(group=ENTRY_POINTS):
        try:
            row = point.load()
        except Exception as error:  # an outside package's import error: reported, not fatal
            warnings.warn(f"measured-format entry point {point.name!r} ({point.value}) could not be loaded: {error}",
                          RuntimeWarning, stacklevel=2)
            continue
        if not isinstance(row, MeasuredFormat):
            warnings.warn(f"measured-format entry point {point.name!r} ({point.value}) is not a MeasuredFormat: "
                          "left out", RuntimeWarning, stacklevel=2)
        elif row.name in found:
            warnings.warn(f"measured-format entry point {point.name!r} ({point.value}) takes the name {row.name!r}, "
                          "already taken: left out", RuntimeWarning, stacklevel=2)
        else:
            found[row.name] = row
    return found


FORMATS: dict[str, MeasuredFormat] = discovered(BUILTIN)
"""Every measured-file format by name: the built-in ones, then the outside ones (:data:`ENTRY_POINTS`)."""


def suffixes() -> tuple[str, ...]:
    """Every suffix a format of :data:`FORMATS` reads."""

    return tuple(dict.fromkeys(s for row in FORMATS.values() for s in row.suffixes))


def format_for(path: str | os.PathLike, name: str | None = None) -> MeasuredFormat | None:
    """
    The format of ``path``: the row named ``name`` (``ValueError`` naming the formats when
    none is), else the first row that reads the file (its suffix, its ``claims``), else ``None``.
    """

    if name is not None:
        if name not in FORMATS:
            raise ValueError(f"format must be one of {', '.join(FORMATS)} (got {name!r})")
        return FORMATS[name]
    path = Path(path)
    return next((row for row in FORMATS.values() if row.reads(path)), None)


def read_samples(source: MeasuredFile | str | os.PathLike) -> Samples:
    """
    The spectra of a measured file (a path, or a :class:`MeasuredFile` saying how to read
    it), settled by the common rules; ``ValueError`` naming the file and the fault.
    """

    file = source if isinstance(source, MeasuredFile) else MeasuredFile(source)
    path = Path(file.path)
    if not path.is_file():
        raise ValueError(f"measured file not found: {path}")
    row = format_for(path, file.format)
    if row is None:
        raise refuse(path, f"no format reads it (suffixes: {', '.join(suffixes())}; name one with format=)")
    if file.splice and not row.splice:
        raise refuse(path, f"splice correction applies to formats with detector splices ("
                           f"{', '.join(r.name for r in FORMATS.values() if r.splice)}), not to {row.name}")
    raw = row.read(path, bool(file.splice))
    if not isinstance(raw, RawSpectra):
        raise refuse(path, f"the {row.name} reader returned {type(raw).__name__}, not RawSpectra")
    return settle(path, raw, row.name, quantity=file.quantity, scale=file.scale)
