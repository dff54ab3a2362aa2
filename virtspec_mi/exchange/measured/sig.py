"""
Spectra Vista ``.sig`` files: a reader of the published layout
==============================================================

A ``.sig`` file (SVC HR-1024i, HR-768i, GER) is a header of ``key= value`` lines (the
first ``/*** Spectra Vista SIG Data ***/``), then, after ``data=``, one row per channel:
wavelength (nm), reference, target and, when present, the reflectance in %, which is the
target / reference ratio the instrument's software wrote; without that column the pair
(reference, target) is ratioed. The format's ratio column is a reflectance (its manual's
name for it): the quantity is told. Every row must be as wide as the first (a row cut
short is refused; a file cut exactly at a line's end cannot be told from a shorter scan:
the format holds no channel count).

No package reader is used: ``specdal`` (MIT) reads ``.sig`` but has had no release since
2018 and pulls pandas, SciPy and Matplotlib.

References
----------
Spectra Vista Corporation, *SVC HR-1024i User Manual* (the ``.sig`` file).
"""

from __future__ import annotations

from pathlib import Path

from virtspec_mi.exchange.measured.base import RawSpectra, number_rows, refuse, text_lines

__all__ = ["read_sig"]


def read_sig(path: Path, splice: bool = False) -> RawSpectra:
    """An SVC ``.sig`` file (see the module docstring)."""

    path = Path(path)
    lines = text_lines(path)
    if not lines or "spectra vista" not in lines[0].lower() and not any(l.lower().startswith("name=") for l in lines[:5]):
        raise refuse(path, "not an SVC .sig file (no '/*** Spectra Vista SIG Data ***/' line, no 'name=')")
    header: dict[str, str] = {}
    start = None
    for k, line in enumerate(lines):
        key, sep, value = line.partition("=")
        if sep and key.strip().lower() == "data":
            start = k + 1
            break
        if sep:
            header[key.strip().lower()] = value.strip()
    if start is None:
        raise refuse(path, "no 'data=' line: truncated before its data?")
    table = number_rows(path, [(k + 1, line) for k, line in enumerate(lines[start:], start)])
    if table.shape[1] not in (3, 4):
        raise refuse(path, f"its data rows must be wavelength, reference, target[, reflectance %] (got "
                           f"{table.shape[1]} columns)")
    label = header.get("name", path.name).strip() or path.name
    label = Path(label).stem if label.lower().endswith(".sig") else label
    metadata = ({key: header[key] for key in ("instrument", "units", "time", "integration") if key in header},)
    told = "the .sig's reflectance column (the target / reference ratio, in %)"
    if table.shape[1] == 4:
        return RawSpectra(wavelengths=table[:, 0], labels=(label,), values=table[None, :, 3], quantity="reflectance",
                          scale="percent", unit="nm", told=told, metadata=metadata)
    return RawSpectra(wavelengths=table[:, 0], labels=(label,), target=table[None, :, 2], reference=table[None, :, 1],
                      quantity="reflectance", unit="nm", told="the .sig's reference and target columns",
                      metadata=metadata)
