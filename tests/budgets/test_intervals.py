"""Tests of virtspec_mi.budgets.intervals: the Clopper-Pearson interval."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from virtspec_mi.budgets.intervals import clopper_pearson


def test_closed_forms_at_the_ends():
    # k = 0: upper = 1 - (delta/2)^(1/n); k = n: lower = (delta/2)^(1/n)
    n, delta = 2000, 0.001
    lower, upper = clopper_pearson(0, n, delta)
    assert lower == 0.0 and upper == pytest.approx(1 - (delta / 2) ** (1 / n), rel=1e-10)
    lower, upper = clopper_pearson(n, n, delta)
    assert upper == 1.0 and lower == pytest.approx((delta / 2) ** (1 / n), rel=1e-10)


def test_tails_are_delta_over_two():
    k, n, delta = 37, 200, 0.05
    lower, upper = clopper_pearson(k, n, delta)
    assert stats.binom.sf(k - 1, n, lower) == pytest.approx(delta / 2, rel=1e-8)  # P(X >= k | lower)
    assert stats.binom.cdf(k, n, upper) == pytest.approx(delta / 2, rel=1e-8)  # P(X <= k | upper)


@pytest.mark.parametrize("p", [0.0, 0.01, 0.1, 0.3, 0.5, 0.77, 1.0])
def test_exact_coverage_at_least_one_minus_delta(p):
    n, delta = 60, 0.1
    k = np.arange(n + 1)
    lower, upper = clopper_pearson(k, n, delta)
    covered = (lower <= p) & (p <= upper)
    assert stats.binom.pmf(k, n, p)[covered].sum() >= 1 - delta - 1e-12


def test_vectorised_and_broadcast():
    lower, upper = clopper_pearson([[0, 5], [10, 20]], 20, 0.01)
    assert lower.shape == upper.shape == (2, 2)
    assert np.all(lower <= np.array([[0, 5], [10, 20]]) / 20) and np.all(upper >= np.array([[0, 5], [10, 20]]) / 20)
    assert np.all(np.diff(clopper_pearson(np.arange(21), 20, 0.01)[0]) > 0)


@pytest.mark.parametrize("k, n, delta, message", [
    (5, 4, 0.1, "0 <= k <= n"), (-1, 4, 0.1, "0 <= k <= n"), (1.5, 4, 0.1, "whole counts"),
    (0, 0, 0.1, "n >= 1"), (1, 4, 0.0, "delta must satisfy 0 < delta < 1"),
])
def test_bad_input(k, n, delta, message):
    with pytest.raises(ValueError, match=message):
        clopper_pearson(k, n, delta)
