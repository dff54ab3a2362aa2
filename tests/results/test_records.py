"""
Tests of virtspec_mi.results.records: a record of fields is a kind of the one result family —
registered by its format tag, its Dataset built from its fields with units on every
variable, written by the one writer and read back by ``vm.read_result`` (its counts checked
by its rules, an edited NetCDF value refused), its kind's own exports written and read
through the file they accompany.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.results.base import KINDS
from virtspec_mi.results.integrity import CountRules, whole_counts
from virtspec_mi.results.records import Record, RecordedData, check_record, plain_floats


@pytest.fixture
def tally():
    """A record kind of two counts per cell (hits within rays), with a ``.txt`` export read through its ``.json``."""

    @dataclass(frozen=True, eq=False)
    class Tally(Record):
        FORMAT: ClassVar[str] = "virtspec-mi tally 1"
        KIND: ClassVar[str] = "tally"
        VARIABLES: ClassVar[dict] = {"cell": ("1", "cell"), "rays": ("1", "rays"), "hits": ("1", "hits")}

        rays: np.ndarray
        hits: np.ndarray
        delta: float = field()  # a reading's property name: a record's field all the same

        def _stored(self) -> Any:
            import xarray as xr

            return xr.Dataset({"rays": ("cell", self.rays), "hits": ("cell", self.hits)},
                              coords={"cell": np.arange(len(self.rays))}, attrs={"delta": self.delta})

        def as_dict(self) -> dict:
            return {"format": self.FORMAT, "rays": self.rays.tolist(), "hits": self.hits.tolist(), "delta": self.delta}

        @classmethod
        def _from_dict(cls, data: Any) -> "Tally":
            return cls(whole_counts(data["rays"], "rays"), whole_counts(data["hits"], "hits"), float(data["delta"]))

        def _count_groups(self) -> list:
            return [("", {"rays": self.rays, "hits": self.hits}, CountRules("rays", parts={"hits": "rays"}), ("cell",))]

    def export(result: Any, path: Path) -> Path:
        path.write_text(" ".join(map(str, result.hits)))
        result.write(path.with_suffix(".json"))
        return path

    Tally.EXPORTS = {".txt": export}
    Tally.COMPANIONS = {".txt": lambda path: path.with_suffix(".json")}
    yield Tally
    del KINDS["tally"]  # the test's kind leaves the registry as it found it


def test_a_record_is_a_kind_written_and_read_in_every_format(tally, tmp_path):
    result = tally(np.array([10, 20]), np.array([3, 20]), 0.05)
    assert KINDS["tally"] is tally and result.delta == 0.05 and result.dims == ("cell",)
    dataset = result.to_dataset()
    assert dataset["hits"].attrs == {"units": "1", "long_name": "hits"} and dataset.attrs["format"] == tally.FORMAT
    for suffix in (".nc", ".json", ".txt"):
        back = vm.read_result(result.write(tmp_path / f"tally{suffix}"))
        assert type(back) is tally and back.as_dict() == result.as_dict()
    assert (tmp_path / "tally.txt").read_text() == "3 20"
    with pytest.raises(ValueError, match="a tally is written as .nc, .json, .txt"):
        result.write(tmp_path / "tally.csv")
    with pytest.raises(AttributeError, match="cannot assign to field .rays."):  # frozen, as every result
        result.rays = np.array([1, 1])


def test_a_record_s_counts_are_checked_and_an_edited_value_refused(tally, tmp_path):
    path = tmp_path / "tally.json"
    path.write_text(json.dumps({"format": "virtspec-mi tally 1", "rays": [10, 20], "hits": [11, 2], "delta": 0.05}))
    with pytest.raises(ValueError, match=r"'hits' holds a count above 'rays' \(cell cell=0\)"):
        vm.read_result(path)
    path.write_text(json.dumps({"format": "virtspec-mi tally 1", "rays": [10, 2.5], "hits": [1, 2], "delta": 0.05}))
    with pytest.raises(ValueError, match="'rays' holds 2.5 at index \\[1\\], not a whole number"):
        vm.read_result(path)
    import xarray as xr

    tally(np.array([10, 20]), np.array([3, 20]), 0.05).write(tmp_path / "tally.nc")
    with xr.open_dataset(tmp_path / "tally.nc") as opened:
        dataset = opened.load()
    dataset.attrs["delta"] = 0.5
    dataset.to_netcdf(tmp_path / "edited.nc")
    with pytest.raises(ValueError, match="the attribute 'delta' holds '0.5' where the result the file holds gives "
                                         "'0.05'"):
        vm.read_result(tmp_path / "edited.nc")


def test_check_record_names_the_group_and_the_cell(tally):
    with pytest.raises(ValueError, match="'hits' holds a count above 'rays' \\(cell cell=1\\)"):
        check_record(tally(np.array([10, 20]), np.array([3, 21]), 0.05))


def test_plain_floats_and_recorded_data():
    assert plain_floats([[1.0, np.nan], [np.inf, 2.0]]) == [[1.0, None], [None, 2.0]]
    assert plain_floats(np.float64(np.nan)) is None
    target = RecordedData({"kind": "band", "tolerance": 0.05}, "reflectance in band B04")
    assert target.kind == "band" and target.as_dict() == {"kind": "band", "tolerance": 0.05}
    assert target.describe() == "reflectance in band B04"
    with pytest.raises(AttributeError):
        target.missing
