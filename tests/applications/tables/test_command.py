"""
Tests of ``virtspec albedo-table`` (virtspec_mi/cli/tables.py): no output replaces an input or
another output, no flag is ignored beside ``--from``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from virtspec_mi.cli import main


@pytest.fixture(scope="module")
def written(mi, tmp_path_factory):
    """A coarse certified Cycles table (.nc) and its drop-in header: the 'published' table of the cases."""

    from virtspec_mi.applications.tables.engine_tables import engine_tables

    folder = tmp_path_factory.mktemp("tables")
    tables = engine_tables("cycles", epsilon=0.2, seed=0, progress=False)
    tables.write(folder / "T.nc")
    tables.write(folder / "pub.h")
    return folder


def _refused(capsys, argv, *words):
    status = main(argv)
    err = capsys.readouterr().err
    assert status == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, err
    return err


def test_the_audit_never_writes_over_the_published_table(written, capsys):
    pub, before = written / "pub.h", (written / "pub.h").read_bytes()
    _refused(capsys, ["albedo-table", "--from", str(written / "T.nc"), "--engine", "cycles", "--audit", str(pub),
                      "--out", str(pub)], f"--out {pub} is --audit {pub}")
    assert pub.read_bytes() == before


def test_the_figure_never_replaces_the_audited_file(written, capsys, tmp_path):
    png = tmp_path / "pub.png"
    png.write_bytes(b"\x89PNG published")
    _refused(capsys, ["albedo-table", "--from", str(written / "T.nc"), "--engine", "unreal", "--audit", str(png),
                      "--figure", str(png)], f"--figure {png} is --audit {png}")
    assert png.read_bytes() == b"\x89PNG published"


def test_an_output_never_replaces_the_table_read(written, capsys, tmp_path):
    source = tmp_path / "T.nc"
    source.write_bytes((written / "T.nc").read_bytes())
    _refused(capsys, ["albedo-table", "--from", str(source), "--out", str(source)], f"--out {source} is --from")
    _refused(capsys, ["albedo-table", "--from", str(source), "--out", str(tmp_path / "a.h"), str(tmp_path / "a.h")],
             "one output would replace the other")


def test_a_companion_json_of_the_users_own_is_not_replaced(written, capsys, tmp_path):
    mine = tmp_path / "E.h.json"
    mine.write_text('{"my": "notes"}')
    _refused(capsys, ["albedo-table", "--from", str(written / "T.nc"), "--engine", "cycles", "--audit",
                      str(written / "pub.h"), "--out", str(tmp_path / "E.h")],
             f"companion file {mine} already exists", "--overwrite")
    assert json.loads(mine.read_text()) == {"my": "notes"} and not (tmp_path / "E.h").exists()


def test_engine_beside_from_must_be_the_tables_own(written, capsys):
    _refused(capsys, ["albedo-table", "--from", str(written / "T.nc"), "--engine", "filament"],
             "--engine filament: the table of --from", "cycles's grid")
    assert main(["albedo-table", "--from", str(written / "T.nc"), "--engine", "cycles"]) == 0


@pytest.mark.parametrize("flags, named", [(["--epsilon", "0.01"], "--epsilon"),
                                          (["--cosines", "1", "0.5"], "--cosines"),
                                          (["--model", "glass"], "--model"), (["--seed", "3"], "--seed")])
def test_measuring_flags_beside_from_are_refused(written, capsys, flags, named):
    _refused(capsys, ["albedo-table", "--from", str(written / "T.nc"), *flags], named, "--from TABLE reads a table")


def test_the_figure_needs_an_audit(written, capsys, tmp_path):
    _refused(capsys, ["albedo-table", "--from", str(written / "T.nc"), "--engine", "cycles", "--out",
                      str(tmp_path / "x.h"), "--figure", str(tmp_path / "f.png")], "--figure draws the heat map")


def test_the_summary_names_the_grid_as_given(mi, capsys):
    """A grid of the user's cells is "grid (mu 2 x alpha 2)", an engine's is "cycles grid (...)" (never "grid grid")."""

    assert main(["albedo-table", "--cosines", "1,0.5", "--alpha", "0.3,0.6", "--epsilon", "0.3", "--quiet"]) == 0
    shown = "".join(capsys.readouterr())
    assert "; grid (mu 2 x alpha 2)" in shown and "grid grid" not in shown, shown
