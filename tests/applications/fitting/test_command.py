"""Tests of ``virtspec fit`` (virtspec_mi/applications/fitting/command.py): its outputs never replace its inputs."""

from __future__ import annotations

import os

import pytest

import virtspec_mi.applications.fitting.inversion as inversion
from measured_csv import write_measured


@pytest.fixture
def no_fit(monkeypatch):
    """A fit that would run is a failure here: every case must be refused before any reading."""

    def refuse(*args, **kwargs):
        raise AssertionError("the fit ran: the output was not checked against the inputs first")

    monkeypatch.setattr(inversion, "fit", refuse)


@pytest.mark.parametrize("flag, name", [("--out", None), ("--plot", "fit.png"), ("--table", None),
                                        ("--directory", None)])
def test_an_output_equal_to_the_measured_file_is_refused_before_any_reading(tmp_path, capsys, no_fit, flag, name):
    from virtspec_mi.cli import main

    measured = write_measured(tmp_path / "measured.json", [500, 600], [0.1, 0.2], [0.3, 0.4])
    before = measured.read_bytes()
    output = measured if name is None else tmp_path / name  # a figure's name: a link to the measured file
    if name is not None:
        os.symlink(measured, output)
    status = main(["fit", str(measured), "--specimen", "prospect_d", "--free", "Cab=10:90", flag, str(output)])
    err = capsys.readouterr().err
    assert status == 1 and f"{flag} {output} is MEASURED" in err and "Traceback" not in err
    assert measured.read_bytes() == before


def test_an_output_reaching_an_input_through_a_link_is_refused(tmp_path, capsys, no_fit):
    from virtspec_mi.cli import main

    measured = write_measured(tmp_path / "R.csv", [500, 600], [0.1, 0.2], [0.3, 0.4])
    transmittance = write_measured(tmp_path / "T.csv", [500, 600], [0.1, 0.2], [0.3, 0.4])
    os.symlink(transmittance, tmp_path / "fit.json")
    status = main(["fit", str(measured), "--transmittance", str(transmittance), "--specimen", "prospect_d",
                   "--free", "Cab=10:90", "--out", str(tmp_path / "fit.json")])
    assert status == 1 and "is --transmittance" in capsys.readouterr().err


def test_two_outputs_of_one_name_are_refused(tmp_path, capsys, no_fit):
    from virtspec_mi.cli import main

    measured = write_measured(tmp_path / "leaf.csv", [500, 600], [0.1, 0.2], [0.3, 0.4])
    status = main(["fit", str(measured), "--specimen", "prospect_d", "--free", "Cab=10:90",
                   "--table", str(tmp_path / "w"), "--directory", str(tmp_path / "w")])
    assert status == 1 and "one output would replace the other" in capsys.readouterr().err


def test_the_api_refuses_a_table_over_the_measured_file(tmp_path):
    measured = write_measured(tmp_path / "leaf.csv", [500, 600], [0.1, 0.2], [0.3, 0.4])
    with pytest.raises(ValueError, match="table .* is measured"):
        inversion.fit(str(measured), "prospect_d", {"Cab": (10, 90)}, table=measured)
