"""
Tests of :mod:`virtspec_mi.applications.tables` (its ``__init__``): the application's row.

It declares ``virtspec albedo-table`` and registers the albedo table and the table comparison
as result kinds; its example's API call and command line ask for the same table. The example
is run by the contract test (``tests/applications/test_applications.py``).
"""

from __future__ import annotations

from virtspec_mi.applications import APPLICATIONS
from virtspec_mi.applications.tables import TablesApplication
from virtspec_mi.applications.tables.table import AlbedoTable, TableComparison
from virtspec_mi.results.kinds import kind_of


def test_the_row_declares_its_command_and_results():
    assert APPLICATIONS["tables"] is TablesApplication
    assert [command.name for command in TablesApplication.commands] == ["albedo-table"]
    assert TablesApplication.results == (AlbedoTable, TableComparison)
    for kind in TablesApplication.results:
        assert kind_of(kind.FORMAT) is kind


def test_the_example_reads_back_what_it_measures(mi, tmp_path):
    table = TablesApplication.example["api"](tmp_path)
    assert table.mu.tolist() == [1.0, 0.5] and table.alpha.tolist() == [0.3] and table.E_avg is None
    path = table.write(tmp_path / "E.nc")
    back = TablesApplication.example["read"](path)
    assert (back.counts["rays"] == table.counts["rays"]).all()
