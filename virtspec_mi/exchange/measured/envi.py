"""
ENVI spectral libraries (``.sli`` + ``.hdr``), the header read with the ``spectral`` package
============================================================================================

An ENVI spectral library is a raw binary file (``.sli``) of ``lines`` spectra of
``samples`` values each (``bands = 1``), described by a text header (``.hdr``, the same
name) whose keywords are ENVI's: ``file type = ENVI Spectral Library``, ``samples``,
``lines``, ``data type`` (2 int16, 3 int32, 4 float32, 5 float64, 12 uint16 …), ``byte
order`` (0 little, 1 big endian), ``header offset``, ``wavelength = {…}``, ``wavelength
units``, ``spectra names = {…}`` and, optionally, ``reflectance scale factor``.

The header is parsed by the ``spectral`` package (Spectral Python, MIT licence:
``spectral.io.envi.read_envi_header`` and ``gen_params``: the braces, the lists over many
lines, the data type and byte order as a NumPy dtype). The data are read here with the
header offset honoured and the file's size checked against ``lines × samples`` values (a
truncated library is refused; ``spectral.io.envi.open`` reads a library without its header
offset and fails on a short file with a reshape error).

What the header tells: the quantity from a ``reflectance scale factor`` (reflectance) or
from ``z plot titles`` / ``description`` naming reflectance or transmittance, else
nothing (state it); the scale from the ``reflectance scale factor`` (values divided by
it: a fraction after); the unit from ``wavelength units`` (``Nanometers``,
``Micrometers``).

References
----------
Harris Geospatial (NV5), *ENVI Header Files* (the keywords above); Boggs, T., Spectral
Python (SPy), https://www.spectralpython.net (MIT licence).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from virtspec_mi.exchange.measured.base import RawSpectra, refuse

__all__ = ["read_envi", "library_paths"]

_UNITS = {"nanometers": "nm", "nanometres": "nm", "nm": "nm", "micrometers": "um", "micrometres": "um",
          "microns": "um", "um": "um", "µm": "um", "wavenumber": "cm-1"}


def library_paths(path: Path) -> tuple[Path, Path]:
    """(header, data) of a library given by either file."""

    if path.suffix.lower() == ".hdr":
        for suffix in (".sli", ".SLI"):
            if path.with_suffix(suffix).is_file():
                return path, path.with_suffix(suffix)
        raise refuse(path, f"no library data beside the header ({path.with_suffix('.sli').name})")
    for suffix in (".hdr", ".HDR"):
        if path.with_suffix(suffix).is_file():
            return path.with_suffix(suffix), path
        if Path(str(path) + suffix).is_file():
            return Path(str(path) + suffix), path
    raise refuse(path, f"no ENVI header beside the library ({path.with_suffix('.hdr').name})")


def _told_quantity(header: dict[str, object]) -> tuple[str | None, str]:
    if "reflectance scale factor" in header:
        return "reflectance", "its header's reflectance scale factor"
    for key in ("z plot titles", "description"):
        text = str(header.get(key, "")).lower()
        found = {q for q in ("reflectance", "transmittance") if q in text}
        if len(found) == 1:
            return found.pop(), f"its header's {key}"
    return None, "its header"


def read_envi(path: Path, splice: bool = False) -> RawSpectra:
    """An ENVI spectral library (see the module docstring)."""

    from spectral.io import envi

    header_path, data_path = library_paths(Path(path))
    try:
        header = envi.read_envi_header(str(header_path))
        params = envi.gen_params(header)
    except (envi.EnviException, KeyError, ValueError, UnicodeDecodeError, OSError) as error:
        raise refuse(header_path, f"not a readable ENVI header ({type(error).__name__}: {error})") from None
    if "spectral library" not in str(header.get("file type", "")).lower():
        raise refuse(header_path, f"its file type is {header.get('file type', '(none)')!r}, not 'ENVI Spectral "
                                  "Library'")
    if params.nbands != 1:
        raise refuse(header_path, f"a spectral library has bands = 1 (got {params.nbands})")
    spectra, channels = params.nrows, params.ncols
    dtype = np.dtype(params.dtype)
    needed = params.offset + spectra * channels * dtype.itemsize
    size = data_path.stat().st_size
    if size < needed:
        raise refuse(data_path, f"truncated: {spectra} spectra of {channels} {dtype.name} values after a "
                                f"{params.offset}-byte offset need {needed} bytes, the file has {size}")
    values = np.fromfile(data_path, dtype=dtype, count=spectra * channels, offset=params.offset)
    values = values.reshape(spectra, channels).astype(np.float64)
    if "wavelength" not in header:
        raise refuse(header_path, "its header holds no wavelength = {...} list")
    try:
        wavelengths = np.array([float(w) for w in header["wavelength"]])
    except ValueError:
        raise refuse(header_path, "its wavelength list holds a value that is not a number") from None
    if len(wavelengths) != channels:
        raise refuse(header_path, f"{len(wavelengths)} wavelengths for samples = {channels}")
    names = header.get("spectra names") or [str(k + 1) for k in range(spectra)]
    if len(names) != spectra:
        raise refuse(header_path, f"{len(names)} spectra names for lines = {spectra}")
    ignore = header.get("data ignore value")
    if ignore is not None:
        values[values == float(ignore)] = np.nan
    quantity, told = _told_quantity(header)
    scale = None
    if "reflectance scale factor" in header:
        factor = float(header["reflectance scale factor"])
        if not factor > 0:
            raise refuse(header_path, f"its reflectance scale factor must be > 0 (got {factor:g})")
        values, scale = values / factor, "fraction"
    unit_text = str(header.get("wavelength units", "")).strip().lower()
    unit = _UNITS.get(unit_text)
    if unit_text and unit is None and unit_text not in ("unknown", "index"):
        raise refuse(header_path, f"its wavelength units {header['wavelength units']!r} are none of Nanometers, "
                                  "Micrometers")
    return RawSpectra(wavelengths=wavelengths, labels=tuple(str(n).strip() for n in names), values=values,
                      quantity=quantity, scale=scale, unit=unit, told=told,
                      metadata=tuple({"name": str(n).strip()} for n in names))
