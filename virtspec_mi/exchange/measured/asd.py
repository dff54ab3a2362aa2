"""
ASD FieldSpec binary files (``.asd``): a reader of the published format
=======================================================================

An ASD file (FieldSpec, LabSpec, HandHeld; file versions 1–8, the first three bytes
``ASD`` or ``as2`` … ``as8``) holds a 484-byte header, the spectrum (``channels`` values,
float32, int32 or float64 by the header's data format) and, from version 2, a reference
header and the white reference in the same data format. The header fields read here (byte
offsets of the *ASD File Format* v8 document): data type (186; 0 raw DN, 1 reflectance,
2 radiance, 6 transmittance …), first wavelength (191, float32 nm) and step (195),
data format (199), channels (204, uint16), splice wavelengths (444, 448, float32 nm).

- A **reflectance** (or **transmittance**) file holds the target's DN and the white
  reference's DN: the reader returns the pair, ratioed by the common rules
  (:func:`~virtspec_mi.exchange.measured.base.settle`).
- A **raw** file with its reference tells no quantity: the pair is ratioed when the user
  states one (``measured_quantity``). Radiance, irradiance, absorbance and the other
  data types are refused (not a reflectance or transmittance factor).
- **Splice correction**, on request only (``splice=True``): the VNIR / SWIR1 / SWIR2
  detectors meet at the header's splice wavelengths (default 1000 and 1800 nm); each
  later detector's segment is shifted by a constant so that its first channel continues
  the line through the last two channels of the segment before it (the additive jump
  correction). It changes the data: the note says by how much.

No package reader is used: ``pyasdreader`` (MIT) writes a log file into the working
directory when imported and reports a bad file in its log instead of raising;
``specdal`` (MIT) has had no release since 2018 and pulls pandas, SciPy and Matplotlib.

References
----------
ASD Inc. (2017), *ASD File Format*, version 8, revision B (the header's byte offsets,
the reference file header, the data types and formats).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from virtspec_mi.exchange.measured.base import RawSpectra, refuse

__all__ = ["read_asd", "splice_correct", "HEADER_BYTES", "DATA_TYPES", "DATA_FORMATS"]

HEADER_BYTES = 484
"""The spectrum file header's size."""

DATA_TYPES: dict[int, str] = {0: "raw", 1: "reflectance", 2: "radiance", 3: "no units", 4: "irradiance",
                              5: "quality index", 6: "transmittance", 7: "unknown", 8: "absorbance"}
"""The header's data type (byte 186)."""

DATA_FORMATS: dict[int, tuple[str, int]] = {0: ("<f4", 4), 1: ("<i4", 4), 2: ("<f8", 8)}
"""The header's data format (byte 199) → NumPy dtype and bytes per value."""

_VERSIONS = {b"ASD": 1, **{f"as{k}".encode(): k for k in range(2, 9)}}
_REFERENCE_HEADER = 2 + 8 + 8  # flag (bool, 2 bytes), reference time, spectrum time (8 bytes each)
_SPLICES = (1000.0, 1800.0)


def _header(path: Path, data: bytes) -> dict[str, object]:
    if len(data) < HEADER_BYTES:
        raise refuse(path, f"truncated: {len(data)} bytes, shorter than the {HEADER_BYTES}-byte ASD header")
    version = _VERSIONS.get(data[:3])
    if version is None:
        raise refuse(path, f"not an ASD file (it starts with {data[:3]!r}, not 'ASD' or 'as2' ... 'as8')")
    data_type = data[186]
    first, step = struct.unpack_from("<ff", data, 191)
    data_format = data[199]
    (channels,) = struct.unpack_from("<H", data, 204)
    splices = struct.unpack_from("<ff", data, 444)
    if data_format not in DATA_FORMATS:
        raise refuse(path, f"its data format (byte 199) is {data_format}, none of 0 (float), 1 (integer), 2 (double)")
    if channels == 0 or not (np.isfinite(first) and np.isfinite(step) and first > 0 and step > 0):
        raise refuse(path, f"its header holds no wavelength scale (channels {channels}, first wavelength {first:g} "
                           f"nm, step {step:g} nm)")
    return {"version": version, "data_type": data_type, "first": first, "step": step, "format": data_format,
            "channels": channels, "splices": splices, "comment": data[3:160].split(b"\0")[0].decode("latin-1")}


