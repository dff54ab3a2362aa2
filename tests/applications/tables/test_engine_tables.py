"""
Tests of :mod:`virtspec_mi.applications.tables.engine_tables`: each engine's own table and its drop-in files.

The file formats round-trip exactly where their number types allow: Filament's ``dfg.inc``
half floats (values k/1024, exact in float16) in GL row order with an optional third channel,
Unreal's G16R16 ``.raw`` and 16-bit PNG (values k/65535), PNG rows under every filter type of
the PNG specification (encoded here from its definitions), a Cycles header's E and E_avg; bad
files are refused with the reason. An Unreal table measured at a loose tolerance writes drop-in
files whose values are its certified ones and whose sidecar states its certificate, and reads
back from its ``.nc`` as the engine's table.

References
----------
PNG (Third Edition), W3C, Sect. 9 (filter types 0–4); Karis (2013); Kulla & Conty (2017).
"""

from __future__ import annotations

import json
import struct
from dataclasses import replace
import zlib

import numpy as np
import pytest

from virtspec_mi.applications.tables.engine_tables import (
    EngineTables,
    check_engine_sidecar,
    engine_layout,
    engine_tables,
    held,
    read_engine_file,
    read_filament_inc,
    read_unreal,
    write_filament_inc,
    write_unreal,
)


def grid(shape: tuple[int, int], denominator: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, denominator + 1, size=shape) / denominator


def test_layouts_and_channel_words():
    assert engine_layout("cycles") == {"E": (32, 32), "E_avg": (32,)}
    assert engine_layout("filament") == {"DFG.x": (128, 128), "DFG.y": (128, 128)}
    assert engine_layout("unreal") == {"A": (32, 128), "B": (32, 128)}
    with pytest.raises(ValueError, match=r"engine must be one of cycles, filament, unreal \(got 'godot'\)"):
        engine_layout("godot")
    assert held({"DFG.x": "E_R", "DFG.y": "E"}) == "DFG.x = E_R, DFG.y = E" and held({"E": "E"}) == "E"


def test_filament_inc_round_trips_half_floats_in_gl_order(tmp_path):
    x, y, cloth = (grid((128, 128), 1024, seed) for seed in (1, 2, 3))
    path = write_filament_inc(tmp_path / "dfg.inc", x, y, ["a comment"])
    text = path.read_text()
    assert "// a comment" in text
    first = int(text.split("0x")[1][:4], 16)  # the first texel written is the last row's first (GL order)
    assert np.array([first], dtype=np.uint16).view(np.float16)[0] == np.float16(x[-1, 0])
    back = read_filament_inc(path)
    np.testing.assert_array_equal(back["DFG.x"], x)
    np.testing.assert_array_equal(back["DFG.y"], y)
    with_cloth = read_filament_inc(write_filament_inc(tmp_path / "cloth.inc", x, y, cloth=cloth))
    np.testing.assert_array_equal(with_cloth["cloth"], cloth)
    (tmp_path / "short.inc").write_text("0x3c00, 0x3c00,\n")
    with pytest.raises(ValueError, match=r"2 half floats, not a 128 x 128 texture of 2 or 3 channels"):
        read_filament_inc(tmp_path / "short.inc")
    with pytest.raises(ValueError, match="x, y .* must be 2-D arrays of one shape"):
        write_filament_inc(tmp_path / "bad.inc", x, y[:5])


@pytest.mark.parametrize("suffix", [".raw", ".png"])
def test_unreal_textures_round_trip_16_bit_values(tmp_path, suffix):
    a, b = grid((32, 128), 65535, 4), grid((32, 128), 65535, 5)
    back = read_unreal(write_unreal(tmp_path / f"gf{suffix}", a, b, ["certified"]))
    np.testing.assert_allclose(back["A"], a, atol=1e-12)
    np.testing.assert_allclose(back["B"], b, atol=1e-12)


def png(rows: np.ndarray, filters: list[int]) -> bytes:
    """A 16-bit RGB PNG of ``rows`` (height, width, 3 uint16), each row filtered by the PNG specification's rule."""

    height, width, _ = rows.shape
    raw = [row.astype(">u2").tobytes() for row in rows]
    stride, pixel = width * 6, 6
    out, previous = b"", bytes(stride)
    for line, kind in zip(raw, filters):
        filtered = bytearray(stride)
        for i in range(stride):
            left = line[i - pixel] if i >= pixel else 0
            up, corner = previous[i], previous[i - pixel] if i >= pixel else 0
            if kind == 0:
                guess = 0
            elif kind == 1:
                guess = left
            elif kind == 2:
                guess = up
            elif kind == 3:
                guess = (left + up) // 2
            else:
                p = left + up - corner
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - corner)
                guess = left if pa <= pb and pa <= pc else up if pb <= pc else corner
            filtered[i] = (line[i] - guess) & 0xFF
        out += bytes([kind]) + bytes(filtered)
        previous = line

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 16, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(out)) + chunk(b"IEND", b""))


