"""
RGL tensor files (``.bsdf``): the layout Mitsuba's ``measured`` plugin reads
============================================================================

A tensor file (Dupuy & Jakob 2018; Mitsuba's ``TensorFile``) is little-endian: the
12-byte magic ``tensor_file\\0``, the version (two bytes, 1 and 0), a uint32 field
count, then per field its name (uint16 length, the bytes), uint16 ndim, a uint8 dtype
(UInt8 = 1, UInt32 = 5, Float32 = 10, Float64 = 11), a uint64 offset and ndim uint64
extents; each field's data at its offset (C order). :func:`write_tensor` writes one,
:func:`read_tensor` reads one back (both with NumPy alone).

Mitsuba's ``measured`` BSDF reads the fields ``description`` (uint8 text), ``theta_i``,
``phi_i``, ``wavelengths`` (float32, 1-D; radians and nm), ``jacobian`` (uint8, one
value), ``ndf``, ``sigma`` (float32, 2-D), ``vndf``, ``luminance`` (float32, 4-D:
φi × θi × n × n) and ``spectra`` (float32, 5-D: φi × θi × λ × n × n): a file with one
(or two) ``phi_i`` is isotropic. The plugin returns the ``spectra`` value interpolated at
the outgoing direction's position in the warped grid with no cosine applied: what is
stored is f·cos θo (and, with ``jacobian`` 1, divided by the NDF / 4σ factor the plugin
applies back).

References
----------
Dupuy, J. and Jakob, W. (2018), An Adaptive Parameterization for Efficient Material
Acquisition and Rendering, ACM Trans. Graph. 37(6), 274 (Sect. 5, the warped grid; the
RGL material database's file format); Mitsuba 3, ``src/bsdfs/measured.cpp`` and
``include/mitsuba/core/tensor.h`` (the fields the plugin checks).
"""

from __future__ import annotations

import os
import struct
from pathlib import Path
from typing import Mapping

import numpy as np

__all__ = ["MAGIC", "DTYPES", "write_tensor", "read_tensor"]

MAGIC = b"tensor_file\0"
"""The first 12 bytes of a tensor file."""

DTYPES: dict[int, np.dtype] = {1: np.dtype("u1"), 5: np.dtype("<u4"), 10: np.dtype("<f4"), 11: np.dtype("<f8")}
"""A field's dtype code → its NumPy dtype (little-endian)."""

_CODES = {dtype: code for code, dtype in DTYPES.items()}


def write_tensor(path: str | os.PathLike, fields: Mapping[str, np.ndarray]) -> Path:
    """
    Write ``fields`` (name → array of a :data:`DTYPES` dtype) as a tensor file at
    ``path`` (atomically: a failed write leaves no partial file).
    """

    from virtspec_mi.base.files import atomic_write

    arrays = {}
    for name, value in fields.items():
        array = np.ascontiguousarray(value)
        dtype = array.dtype.newbyteorder("<") if array.dtype.itemsize > 1 else array.dtype
        if dtype not in _CODES:
            raise ValueError(f"tensor field {name!r} must be uint8, uint32, float32 or float64 (got {array.dtype})")
        arrays[name] = array.astype(dtype, copy=False)
    header = bytearray(MAGIC + bytes((1, 0)) + struct.pack("<I", len(arrays)))
    entries = []
    for name, array in arrays.items():
        encoded = name.encode("ascii")
        entries.append((encoded, array))
    size = len(header) + sum(2 + len(n) + 2 + 1 + 8 + 8 * a.ndim for n, a in entries)
    offset, blobs = size, []
    for encoded, array in entries:
        header += struct.pack("<H", len(encoded)) + encoded + struct.pack("<HB", array.ndim, _CODES[array.dtype])
        header += struct.pack("<Q", offset) + b"".join(struct.pack("<Q", extent) for extent in array.shape)
        blobs.append(array.tobytes())
        offset += len(blobs[-1])
    body = bytes(header) + b"".join(blobs)

    def write(name: str) -> None:
        Path(name).write_bytes(body)

    return atomic_write(path, write)


def read_tensor(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """The fields of a tensor file by name; ``ValueError`` naming the file and the fault."""

    path = Path(path)
    data = path.read_bytes()
    if data[:12] != MAGIC:
        raise ValueError(f"{path.name}: not a tensor file (no 'tensor_file' magic)")
    if data[12:14] != bytes((1, 0)):
        raise ValueError(f"{path.name}: tensor file version {data[12]}.{data[13]}, not 1.0")
    try:
        (count,) = struct.unpack_from("<I", data, 14)
        at, fields = 18, {}
        for _ in range(count):
            (length,) = struct.unpack_from("<H", data, at)
            name = data[at + 2:at + 2 + length].decode("ascii")
            at += 2 + length
            ndim, code = struct.unpack_from("<HB", data, at)
            (offset,) = struct.unpack_from("<Q", data, at + 3)
            shape = struct.unpack_from(f"<{ndim}Q", data, at + 11)
            at += 11 + 8 * ndim
            dtype = DTYPES[code]
            count_values = int(np.prod(shape)) if shape else 1
            if offset + count_values * dtype.itemsize > len(data):
                raise ValueError(f"{path.name}: field {name!r} reaches past the end of the file (truncated)")
            fields[name] = np.frombuffer(data, dtype=dtype, count=count_values, offset=offset).reshape(shape)
    except (struct.error, KeyError, UnicodeDecodeError) as error:
        raise ValueError(f"{path.name}: damaged tensor file header ({type(error).__name__}: {error})") from None
    return fields
