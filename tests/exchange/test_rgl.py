"""
Tests of :mod:`virtspec_mi.exchange.rgl`: tensor files written and read back with NumPy alone.

Every dtype round-trips (big-endian input stored little-endian); the bytes of a one-field
file are the documented layout, checked by hand; a file with another magic, version, a
truncated field or a damaged header is refused with its name and the fault; an unsupported
dtype is refused before anything is written. Mitsuba's ``measured`` plugin loading such a
file is tested in ``tests/instruments/goniophotometer/test_rgl.py``.

References
----------
Dupuy & Jakob (2018), ACM Trans. Graph. 37(6), 274; Mitsuba 3, ``include/mitsuba/core/tensor.h``.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest

from virtspec_mi.exchange.rgl import DTYPES, MAGIC, read_tensor, write_tensor


def test_every_dtype_round_trips(tmp_path):
    fields = {
        "description": np.frombuffer("a sample — UTF-8".encode(), dtype=np.uint8),
        "theta_i": np.linspace(0.0, 1.5, 7, dtype=np.float32),
        "counts": np.arange(24, dtype=np.uint32).reshape(2, 3, 4),
        "spectra": np.random.default_rng(0).random((1, 2, 3, 4, 5)),
        "big": np.arange(5, dtype=">f8"),
        "jacobian": np.array([1], dtype=np.uint8),
    }
    path = write_tensor(tmp_path / "sample.bsdf", fields)
    back = read_tensor(path)
    assert list(back) == list(fields)
    for name, value in fields.items():
        np.testing.assert_array_equal(back[name], value, err_msg=name)
        assert back[name].shape == value.shape
        assert back[name].dtype.byteorder in ("<", "=", "|")
    assert back["description"].tobytes().decode() == "a sample — UTF-8"
    assert set(DTYPES) == {1, 5, 10, 11}


def test_the_bytes_are_the_documented_layout(tmp_path):
    path = write_tensor(tmp_path / "one.bsdf", {"ab": np.array([[1.5, -2.0]], dtype=np.float32)})
    data = path.read_bytes()
    assert data[:12] == MAGIC == b"tensor_file\0" and data[12:14] == bytes((1, 0))
    assert struct.unpack_from("<I", data, 14) == (1,)
    assert struct.unpack_from("<H", data, 18) == (2,) and data[20:22] == b"ab"
    ndim, code = struct.unpack_from("<HB", data, 22)
    (offset,) = struct.unpack_from("<Q", data, 25)
    assert (ndim, code) == (2, 10) and struct.unpack_from("<2Q", data, 33) == (1, 2)
    assert offset == 49 == len(data) - 8  # the header, then the data
    assert struct.unpack_from("<2f", data, offset) == (1.5, -2.0)


def test_an_unsupported_dtype_is_refused_before_writing(tmp_path):
    with pytest.raises(ValueError, match=r"tensor field 'n' must be uint8, uint32, float32 or float64 \(got int64\)"):
        write_tensor(tmp_path / "bad.bsdf", {"n": np.arange(3)})
    assert not (tmp_path / "bad.bsdf").exists()


def test_damaged_files_are_refused_with_the_fault(tmp_path):
    good = write_tensor(tmp_path / "good.bsdf", {"x": np.arange(10, dtype=np.float64)}).read_bytes()
    cases = {
        "magic.bsdf": (b"tensor_fil\0\0" + good[12:], r"magic.bsdf: not a tensor file \(no 'tensor_file' magic\)"),
        "version.bsdf": (good[:12] + bytes((2, 0)) + good[14:], r"version.bsdf: tensor file version 2.0, not 1.0"),
        "truncated.bsdf": (good[:-8], r"truncated.bsdf: field 'x' reaches past the end of the file \(truncated\)"),
        "header.bsdf": (good[:20], r"header.bsdf: damaged tensor file header \(error:"),
        "dtype.bsdf": (good[:23] + bytes((7,)) + good[24:], r"dtype.bsdf: damaged tensor file header \(KeyError: 7\)"),
    }
    for name, (data, message) in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(ValueError, match=message):
            read_tensor(tmp_path / name)
