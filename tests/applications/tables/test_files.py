"""
Tests of :mod:`virtspec_mi.applications.tables.files`: an albedo table's ``.npy`` and C-header exports.

The ``.npy`` holds Ê as float32 in the engine's memory order, ``NAME_avg.npy`` the E_avg,
and ``NAME.json`` the whole table sealed with its checksum, from which ``read_result`` reads
the table back (from the ``.npy`` or its ``_avg``); a foreign ``NAME.json`` is not replaced
without ``overwrite``; a C header holds the values alone and reading it as a result is refused
with the reason.

References
----------
NumPy's ``.npy`` format (NEP 1); :mod:`virtspec_mi.exchange.header`.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.tables.files import _sidecar
from virtspec_mi.results.integrity import checksum


@pytest.fixture(scope="module")
def table(mi):
    from virtspec_mi.applications.tables.albedo import albedo_table

    made = albedo_table("conductor", engine=None, mu=[1.0, 0.5, 0.2], alpha=[0.3, 0.8], epsilon=0.05, seed=5,
                        progress=False)
    return replace(made, order=("alpha", "mu"))  # an engine's memory order other than the canonical one


def test_npy_holds_the_values_in_memory_order_and_the_sidecar_the_table(table, tmp_path):
    path = table.write(tmp_path / "ggx.npy")
    values = np.load(path)
    assert values.dtype == np.float32 and values.shape == (2, 3)
    np.testing.assert_array_equal(values, table.E.T.astype(np.float32))
    np.testing.assert_array_equal(np.load(tmp_path / "ggx_avg.npy"), table.E_avg.astype(np.float32))
    sealed = json.loads((tmp_path / "ggx.json").read_text())
    stored = sealed.pop("checksum")
    assert stored == checksum(sealed) and sealed["format"] == "virtspec-mi albedo table 1"
    for name in (path, tmp_path / "ggx_avg.npy", tmp_path / "ggx.json"):
        back = vm.read_result(name)
        np.testing.assert_array_equal(back.counts["rays"], table.counts["rays"])
        np.testing.assert_array_equal(back.E, table.E)


def test_a_foreign_sidecar_is_not_replaced_without_overwrite(table, tmp_path):
    (tmp_path / "ggx.json").write_text('{"mine": true}')
    with pytest.raises(ValueError, match=r"its companion file .*ggx.json already exists and was not written by "
                                         r"virtspec-mi for this output"):
        table.write(tmp_path / "ggx.npy")
    assert (tmp_path / "ggx.json").read_text() == '{"mine": true}' and not (tmp_path / "ggx.npy").exists()
    table.write(tmp_path / "ggx.npy", overwrite=True)
    assert json.loads((tmp_path / "ggx.json").read_text())["format"] == "virtspec-mi albedo table 1"
    table.write(tmp_path / "ggx.npy")  # our own sidecar: replaced without asking


@pytest.mark.parametrize("suffix", [".h", ".hpp"])
def test_a_header_holds_values_and_is_no_result(table, tmp_path, suffix):
    path = table.write(tmp_path / f"ggx{suffix}")
    text = path.read_text()
    assert "float" in text and f"{float(table.E.T.ravel()[0]):.6f}"[:6] in text
    with pytest.raises(ValueError, match=r"a C header holds an albedo table's values, not its counts or certificate: "
                                         r"read the table's .nc or .json"):
        vm.read_result(path)


def test_the_sidecar_of_either_npy():
    assert _sidecar(Path("out/ggx.npy")) == Path("out/ggx.json")
    assert _sidecar(Path("out/ggx_avg.npy")) == Path("out/ggx.json")
