"""
JCAMP-DX spectra (``.jdx``, ``.dx``), read with the ``jcamp`` package
=====================================================================

A JCAMP-DX file (version 4.24 and after) is labelled data records, ``##LABEL= value``,
then the data (``##XYDATA=(X++(Y..Y))`` in AFFN or the compressed ASDF forms, or
``##XYPOINTS=(XY..XY)``); a compound file (``##DATA TYPE= LINK``) holds one block per
spectrum, each with its ``##TITLE``. The parsing is the ``jcamp`` package's (MIT
licence; ``jcamp.read``: every record, the ASDF decompression, ``##XFACTOR`` and
``##YFACTOR`` applied); this module adds the checks that package only prints: the
number of values against ``##NPOINTS``, the ``##END=`` that closes every block (a
truncated file is refused), and the checks of compressed lines.

What the records tell:

- the quantity, from ``##YUNITS``: ``REFLECTANCE`` (or ``%R``), ``TRANSMITTANCE`` (or
  ``%T``); ``ABSORBANCE``, ``KUBELKA-MUNK`` and the other ordinates are refused, and
  ``ARBITRARY UNITS`` or none tells nothing (state it);
- the scale: ``%`` or ``PERCENT`` in ``##YUNITS`` is a percentage, else untold;
- the wavelength unit, from ``##XUNITS``: ``NANOMETERS``, ``MICROMETERS`` (``MICRONS``)
  or ``1/CM`` (wavenumbers, converted to nm).

References
----------
McDonald, R.S. and Wilks, P.A. (1988), JCAMP-DX: A Standard Form for Exchange of
Infrared Spectra in Computer Readable Form, Applied Spectroscopy 42(1):151–162
(labelled data records, ##XYDATA forms, ##NPOINTS, ##END); Lampen, P. et al. (1994),
Applied Spectroscopy 48(12):1545–1552 (compound files, ##BLOCKS).
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.exchange.measured.base import RawSpectra, refuse

__all__ = ["read_jcamp", "x_unit", "y_quantity"]


def x_unit(xunits: str) -> str | None:
    """``##XUNITS`` → ``nm``, ``um``, ``cm-1`` or ``None`` (not told)."""

    text = xunits.strip().upper().replace(" ", "")
    if text in ("NANOMETERS", "NANOMETRES", "NM"):
        return "nm"
    if text in ("MICROMETERS", "MICROMETRES", "MICRONS", "UM", "µM"):
        return "um"
    if text in ("1/CM", "CM-1", "CM^-1"):
        return "cm-1"
    return None


def y_quantity(yunits: str) -> tuple[str | None, str | None]:
    """``##YUNITS`` → (quantity or ``None``, scale or ``None``); an ordinate of neither names itself."""

    text = yunits.strip().upper()
    scale = "percent" if ("%" in text or "PERCENT" in text) else None
    if "REFLECT" in text or text.replace(" ", "") == "%R":
        return "reflectance", scale
    if "TRANSMIT" in text or text.replace(" ", "") == "%T":
        return "transmittance", scale
    if not text or "ARBITRARY" in text:
        return None, scale
    return text.lower(), scale  # absorbance, Kubelka-Munk ...: refused by the common rules


def _blocks(path: Path, text: str) -> list[dict[str, Any]]:
    import jcamp

    opened = sum(1 for line in text.splitlines() if line.upper().startswith("##TITLE"))
    closed = sum(1 for line in text.splitlines() if line.upper().replace(" ", "").startswith("##END="))
    if not opened:
        raise refuse(path, "not a JCAMP-DX file (no ##TITLE= record)")
    if closed < opened:
        raise refuse(path, f"truncated: {opened} ##TITLE= records, {closed} ##END= (every block ends with ##END=)")
    printed = io.StringIO()
    try:
        with contextlib.redirect_stdout(printed):
            record = jcamp.read(io.StringIO(text))
    except Exception as error:  # the package raises bare Exception on an unknown character
        raise refuse(path, f"its data cannot be parsed as JCAMP-DX ({error})") from None
    for message in printed.getvalue().splitlines():
        if "check failed" in message.lower():  # a compressed line's X or Y check (the counts: read_jcamp)
            raise refuse(path, f"damaged data ({message.strip()})")
    return record.get("children") or [record]


def read_jcamp(path: Path, splice: bool = False) -> RawSpectra:
    """A JCAMP-DX file of one spectrum or a compound file of many (see the module docstring)."""

    path = Path(path)
    try:
        text = path.read_text(encoding="latin-1")
    except OSError as error:
        raise refuse(path, f"cannot be read ({error.strerror or error})") from None
    blocks = [block for block in _blocks(path, text) if len(np.atleast_1d(block.get("y", [])))]
    if not blocks:
        raise refuse(path, "it holds no ##XYDATA= or ##XYPOINTS= data")
    grid, rows, labels, metadata = None, [], [], []
    told: tuple[Any, ...] | None = None
    for k, block in enumerate(blocks):
        x, y = np.asarray(block["x"], dtype=np.float64), np.asarray(block["y"], dtype=np.float64)
        title = str(block.get("title", "")).strip() or f"block {k + 1}"
        expected = block.get("npoints")
        if len(x) != len(y) or (isinstance(expected, (int, float)) and len(y) != int(expected)):
            raise refuse(path, f"block {title!r}: {len(y)} values for {len(x)} abscissae and ##NPOINTS= "
                               f"{expected} (truncated or damaged)")
        this = (x_unit(str(block.get("xunits", ""))), *y_quantity(str(block.get("yunits", ""))))
        if told is not None and this != told:
            raise refuse(path, f"block {title!r} has ##XUNITS / ##YUNITS other than the first block's")
        told = this
        if grid is None:
            grid = x
        elif len(x) != len(grid) or not np.allclose(x, grid, rtol=1e-9, atol=1e-9):
            raise refuse(path, f"block {title!r} is on other abscissae than the first (spectra of one file must "
                               "share their wavelengths)")
        rows.append(y)
        labels.append(title)
        metadata.append({key: block[key] for key in ("title", "origin", "owner", "date", "data type", "yunits",
                                                     "xunits") if key in block})
    assert told is not None and grid is not None
    unit, quantity, scale = told
    return RawSpectra(wavelengths=grid, labels=tuple(labels), values=np.array(rows), quantity=quantity, scale=scale,
                      unit=unit, told=f"its ##YUNITS= {blocks[0].get('yunits', '')}", metadata=tuple(metadata))
