"""
Audits of published engine tables (virtspec_mi.applications.tables.audit) and the engines' drop-in
files (virtspec_mi.applications.tables.engine_tables).

The "published" Cycles table is generated here: the independent quadrature of the tests
(tests/microfacet_quadrature.py) on Cycles' grid, printed with six decimals in Cycles'
header layout, with Cycles' own table_ggx_Eavg (quoted in tests/published_tables.py).
A clean table is flagged nowhere (probability ≥ 1 − δ per seed; fixed seeds); a value
moved by 2ε in one cell is caught (|v − Ê| ≥ 2ε − ε > ε′ whenever the certificate holds).
"""

from __future__ import annotations

import dataclasses
import struct
import subprocess
import sys
import zlib

import numpy as np
import pytest

from microfacet_quadrature import albedo
from published_tables import CYCLES_GGX_EAVG
from virtspec_mi.applications.tables.audit import audit
from virtspec_mi.exchange.conventions import convention
from virtspec_mi.applications.tables.engine_tables import (engine_tables, read_engine_file, read_filament_inc, read_unreal,
                                                write_filament_inc, write_unreal)

EPSILON = 0.05


def _cycles_header(path, values: np.ndarray, average: list[float]) -> None:
    def block(name, numbers):
        body = ",\n".join("  " + ", ".join(f"{v:.6f}f" for v in numbers[i:i + 8]) for i in range(0, len(numbers), 8))
        return f"static const float {name}[{len(numbers)}] = {{\n{body}\n}};\n"

    path.write_text("/* a table in the layout of Cycles' shader.tables */\n" + block("table_ggx_E", values.ravel())
                    + block("table_ggx_Eavg", average))


@pytest.fixture(scope="module")
def published(tmp_path_factory):
    """Height-correlated GGX on Cycles' grid by the test quadrature, six decimals ([mu][roughness])."""

    grid = convention("cycles")
    values = np.array([[albedo(max(mu, 1e-4), alpha, "ggx", "height_correlated", nodes=64) for alpha in grid.alpha]
                       for mu in grid.mu])
    check = [albedo(grid.mu[i], grid.alpha[j], "ggx", "height_correlated", nodes=128) for i, j in
             ((0, 31), (1, 20), (5, 5), (31, 31), (10, 16))]
    assert np.max(np.abs(np.array(check) - values[[0, 1, 5, 31, 10], [31, 20, 5, 31, 16]])) < EPSILON / 20
    path = tmp_path_factory.mktemp("published") / "shader.tables.h"
    _cycles_header(path, np.round(values, 6), CYCLES_GGX_EAVG)
    return path, np.round(values, 6)


@pytest.fixture(scope="module", params=[1, pytest.param(2, marks=pytest.mark.slow),
                                        pytest.param(3, marks=pytest.mark.slow), 4])
def certified(request, mi):
    return engine_tables("cycles", epsilon=EPSILON, seed=request.param, progress=False)


def test_a_clean_published_table_is_flagged_nowhere(published, certified):
    path, _ = published
    report = audit(path, certified)
    assert report.outside == 0, report.summary()
    assert set(report.channels) == {"E", "E_avg"} and report.cells == 1056
    assert "0 of 1,056 published cells outside" in report.summary()


def test_a_planted_error_of_two_epsilon_is_caught(published, certified):
    _, values = published
    for sign, (i, j) in ((+1, (7, 19)), (-1, (26, 3)), (+1, (12, 31))):
        moved = values.copy()
        moved[i, j] += sign * 2 * EPSILON
        report = audit({"E": moved, "E_avg": np.array(CYCLES_GGX_EAVG)}, certified)
        assert report.outside == 1, report.summary()
        worst = report.worst(1)[0]
        assert worst["index"] == (i, j) and worst["channel"] == "E"
        assert worst["discrepancy_eps"] == pytest.approx(sign * 2, abs=1.0)
        assert worst["excess_eps"] > 0
        assert worst["mu"] == pytest.approx(convention("cycles").mu[i])
        assert worst["roughness"] == pytest.approx(convention("cycles").roughness[j])


def test_the_heat_map_and_the_drop_in_header(published, certified, tmp_path):
    _, values = published
    moved = values.copy()
    moved[4, 4] += 3 * EPSILON
    report = audit({"E": moved}, certified)
    report.figure(tmp_path / "audit.png")
    assert (tmp_path / "audit.png").read_bytes().startswith(b"\x89PNG")
    certified.write(tmp_path / "ggx.h")
    back = read_engine_file(tmp_path / "ggx.h", "cycles")
    assert np.allclose(back["E"], certified.values("E"), atol=1e-7)
    assert np.allclose(back["E_avg"], certified.table.E_avg, atol=1e-7)
    assert "height-correlated" in (tmp_path / "ggx.h").read_text()
    assert (tmp_path / "ggx.h.json").exists()
    with pytest.raises(ValueError, match=r"must end in \.h or \.hpp"):
        certified.write(tmp_path / "ggx.inc")


