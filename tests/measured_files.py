"""
Small valid files of every measured-file format, written here from the published layouts
(the readers under test are never used to write them): ASD binary (the v8 header's byte
offsets), SVC ``.sig``, Spectral Evolution ``.sed``, JCAMP-DX (AFFN ``(X++(Y..Y))`` and
``(XY..XY)``, compound ``LINK`` files), ENVI spectral libraries and EcoSIS-style CSV tables.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Sequence

import numpy as np

__all__ = ["write_asd", "write_sig", "write_sed", "write_jcamp", "write_envi", "write_columns", "write_rows"]


def write_asd(path: Path, first: float, step: float, target: Sequence[float], reference: Sequence[float] | None,
              *, data_type: int = 1, data_format: int = 2, version: bytes = b"as8",
              splices: tuple[float, float] = (1000.0, 1800.0), comment: bytes = b"virtspec test") -> Path:
    """An ASD file: the 484-byte header, the spectrum, the reference header and the reference."""

    dtype = {0: "<f4", 1: "<i4", 2: "<f8"}[data_format]
    header = bytearray(484)
    header[0:3] = version
    header[3:3 + len(comment)] = comment
    header[178], header[179] = 6, 8  # program and file versions
    header[186] = data_type
    struct.pack_into("<ff", header, 191, first, step)
    header[199] = data_format
    struct.pack_into("<H", header, 204, len(target))
    struct.pack_into("<ff", header, 444, *splices)
    body = bytes(header) + np.asarray(target, dtype=dtype).tobytes()
    if reference is not None:
        description = b"white reference"
        body += struct.pack("<h", 1) + struct.pack("<d", 0.0) + struct.pack("<d", 0.0)
        body += struct.pack("<H", len(description)) + description + np.asarray(reference, dtype=dtype).tobytes()
    path.write_bytes(body)
    return path


def write_sig(path: Path, wavelengths: Sequence[float], reference: Sequence[float], target: Sequence[float],
              percent: Sequence[float] | None) -> Path:
    """An SVC ``.sig`` file: its header lines, ``data=``, then wavelength, reference, target[, reflectance %]."""

    lines = ["/*** Spectra Vista SIG Data ***/", f"name= {path.name}", "instrument= HI: 1012064 (HR-1024i)",
             "integration= 100, 20, 10, 100, 20, 10", "units= Radiance, Radiance",
             "time= 4/11/2016 2:36:29 PM, 4/11/2016 2:37:34 PM",
             "factors= 1.000, 1.000, 1.000 [Applied reference reflectance correction factors]", "data= "]
    for k, w in enumerate(wavelengths):
        row = f"{w:.1f}  {reference[k]:.4f}  {target[k]:.4f}"
        lines.append(row + (f"  {percent[k]:.4f}" if percent is not None else ""))
    path.write_text("\n".join(lines) + "\n")
    return path


def write_sed(path: Path, wavelengths: Sequence[float], columns: dict[str, Sequence[float]], *,
              measurement: str = "REFLECTANCE", channels: int | None = None) -> Path:
    """A Spectral Evolution ``.sed`` file: its ``Key: value`` header, ``Data:``, the column names, the rows."""

    lines = ["Comment: ", "Version: 2.4 [2.4.0.1]", f"File Name: C:\\DATA\\{path.name}", "Instrument: PSR-3500_SN1 [3]",
             "Detectors: 512,256,256", f"Measurement: {measurement}", "Date: 01/15/2016,01/15/2016",
             "Units: Radiance", f"Channels: {len(wavelengths) if channels is None else channels}",
             f"Columns [{len(columns) + 1}]:", "Data:", "\t".join(["Wvl", *columns])]
    for k, w in enumerate(wavelengths):
        lines.append("\t".join([f"{w:.1f}", *(f"{values[k]:.6f}" for values in columns.values())]))
    path.write_text("\r\n".join(lines) + "\r\n")
    return path


def _jcamp_block(title: str, wavelengths: Sequence[float], values: Sequence[float], xunits: str, yunits: str,
                 form: str, yfactor: float) -> list[str]:
    x = np.asarray(wavelengths, dtype=float)
    lines = [f"##TITLE= {title}", "##JCAMP-DX= 4.24", "##DATA TYPE= UV/VIS SPECTRUM", f"##XUNITS= {xunits}",
             f"##YUNITS= {yunits}", "##XFACTOR= 1", f"##YFACTOR= {yfactor:g}", f"##FIRSTX= {x[0]:g}",
             f"##LASTX= {x[-1]:g}", f"##NPOINTS= {len(x)}"]
    scaled = np.rint(np.asarray(values, dtype=float) / yfactor).astype(int)
    if form == "(X++(Y..Y))":
        lines.append("##XYDATA= (X++(Y..Y))")
        for start in range(0, len(x), 5):
            lines.append(f"{x[start]:g} " + " ".join(str(v) for v in scaled[start:start + 5]))
    else:
        lines.append("##XYPOINTS= (XY..XY)")
        lines += [f"{a:g}, {b}" for a, b in zip(x, scaled)]
    return lines + ["##END="]


def write_jcamp(path: Path, wavelengths: Sequence[float], spectra: dict[str, Sequence[float]], *,
                xunits: str = "NANOMETERS", yunits: str = "REFLECTANCE", form: str = "(X++(Y..Y))",
                yfactor: float = 1e-5) -> Path:
    """A JCAMP-DX file: one block, or a compound ``LINK`` file of one block per spectrum."""

    if len(spectra) == 1:
        ((title, values),) = spectra.items()
        lines = _jcamp_block(title, wavelengths, values, xunits, yunits, form, yfactor)
    else:
        lines = ["##TITLE= library", "##JCAMP-DX= 4.24", "##DATA TYPE= LINK", f"##BLOCKS= {len(spectra)}"]
        for title, values in spectra.items():
            lines += _jcamp_block(title, wavelengths, values, xunits, yunits, form, yfactor)
        lines.append("##END=")
    path.write_text("\n".join(lines) + "\n")
    return path


def write_envi(path: Path, wavelengths: Sequence[float], spectra: dict[str, Sequence[float]], *,
               units: str = "Nanometers", dtype: str = "<f4", scale: float | None = None, offset: int = 0,
               extra: str = "") -> Path:
    """An ENVI spectral library: ``path`` (``.sli``, raw values) and its ``.hdr``."""

    codes = {"<f4": 4, "<f8": 5, "<i2": 2, "<i4": 3, "<u2": 12, ">f4": 4}
    values = np.array(list(spectra.values()), dtype=float)
    if scale is not None:
        values = values * scale
    path.write_bytes(b"\0" * offset + values.astype(dtype).tobytes())
    header = ["ENVI", "description = {test library}", f"samples = {len(wavelengths)}", f"lines = {len(spectra)}",
              "bands = 1", f"header offset = {offset}", "file type = ENVI Spectral Library",
              f"data type = {codes[dtype]}", "interleave = bsq", f"byte order = {1 if dtype.startswith('>') else 0}",
              f"wavelength units = {units}",
              "wavelength = {" + ", ".join(f"{w:g}" for w in wavelengths) + "}",
              "spectra names = {" + ", ".join(spectra) + "}"]
    if scale is not None:
        header.append(f"reflectance scale factor = {scale:g}")
    path.with_suffix(".hdr").write_text("\n".join(header) + ("\n" + extra if extra else "") + "\n")
    return path


def write_columns(path: Path, wavelengths: Sequence[float], spectra: dict[str, Sequence[float]],
                  wavelength_name: str = "wavelength") -> Path:
    """A CSV table, one column per sample."""

    rows = [",".join([wavelength_name, *spectra])]
    rows += [",".join([f"{w:g}", *(f"{v[k]:.6f}" for v in spectra.values())]) for k, w in enumerate(wavelengths)]
    path.write_text("\n".join(rows) + "\n")
    return path


def write_rows(path: Path, wavelengths: Sequence[float], spectra: dict[str, Sequence[float]],
               quantity: str | None = None) -> Path:
    """An EcoSIS-style CSV table, one row per sample: metadata columns, then one column per wavelength."""

    meta = ["sample_name", "species", *(["quantity"] if quantity else [])]
    rows = [",".join([*meta, *(f"{w:g}" for w in wavelengths)])]
    for name, values in spectra.items():
        rows.append(",".join([name, "Glycine max", *([quantity] if quantity else []),
                              *(f"{v:.6f}" for v in values)]))
    path.write_text("\n".join(rows) + "\n")
    return path
