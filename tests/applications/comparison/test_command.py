"""
Tests of :mod:`virtspec_mi.applications.comparison.command`: ``virtspec compare``, declared.

The command's flags read back (``--sel`` only as NAME=VALUE); ``virtspec compare RESULT MEASURED
--json`` prints the comparison the API gives, as a file :func:`virtspec_mi.read_result` reads; a
bad figure path is refused before any work; the row declares the
command and the comparison's result kind.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications import APPLICATIONS
from virtspec_mi.applications.comparison.command import COMPARE, ComparisonApplication, CompareFlags, _inputs, _api
from virtspec_mi.applications.comparison.result import Comparison
from virtspec_mi.cli import main


@pytest.fixture(scope="module")
def folder(mi, tmp_path_factory):
    made = tmp_path_factory.mktemp("compare")
    _inputs(made)
    return made


def test_selections_are_name_value_pairs():
    check = {name: item.metadata["check"] for name, item in CompareFlags.__dataclass_fields__.items()
             if item.metadata}["selections"]
    assert check(["theta_i=8", "wavelength=550"]) == ("theta_i=8", "wavelength=550")
    with pytest.raises(ValueError, match=r"--sel takes NAME=VALUE \(got 'theta_i'\)"):
        check(["theta_i"])


def test_the_command_prints_the_apis_comparison(folder, capsys):
    assert main(["compare", str(folder / "r.nc"), str(folder / "m.csv"), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    expected = _api(folder)
    np.testing.assert_allclose(printed["residuals"], expected.residuals)
    path = folder / "printed.json"
    path.write_text(json.dumps(printed))
    back = vm.read_result(path)
    assert isinstance(back, Comparison) and back.result_name == "r.nc"
    np.testing.assert_array_equal(back.within, expected.within)


def test_a_bad_figure_is_refused_before_any_work(folder, capsys):
    assert main(["compare", str(folder / "r.nc"), str(folder / "m.csv"), "--plot", str(folder / "figure.txt")]) == 1
    assert "plot must end in one of" in capsys.readouterr().err
    assert not (folder / "figure.txt").exists()


def test_the_row():
    assert APPLICATIONS["comparison"] is ComparisonApplication
    assert ComparisonApplication.commands == (COMPARE,) and COMPARE.name == "compare"
    assert ComparisonApplication.results == (Comparison,)