def test_filament_inc_round_trip_in_gl_order(tmp_path):
    rng = np.random.default_rng(0)
    x, y, cloth = rng.random((3, 128, 128))
    write_filament_inc(tmp_path / "dfg.inc", x, y, ["a comment"])
    back = read_filament_inc(tmp_path / "dfg.inc")
    assert set(back) == {"DFG.x", "DFG.y"}
    assert np.array_equal(back["DFG.x"], x.astype(np.float16).astype(np.float64))
    text = (tmp_path / "dfg.inc").read_text()
    first = [w for w in text.split() if w.startswith("0x")][:2]  # GL order: the table's last row first
    assert int(first[0][2:-1], 16) == np.float16(x[-1, 0]).view(np.uint16)
    assert int(first[1][2:-1], 16) == np.float16(y[-1, 0]).view(np.uint16)
    write_filament_inc(tmp_path / "dfg3.inc", x, y, cloth=cloth)
    assert set(read_filament_inc(tmp_path / "dfg3.inc")) == {"DFG.x", "DFG.y", "cloth"}
    (tmp_path / "bad.inc").write_text("0x3c00, " * 10)
    with pytest.raises(ValueError, match="not a 128 x 128 texture"):
        read_filament_inc(tmp_path / "bad.inc")


def _png(path, rgb16: np.ndarray, filters: list[int]) -> None:
    """A 16-bit RGB PNG with the given filter per row (the test's own encoder)."""

    h, w, _ = rgb16.shape
    raw = rgb16.astype(">u2").view(np.uint8).reshape(h, w * 6).astype(np.int64)
    out, previous = b"", np.zeros(w * 6, dtype=np.int64)
    for r in range(h):
        line, kind = raw[r], filters[r % len(filters)]
        left = np.concatenate([np.zeros(6, dtype=np.int64), line[:-6]])
        corner = np.concatenate([np.zeros(6, dtype=np.int64), previous[:-6]])
        if kind == 0:
            coded = line
        elif kind == 1:
            coded = line - left
        elif kind == 2:
            coded = line - previous
        elif kind == 3:
            coded = line - (left + previous) // 2
        else:
            p = left + previous - corner
            pa, pb, pc = np.abs(p - left), np.abs(p - previous), np.abs(p - corner)
            coded = line - np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, previous, corner))
        out += bytes([kind]) + (coded & 0xFF).astype(np.uint8).tobytes()
        previous = line

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(out)) + chunk(b"IEND", b""))


def test_unreal_raw_and_png_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    a, b = rng.random((2, 32, 128))
    expected_a = np.floor(a * 65535 + 0.5) / 65535
    for name in ("gf.raw", "gf.png"):
        write_unreal(tmp_path / name, a, b, ["provenance"])
        back = read_unreal(tmp_path / name)
        assert np.array_equal(back["A"], expected_a) and np.allclose(back["B"], b, atol=0.5 / 65535 + 1e-12)
    assert (tmp_path / "gf.raw").stat().st_size == 32 * 128 * 4
    assert b"tEXt" in (tmp_path / "gf.png").read_bytes()
    rgb = np.stack([np.rint(a * 65535), np.rint(b * 65535), np.zeros_like(a)], axis=-1).astype(np.uint16)
    _png(tmp_path / "filtered.png", rgb, [0, 1, 2, 3, 4])  # every PNG filter an exporter may choose
    back = read_unreal(tmp_path / "filtered.png")
    assert np.array_equal(back["A"], rgb[..., 0] / 65535.0) and np.array_equal(back["B"], rgb[..., 1] / 65535.0)
    with pytest.raises(ValueError, match="not a 128 x 32 G16R16 texture"):
        (tmp_path / "short.raw").write_bytes(b"\0" * 100)
        read_unreal(tmp_path / "short.raw")


@pytest.mark.slow
def test_unreal_audit_of_its_own_model(mi, tmp_path):
    """Unreal's A and B certified (ε = 0.05), written as PNG-16, audited clean, then with a planted error."""

    tables = engine_tables("unreal", epsilon=EPSILON, seed=8, progress=False)
    tables.write(tmp_path / "gf.png")
    assert audit(tmp_path / "gf.png", tables).outside == 0
    values = read_unreal(tmp_path / "gf.png")
    values["B"][10, 100] -= 2 * EPSILON
    report = audit(values, tables)
    assert report.outside == 1 and report.worst(1)[0]["index"] == (10, 100)


