"""
Tests of :mod:`virtspec_mi.applications.fitting.result`: what a fit found, its files and their check.

:func:`intervals` carries each end of the consistent candidates' values out to the next value
tested (the bound when none), NaN when none is consistent. A small fit (the application's
example: PROSPECT-D's Cab from four measured reflectances, a second) holds what its candidates
give: the verdicts are s ≤ 1, ``consistent`` is any of them, the residuals are fitted − measured;
its files read back the same, and a file edited against its candidates (an interval tightened,
a verdict flipped) is refused naming what disagrees.

References
----------
Féret et al. (2017); Baranoski et al. (2001), eq. (23).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.fitting.result import FitResult, intervals, read_fit


def test_intervals_reach_the_next_value_tested():
    values = np.array([[10.0], [20.0], [30.0], [40.0], [50.0]])
    bounds = np.array([[0.0, 60.0]])
    consistent = np.array([False, False, True, True, False])
    np.testing.assert_array_equal(intervals(values, consistent, bounds), [[20.0, 50.0]])
    np.testing.assert_array_equal(intervals(values, np.array([True, False, False, False, True]), bounds),
                                  [[0.0, 60.0]])  # the extremes: out to the bounds
    assert np.isnan(intervals(values, np.zeros(5, dtype=bool), bounds)).all()


@pytest.fixture(scope="module")
def fit(mi, tmp_path_factory):
    from virtspec_mi.applications.fitting import FittingApplication, _inputs

    folder = tmp_path_factory.mktemp("fit")
    _inputs(folder)
    return FittingApplication.example["api"](folder)


def test_the_fit_holds_what_its_candidates_give(fit):
    assert isinstance(fit, FitResult) and fit.names == ("Cab",)
    np.testing.assert_array_equal(fit.candidate_consistent, fit.candidate_statistic <= 1.0)
    assert fit.consistent == bool(np.any(fit.candidate_consistent)) and fit.consistent_candidates > 0
    np.testing.assert_array_equal(fit.intervals, intervals(fit.candidate_values, fit.candidate_consistent, fit.bounds))
    assert fit.intervals[0, 0] <= fit.estimate[0] <= fit.intervals[0, 1]
    for quantity in fit.quantities:
        np.testing.assert_allclose(fit.residuals[quantity], fit.fitted[quantity] - fit.measured[quantity])
    assert fit.level == pytest.approx(0.8) and fit.estimates == {"Cab": float(fit.estimate[0])}
    assert fit.forward_tolerance == max(float(np.max(v)) for v in fit.fitted_tolerance.values())
    assert fit.summary().startswith("fit of ") and "Cab = " in fit.summary()
    with pytest.raises(ValueError, match=r"'N' is not a free parameter of this fit \(Cab\)"):
        fit.profile("N")


@pytest.mark.parametrize("suffix", [".json", ".nc"])
def test_files_read_back_the_same(fit, tmp_path, suffix):
    back = read_fit(fit.write(tmp_path / f"fit{suffix}"))
    np.testing.assert_array_equal(back.candidate_values, fit.candidate_values)
    np.testing.assert_array_equal(back.intervals, fit.intervals)
    assert back.rays == fit.rays and back.consistent == fit.consistent


def test_an_edited_file_is_refused(fit, tmp_path):
    data = fit.as_dict()
    data.pop("checksum", None)
    data["intervals"] = [[fit.intervals[0, 0] + 1.0, fit.intervals[0, 1]]]
    (tmp_path / "tightened.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"intervals .* disagrees with the fit's own candidates"):
        vm.read_result(tmp_path / "tightened.json")
    data = fit.as_dict()
    data.pop("checksum", None)
    data["consistent"] = not fit.consistent
    (tmp_path / "flipped.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"consistent = .* disagrees with the fit's own candidates"):
        vm.read_result(tmp_path / "flipped.json")