def _block(path: Path, data: bytes, start: int, channels: int, data_format: int, what: str) -> np.ndarray:
    dtype, size = DATA_FORMATS[data_format]
    end = start + channels * size
    if len(data) < end:
        raise refuse(path, f"truncated in its {what}: {channels} values of {size} bytes need bytes {start}-{end}, "
                           f"the file has {len(data)}")
    return np.frombuffer(data, dtype=dtype, count=channels, offset=start).astype(np.float64)


def _reference(path: Path, data: bytes, start: int, channels: int, data_format: int) -> np.ndarray:
    if len(data) < start + _REFERENCE_HEADER + 2:
        raise refuse(path, f"truncated before its reference: the reference header starts at byte {start}, the file "
                           f"has {len(data)} bytes")
    (flag,) = struct.unpack_from("<h", data, start)
    (length,) = struct.unpack_from("<H", data, start + _REFERENCE_HEADER)
    if not flag:
        raise refuse(path, "its reference flag is off: it holds no white reference to ratio against")
    return _block(path, data, start + _REFERENCE_HEADER + 2 + length, channels, data_format, "reference data")


def splice_correct(wavelengths: np.ndarray, values: np.ndarray, splices: tuple[float, ...]) -> tuple[np.ndarray, str]:
    """
    The additive jump correction at each splice wavelength (see the module docstring):
    the corrected values and a note of the shifts applied.
    """

    corrected = np.array(values, dtype=np.float64)
    shifts = []
    for splice in sorted(splices):
        left = np.flatnonzero(wavelengths <= splice)
        right = np.flatnonzero(wavelengths > splice)
        if len(left) < 2 or not len(right):
            continue
        a, b, c = left[-2], left[-1], right[0]
        slope = (corrected[b] - corrected[a]) / (wavelengths[b] - wavelengths[a])
        expected = corrected[b] + slope * (wavelengths[c] - wavelengths[b])
        shift = expected - corrected[c]
        corrected[right] += shift
        shifts.append(f"{shift:+.5g} above {splice:g} nm")
    return corrected, ("splice-corrected: " + ", ".join(shifts)) if shifts else "splice correction: no splice inside"


def read_asd(path: Path, splice: bool = False) -> RawSpectra:
    """One ASD file's spectrum (see the module docstring); ``ValueError`` naming the file and the fault."""

    path = Path(path)
    data = path.read_bytes()
    header = _header(path, data)
    channels, data_format = int(header["channels"]), int(header["format"])  # type: ignore[call-overload]
    wavelengths = header["first"] + header["step"] * np.arange(channels)  # type: ignore[operator]
    data_type = int(header["data_type"])  # type: ignore[call-overload]
    kind = DATA_TYPES.get(data_type, f"data type {data_type}")
    told = f"its header's data type {data_type}, {kind}"
    if kind not in ("raw", "reflectance", "transmittance"):
        raise refuse(path, f"it holds {kind} ({told}): not a reflectance or transmittance factor (export the "
                           "reflectance, or save the file as reflectance)")
    if header["version"] == 1:
        raise refuse(path, "an ASD file of version 1 holds no white reference: nothing to ratio the target against")
    target = _block(path, data, HEADER_BYTES, channels, data_format, "spectrum data")
    reference = _reference(path, data, HEADER_BYTES + channels * DATA_FORMATS[data_format][1], channels,
                           data_format)
    note = ""
    if splice:
        splices = tuple(s if np.isfinite(s) and s > 0 else d for s, d in zip(header["splices"], _SPLICES))  # type: ignore[call-overload]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(reference > 0, target / np.where(reference > 0, reference, 1.0), np.nan)
        corrected, note = splice_correct(wavelengths, ratio, splices)
        target, reference = corrected, np.where(np.isfinite(corrected), 1.0, 0.0)
    return RawSpectra(wavelengths=wavelengths, labels=(path.stem,), target=target[None], reference=reference[None],
                      quantity=None if kind == "raw" else kind, unit="nm", told=told,
                      metadata=({"comment": header["comment"], "version": header["version"], "data_type": kind},),
                      note=note)