def test_audit_refuses_mismatches(published, certified):
    with pytest.raises(ValueError, match="does not match"):
        audit(published[0], certified, engine="unreal")
    with pytest.raises(ValueError, match=r"shape \(31, 32\)"):
        audit({"E": np.zeros((31, 32))}, certified)
    with pytest.raises(ValueError, match="no channel 'E'"):
        audit({"A": np.zeros((32, 32))}, certified)


def test_the_command_line_audit(published, tmp_path):
    path, _ = published
    figure, table = tmp_path / "fig.png", tmp_path / "certified.nc"
    run = subprocess.run([sys.executable, "-m", "virtspec_mi", "albedo-table", "--engine", "cycles", "--epsilon",
                          str(EPSILON), "--seed", "4", "--quiet", "--audit", str(path), "--figure", str(figure),
                          "--out", str(table)], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "0 of 1,056 published cells outside" in run.stdout and figure.exists() and table.exists()
    again = subprocess.run([sys.executable, "-m", "virtspec_mi", "albedo-table", "--engine", "cycles", "--from",
                            str(table), "--audit", str(path)], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert again.stdout.count("rays") >= 1 and "0 of 1,056 published cells outside" in again.stdout


def test_an_engine_table_read_back(certified, tmp_path):
    from virtspec_mi.applications.tables.table import read_albedo_table
    from virtspec_mi.applications.tables.engine_tables import EngineTables

    certified.write(tmp_path / "t.nc")
    back = EngineTables.from_table(read_albedo_table(tmp_path / "t.nc"))
    assert back.engine == "cycles" and np.array_equal(back.values("E"), certified.values("E"))
    with pytest.raises(ValueError, match="not an engine table"):
        EngineTables.from_table(dataclasses.replace(certified.table, engine="grid"))


@pytest.fixture(scope="module")
def coarse(mi):
    """A coarse certified Cycles table (epsilon 0.2: seconds), for the refusals."""

    return engine_tables("cycles", epsilon=0.2, seed=0, progress=False)


def test_nan_cells_are_refused_not_passed(coarse):
    values = coarse.values("E").copy()
    values[3, 7] = np.nan
    with pytest.raises(ValueError, match=r"channel 'E': 1 cell not a finite number \(the first at index \(3, 7\)"):
        audit({"E": values.tolist()}, coarse)  # Python lists, as a user hands them
    with pytest.raises(ValueError, match="channel 'E' must hold numbers"):
        audit({"E": [["a"] * 32] * 32}, coarse)


def test_a_filament_half_float_nan_is_refused(tmp_path):
    from virtspec_mi.applications.tables.audit import check_finite

    x, y = np.full((128, 128), 0.5), np.full((128, 128), 0.25)
    y[5, 9] = np.nan
    write_filament_inc(tmp_path / "dfg.inc", x, y)
    read = read_filament_inc(tmp_path / "dfg.inc")
    assert np.isnan(read["DFG.y"][5, 9])
    with pytest.raises(ValueError, match=r"DFG.y'?: 1 cell not a finite number \(the first at index \(5, 9\)"):
        check_finite(read["DFG.y"], "dfg.inc: channel 'DFG.y'")


def test_an_e_avg_of_31_values_is_refused_not_skipped(coarse, tmp_path):
    header = tmp_path / "short.h"
    _cycles_header(header, coarse.values("E"), list(coarse.values("E", average=True))[:31])
    with pytest.raises(ValueError, match="table_ggx_Eavg"):
        audit(header, coarse)
    with pytest.raises(ValueError, match=r"channel 'E_avg' has shape \(31,\)"):
        audit({"E": coarse.values("E"), "E_avg": np.zeros(31)}, coarse)


def test_the_heat_map_never_replaces_the_audited_file(coarse, tmp_path):
    header = tmp_path / "pub.h"
    _cycles_header(header, coarse.values("E"), list(coarse.values("E", average=True)))
    report = audit(header, coarse)
    (tmp_path / "map.png").symlink_to(header)
    with pytest.raises(ValueError, match="is the audited table"):
        report.figure(tmp_path / "map.png")
    assert "table_ggx_E" in header.read_text()


def test_a_channel_named_as_its_quantity_is_named_once():
    from virtspec_mi.applications.tables.engine_tables import held
    from virtspec_mi.exchange.engine_models import ENGINE_CHANNELS

    assert held(ENGINE_CHANNELS["cycles"][1]) == "E"  # not "E = E"
    assert held(ENGINE_CHANNELS["filament"][1]) == "DFG.x = E_R, DFG.y = E"
