"""Tests of virtspec_mi.budgets.scores: the empirical Bernstein interval of bounded scores (Maurer & Pontil 2009)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.budgets.scores import score_half_width, score_interval


def test_the_interval_is_theorem_4_at_delta_over_two_each_side():
    rng = np.random.default_rng(1)
    q = rng.integers(0, 101, size=5000)  # scores q/100 in [0, 1]
    n, delta = q.size, 0.05
    lower, upper = score_interval(int(q.sum()), int((q * q).sum()), n, delta, scale=100)
    x = q / 100
    width = math.sqrt(2 * x.var(ddof=1) * math.log(4 / delta) / n) + 7 * math.log(4 / delta) / (3 * (n - 1))
    assert lower == pytest.approx(x.mean() - width, rel=1e-12) and upper == pytest.approx(x.mean() + width, rel=1e-12)
    assert score_half_width(n, x.var(ddof=1), delta) == pytest.approx(width, rel=1e-12)


def test_below_and_above_widen_the_ends_and_the_interval_stays_in_zero_one():
    lower, upper = score_interval(300, 300 * 7, 1000, 0.1, scale=7)  # every score 300/1000/7 ... consistent sums
    wide_lower, wide_upper = score_interval(300, 300 * 7, 1000, 0.1, scale=7, below=1e-3, above=2e-3)
    assert wide_lower == pytest.approx(lower - 1e-3) and wide_upper == pytest.approx(upper + 2e-3)
    assert score_interval(0, 0, 10, 0.1) == (0.0, pytest.approx(7 * math.log(40) / 27))
    assert score_interval(5, 5, 1, 0.1) == (0.0, 1.0)  # one score certifies nothing
    low, high = score_interval(10, 10, 10, 0.1)
    assert high == 1.0 and 0.0 <= low < 1.0


def test_the_variance_is_computed_from_the_exact_sums():
    """Sums beyond 2**53 (float64's integers): the variance of scores all equal to one value is 0 exactly."""

    n, scale, q = 3 * 10**9, 1 << 15, 12345
    lower, upper = score_interval(n * q, n * q * q, n, 0.01, scale=scale)
    range_term = 7 * math.log(400) / (3 * (n - 1))
    assert upper - q / scale == pytest.approx(range_term, rel=1e-6)
    assert q / scale - lower == pytest.approx(range_term, rel=1e-6)


def test_sums_that_no_scores_give_and_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="not those of 10 scores"):
        score_interval(11, 11, 10, 0.1)  # a mean above 1
    with pytest.raises(ValueError, match="not those of 10 scores"):
        score_interval(5, 1, 10, 0.1)  # squares below what the total implies
    with pytest.raises(ValueError, match="whole numbers"):
        score_interval(0.5, 1, 10, 0.1)
    with pytest.raises(ValueError, match="delta"):
        score_interval(1, 1, 10, 1.5)
    with pytest.raises(ValueError, match="scale"):
        score_interval(1, 1, 10, 0.1, scale=0)
    with pytest.raises(ValueError, match="below"):
        score_interval(1, 1, 10, 0.1, below=-1.0)


@pytest.mark.parametrize("shape", [(0.3, 8.0), (2.0, 2.0), (0.05, 0.05)])
def test_coverage_at_delta_02_over_many_samples(shape):
    """Beta-distributed scores (skewed, symmetric, U-shaped): the interval at δ = 0.2 holds the mean in at least
    80 % of 400 samples (it is conservative: far more); a miss count above the binomial's 1e-6 quantile fails."""

    from scipy import stats

    a, b = shape
    mean, delta, scale, n, trials = a / (a + b), 0.2, 1 << 15, 400, 400
    rng = np.random.default_rng(7)
    x = rng.beta(a, b, size=(trials, n))
    q = np.floor(x * scale + rng.random(x.shape)).astype(np.int64)  # stochastic rounding keeps the mean
    lower, upper = score_interval(q.sum(axis=1), (q * q).sum(axis=1), n, delta, scale=scale)
    misses = int(np.sum((mean < lower) | (mean > upper)))
    assert misses <= stats.binom.ppf(1 - 1e-6, trials, delta)
    assert np.all(lower <= upper)
