"""
Tests of :mod:`virtspec_mi.applications.tables.comparison`: a published table held to a certified one.

A table compared with its own values flags nothing; values moved by more than the certified
tolerance (plus the stated rounding) in chosen cells flag exactly those cells, with their
coordinates, the published and certified values; the comparison is a result kind whose
files read back as the same comparison, and an edited list of flagged cells is refused.

References
----------
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.tables.comparison import TableComparison


@pytest.fixture(scope="module")
def table(mi):
    from virtspec_mi.applications.tables.albedo import albedo_table

    return albedo_table("conductor", engine=None, mu=[1.0, 0.5, 0.2], alpha=[0.3, 0.8], epsilon=0.05, seed=7,
                        progress=False)


def test_the_tables_own_values_flag_nothing(table):
    comparison = table.compare(table.layout())
    assert isinstance(comparison, TableComparison)
    assert comparison.outside == [] and comparison.cells == 6 and comparison.share_outside == 0.0
    assert comparison.summary().startswith("E: 0 of 6 published cells outside the certified interval")


def test_moved_cells_are_flagged_exactly(table):
    published = table.layout().copy()
    published[0, 1] += 0.2  # beyond epsilon = 0.05
    published[2, 0] -= 0.049  # within it
    comparison = table.compare(published)
    assert [cell["index"] for cell in comparison.outside] == [(0, 1)]
    cell = comparison.outside[0]
    assert (cell["mu"], cell["alpha"]) == (1.0, 0.8)
    assert cell["published"] == pytest.approx(table.E[0, 1] + 0.2) and cell["certified"] == table.E[0, 1]
    assert cell["tolerance"] == pytest.approx(table.certified_epsilon()[0, 1])
    assert comparison.share_outside == pytest.approx(1 / 6)
    assert comparison.summary().splitlines()[0].startswith("E: 1 of 6 published cells outside")
    rounded = table.compare(published, rounding=0.2)  # a published value can not be held to more than its digits
    assert rounded.outside == []


def test_the_average_and_the_refusals(table):
    averaged = table.compare(table.E_avg + np.array([0.0, 0.3]), average=True)
    assert [cell["index"] for cell in averaged.outside] == [(1,)] and averaged.summary().startswith("E_avg: 1 of 2")
    with pytest.raises(ValueError, match=r"side='inside' names a glass table's block"):
        table.compare(table.layout(), side="inside")
    with pytest.raises(ValueError, match=r"rounding must be a finite number >= 0 \(got -1\)"):
        table.compare(table.layout(), rounding=-1)


def test_the_comparison_reads_back_and_refuses_an_edited_list(table, tmp_path):
    published = table.layout().copy()
    published[1, 1] = 0.0
    comparison = table.compare(published)
    path = comparison.write(tmp_path / "comparison.json")
    back = vm.read_result(path)
    assert isinstance(back, TableComparison) and back.outside == comparison.outside
    np.testing.assert_array_equal(back.published, published)
    dataset = comparison.to_dataset()
    assert int(dataset["flagged"].sum()) == 1 and int(dataset["flagged"][1, 1]) == 1
    data = json.loads(path.read_text())
    data["outside"] = []
    data.pop("checksum", None)
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"'outside' disagrees with the table and the published values the file holds "
                                         r"\(edited\?\)"):
        vm.read_result(edited)