def test_png_rows_under_every_filter_type(tmp_path):
    rows = np.random.default_rng(6).integers(0, 65536, size=(32, 128, 3)).astype(np.uint16)
    (tmp_path / "filtered.png").write_bytes(png(rows, [k % 5 for k in range(32)]))
    back = read_unreal(tmp_path / "filtered.png")
    np.testing.assert_array_equal(np.rint(back["A"] * 65535).astype(np.uint16), rows[..., 0])
    np.testing.assert_array_equal(np.rint(back["B"] * 65535).astype(np.uint16), rows[..., 1])


def test_bad_textures_are_refused(tmp_path):
    (tmp_path / "short.raw").write_bytes(b"\x00" * 100)
    with pytest.raises(ValueError, match=r"100 bytes, not a 128 x 32 G16R16 texture \(16384 bytes\)"):
        read_unreal(tmp_path / "short.raw")
    (tmp_path / "text.png").write_text("hello")
    with pytest.raises(ValueError, match="not a .raw texture or a PNG file"):
        read_unreal(tmp_path / "text.png")
    small = np.zeros((4, 8, 3), dtype=np.uint16)
    (tmp_path / "small.png").write_bytes(png(small, [0] * 4))
    with pytest.raises(ValueError, match=r"8 x 4 pixels, Unreal's PreintegratedGF is 128 x 32"):
        read_unreal(tmp_path / "small.png")


def test_a_cycles_header_and_its_average(tmp_path):
    e, e_avg = grid((32, 32), 1000, 7), np.linspace(0.5, 1.0, 32)

    def array(name, values):
        numbers = ", ".join(f"{v:.6f}f" for v in values.ravel())
        return f"static const float {name}[{values.size}] = {{{numbers}}};\n"

    (tmp_path / "ggx.h").write_text(array("table_ggx_E", e) + array("table_ggx_Eavg", e_avg))
    found = read_engine_file(tmp_path / "ggx.h", "cycles")
    np.testing.assert_allclose(found["E"], e, atol=5e-7)
    np.testing.assert_allclose(found["E_avg"], e_avg, atol=5e-7)
    (tmp_path / "short.h").write_text(array("table_ggx_E", e) + array("table_ggx_Eavg", e_avg[:31]))
    with pytest.raises(ValueError, match=r"table_ggx_Eavg \(Cycles' E_avg, 32 values\)"):
        read_engine_file(tmp_path / "short.h", "cycles")
    with pytest.raises(ValueError, match="does not exist"):
        read_engine_file(tmp_path / "absent.h", "cycles")


@pytest.fixture(scope="module")
def unreal(mi):
    return engine_tables("unreal", epsilon=0.1, delta=0.1, seed=2, progress=False)


def test_an_engines_drop_in_files_hold_its_certified_values(unreal, tmp_path):
    assert isinstance(unreal, EngineTables) and unreal.channels == {"A": "E_T", "B": "E_R"}  # Karis's A and B
    a = unreal.values("A")
    assert a.shape == (32, 128) and unreal.tolerance("A").shape == (32, 128)
    back = read_engine_file(unreal.write(tmp_path / "gf.png"), "unreal")
    np.testing.assert_allclose(back["A"], a, atol=0.5 / 65535 + 1e-12)
    np.testing.assert_allclose(back["B"], unreal.values("B"), atol=0.5 / 65535 + 1e-12)
    sidecar = json.loads((tmp_path / "gf.png.json").read_text())
    assert sidecar["engine"] == "unreal" and sidecar["certificate"] == unreal.statement()
    with pytest.raises(ValueError, match=r"path for engine 'unreal' must end in .raw or .png, or .nc"):
        unreal.write(tmp_path / "gf.h")
    with pytest.raises(ValueError, match=r"channel must be one of A, B \(got 'C'\)"):
        unreal.values("C")


def test_the_table_reads_back_as_the_engines_and_sidecars_are_kept(unreal, tmp_path):
    from virtspec_mi.applications.tables.table import read_albedo_table

    again = EngineTables.from_table(read_albedo_table(unreal.write(tmp_path / "gf.nc")))
    np.testing.assert_array_equal(again.values("A"), unreal.values("A"))
    with pytest.raises(ValueError, match="is not an engine table made by engine_tables"):
        EngineTables.from_table(replace(again.table, bsdf={**again.table.bsdf, "fresnel": "one"}))
    (tmp_path / "mine.png.json").write_text('{"mine": 1}')
    with pytest.raises(ValueError, match=r"mine.png.json already exists and was not written by virtspec-mi"):
        check_engine_sidecar(tmp_path / "mine.png")
    check_engine_sidecar(tmp_path / "gf.png", overwrite=True)
