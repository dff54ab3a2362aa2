"""Tests of the cheaper search of a fit (virtspec_mi/applications/fitting/search.py and its use in vm.fit).

The specimen is PROSPECT-D, whose model makes the synthetic measurement (as in test_fitting.py).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.fitting.forward import Reading
from virtspec_mi.applications.fitting.inversion import LOSSES, verdicts
from virtspec_mi.applications.fitting.search import search_problem, table_start
from virtspec_mi.plugins.bsdfs.prospect_model import prospect_d

WAVELENGTHS = np.arange(450.0, 2451.0, 40.0)  # 51 wavelengths
FAST = dict(evaluations=(8, 4, 2), profile_points=3, table_points=5, theta_i=8.0, beam="collimated", delta=0.1)


@dataclasses.dataclass(frozen=True)
class _Problem:
    """What the losses and the search need of a problem: the measurement on its wavelengths."""

    wavelengths: np.ndarray
    measured: dict
    uncertainty: dict

    @property
    def quantities(self) -> tuple:
        return tuple(self.measured)


def test_the_table_interpolated_starts_between_its_nodes():
    # a table of PROSPECT-D spectra (exact, no rays) on a 5 x 5 grid; the measurement between the nodes
    wavelengths = np.array([550.0, 700.0, 1450.0, 2200.0])
    cab, cm = np.linspace(10, 90, 5), np.linspace(0.002, 0.02, 5)
    readings = []
    for a in cab:
        for b in cm:
            r, t = prospect_d(wavelengths, Cab=a, Cm=b)
            readings.append(Reading(values=np.array([a, b]), mu=0.02, predicted={"reflectance": r, "transmittance": t},
                                    tolerance={}, rays=1, stage="table"))
    r, t = prospect_d(wavelengths, Cab=43.0, Cm=0.0087)
    problem = _Problem(wavelengths, {"reflectance": r, "transmittance": t},
                       {"reflectance": np.full(4, 0.01), "transmittance": np.full(4, 0.01)})
    start = table_start(readings, problem, LOSSES["chi2"])
    node = min(readings, key=lambda reading: LOSSES["chi2"](reading, problem)).values
    assert abs(start[0] - 43.0) < abs(node[0] - 43.0) and abs(start[0] - 43.0) < 4.0, (start, node)
    assert abs(start[1] - 0.0087) < 0.0012, start
    # not a full grid: the best node
    np.testing.assert_array_equal(table_start(readings[:-1], problem, LOSSES["chi2"]),
                                  min(readings[:-1], key=lambda reading: LOSSES["chi2"](reading, problem)).values)


def test_the_search_wavelengths_are_spread_and_keep_the_windows():
    measured = synthetic({"Cab": 40.0}, 0.02, seed=0)
    problem = vm.applications.fitting.problem.fit_problem(measured, "prospect_d", {"Cab": (10, 80)})
    keep = (problem.wavelengths >= 690) & (problem.wavelengths <= 730)
    sub, mask = search_problem(problem, 8, keep)
    assert sub.wavelengths[0] == 450.0 and sub.wavelengths[-1] == 2450.0
    assert set(problem.wavelengths[keep]) <= set(sub.wavelengths) and 8 <= len(sub.wavelengths) <= 9
    np.testing.assert_array_equal(sub.measured["reflectance"], problem.measured["reflectance"][mask])
    assert search_problem(problem, 51, None) is None and search_problem(problem, None, None) is None


def test_the_search_wavelengths_are_where_each_parameter_changes_the_table():
    # a 3 x 3 table over two parameters on 40 wavelengths: the first changes R only at 1000 nm, the second only
    # at 2000 nm (and T nowhere); 6 search wavelengths: 2 evenly spread (the ends), 2 per parameter
    wavelengths = np.linspace(450.0, 2400.0, 40)
    at_1000, at_2000 = np.argmin(np.abs(wavelengths - 1000)), np.argmin(np.abs(wavelengths - 2000))
    readings = []
    for a in (0.0, 1.0, 2.0):
        for b in (0.0, 1.0, 2.0):
            r = np.full(40, 0.3)
            r[at_1000] += 0.05 * a
            r[at_2000] += 0.03 * b
            readings.append(Reading(values=np.array([a, b]), mu=0.02, predicted={"reflectance": r,
                                                                                  "transmittance": np.full(40, 0.4)},
                                    tolerance={}, rays=1, stage="table"))
    problem = _Problem(wavelengths, {"reflectance": np.full(40, 0.3), "transmittance": np.full(40, 0.4)},
                       {"reflectance": np.full(40, 0.01), "transmittance": np.full(40, 0.01)})
    sub, mask = search_problem(problem, 6, None, readings)
    chosen = set(np.flatnonzero(mask))
    assert {0, 39, at_1000, at_2000} <= chosen and len(chosen) == 6


def test_a_candidate_read_both_ways_is_judged_by_its_full_reading():
    def reading(mu, subset):
        return Reading(values=np.array([1.0]), mu=mu, predicted={}, tolerance={}, rays=1, stage="",
                       subset=None if not subset else np.array([True, False]))

    readings = [reading(0.01, True), reading(0.01, False), reading(0.005, True)]
    # at 0.01 the full reading (inconsistent) wins over the subset's; a finer subset reading wins over both
    np.testing.assert_array_equal(verdicts(readings[:2], np.array([0.5, 1.5])), [False, False])
    np.testing.assert_array_equal(verdicts(readings, np.array([0.5, 1.5, 0.9])), [True, True, True])


def synthetic(truth: dict, u: float, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    reflectance, transmittance = prospect_d(WAVELENGTHS, **truth)
    n = len(WAVELENGTHS)
    return {"reflectance": (WAVELENGTHS, reflectance + rng.uniform(-u, u, n), np.full(n, u)),
            "transmittance": (WAVELENGTHS, transmittance + rng.uniform(-u, u, n), np.full(n, u))}


def test_a_fit_searches_on_fewer_wavelengths_and_reads_its_estimate_on_all(tmp_path):
    truth = {"Cab": 47.0, "Cm": 0.011}
    measured = synthetic(truth, 0.02, seed=8)
    free = {"Cab": (10, 90), "Cm": (0.002, 0.02)}
    options = dict(FAST, profile_points=0)  # the profiles read every wavelength: here only the search differs
    fewer = vm.fit(measured, "prospect_d", free, search_wavelengths=12, seed=3, **options)
    every = vm.fit(measured, "prospect_d", free, search_wavelengths=None, seed=3, **options)
    assert fewer.search_wavelengths == 12 and every.search_wavelengths == 0
    assert any(stage == "refine 1 (12 wavelengths)" for stage in fewer.candidate_stage)
    assert "estimate" in fewer.candidate_stage and "estimate" not in every.candidate_stage
    assert "the search and confirmation on 12 of the wavelengths" in fewer.summary()
    for result in (fewer, every):
        assert result.consistent and result.statistic <= 1.0
        assert len(result.fitted["reflectance"]) == len(WAVELENGTHS)  # the estimate: every wavelength, at mu*
        assert result.forward_tolerance <= result.forward_mu + 1e-12
        for i, name in enumerate(result.names):
            assert result.intervals[i, 0] <= truth[name] <= result.intervals[i, 1], (name, result.intervals)
    assert fewer.rays < 0.8 * every.rays  # the search is cheaper (the table and the estimate read every wavelength)
    for name in ("fit.json", "fit.nc"):
        assert vm.read_fit(fewer.write(tmp_path / name)).search_wavelengths == 12
    with pytest.raises(ValueError, match="search_wavelengths must be None"):
        vm.fit(measured, "prospect_d", free, search_wavelengths=1)


@pytest.mark.slow
def test_confidence_sets_searched_on_fewer_wavelengths_cover_the_truth():
    """
    Coverage with the search on 12 of 51 wavelengths: over T seeded round trips with random true
    leaves, the confidence sets missing the truth are Binomial(T, p) with p <= delta; the test fails
    when they exceed the binomial's 0.999 quantile at p = delta. Power: a planted bias of 2.5 u on
    the reflectance is flagged inconsistent in most trials.
    """

    from scipy.stats import binom

    trials, delta = 10, 0.1
    rng = np.random.default_rng(31)
    misses, flagged = 0, 0
    bounds = {"Cab": (10, 90), "Cm": (0.002, 0.02)}
    for trial in range(trials):
        truth = {"Cab": float(rng.uniform(15, 85)), "Cm": float(rng.uniform(0.003, 0.018))}
        result = vm.fit(synthetic(truth, 0.02, seed=300 + trial), "prospect_d", bounds, search_wavelengths=12,
                        seed=trial, **FAST)
        misses += not (result.consistent and all(result.intervals[i, 0] <= truth[name] <= result.intervals[i, 1]
                                                 for i, name in enumerate(result.names)))
        biased = synthetic(truth, 0.02, seed=400 + trial)
        w, r, u = biased["reflectance"]
        biased["reflectance"] = (w, r + 0.05, u)
        flagged += not vm.fit(biased, "prospect_d", bounds, search_wavelengths=12, seed=trial, **FAST).consistent
    assert misses <= binom.ppf(0.999, trials, delta), misses
    assert flagged >= trials - 2, flagged
