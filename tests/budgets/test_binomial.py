"""Ray budgets of many cells (virtspec_mi.budgets.binomial): each rule against the exact binomial law."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import ndtr
from scipy.stats import binom

from virtspec_mi.budgets.bounds import max_miss_probability
from virtspec_mi.budgets.intervals import clopper_pearson_each
from virtspec_mi.budgets.binomial import (bernoulli_kl, binomial_rays, chernoff_rays,
                                         stage_two_shares, union_hoeffding_rays, upper_exponent)
from virtspec_mi.budgets.intervals import clopper_pearson


def test_zubkov_serov_bounds_hold_for_the_exact_binomial_law():
    """The theorem the two-stage rule rests on, checked against scipy's binomial CDF."""

    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(3000):
        n = int(rng.integers(1, 4000))
        p = float(rng.uniform(0.001, 0.999))
        k = int(rng.integers(0, n))
        cdf = binom.cdf(k, n, p)
        if cdf < 1e-250:  # below what float64 holds: nothing to compare
            continue
        lower = ndtr(np.sign(k / n - p) * np.sqrt(2 * n * bernoulli_kl(k / n, p)))
        upper = ndtr(np.sign((k + 1) / n - p) * np.sqrt(2 * n * bernoulli_kl((k + 1) / n, p)))
        assert lower <= cdf * (1 + 1e-9) and cdf <= upper * (1 + 1e-9), (n, k, p)
        checked += 1
    assert checked > 2000


@pytest.mark.parametrize("lo, hi, eps, delta", [(0.0, 1.0, 0.02, 0.01), (0.1, 0.3, 0.01, 1e-3), (0.9, 1.0, 0.01, 1e-4),
                                                (0.0, 0.02, 0.005, 1e-3), (0.97, 1.0, 0.003, 1e-2)])
def test_binomial_rays_certify_every_p_of_the_interval(lo, hi, eps, delta):
    n = int(binomial_rays(lo, hi, eps, delta))
    assert max_miss_probability(n, eps, lo, hi) <= delta
    assert max_miss_probability(n + 17, eps, lo, hi) <= delta  # and larger N (periods of the lattice)
    # not wasteful: within 15 % of the exact rule's N where the exact rule is cheap to find
    smaller = int(n * 0.85)
    assert max_miss_probability(smaller, eps, lo, hi) > delta * 0.5 or smaller < 1 / eps


def test_binomial_rays_never_exceed_hoeffding_and_beat_it_near_the_ends():
    hoeffding = union_hoeffding_rays(1e-3, 1e-5, 1)
    assert int(binomial_rays(0.0, 1.0, 1e-3, 1e-5)) <= hoeffding
    assert int(binomial_rays(0.99, 1.0, 1e-3, 1e-5)) < 0.05 * hoeffding
    assert int(binomial_rays(0.45, 0.55, 1e-3, 1e-5)) < int(chernoff_rays(0.45, 0.55, 1e-3, 1e-5))


def test_upper_exponent_is_the_minimum_over_the_interval():
    p = np.linspace(1e-6, 1 - 2e-3, 400001)
    kl = bernoulli_kl(p + 2e-3, p)
    for lo, hi in ((0.1, 0.2), (0.4, 0.6), (0.0, 0.3), (0.7, 0.95)):
        inside = (p >= lo) & (p <= hi)
        assert upper_exponent(lo, hi, 2e-3) <= kl[inside].min() * (1 + 1e-9)
        assert upper_exponent(lo, hi, 2e-3) >= kl[inside].min() * (1 - 1e-4)
    assert np.isinf(upper_exponent(0.9995, 1.0, 1e-3))  # p + ε > 1: the upper tail cannot happen


def test_shares_add_up_and_follow_the_variance():
    lo = np.array([[0.0, 0.45], [0.98, 0.3]])
    hi = np.array([[0.01, 0.55], [1.0, 0.4]])
    shares = stage_two_shares({"a": [(lo, hi)], "b": [(lo[:1], hi[:1]), (lo[1:], hi[1:])]}, 0.009)
    total = shares["a"].sum() + 2 * shares["b"].sum()
    assert total == pytest.approx(0.009, rel=1e-12)
    assert shares["a"][0, 1] > shares["a"][0, 0]  # the cell near 1/2 gets the larger share


def test_clopper_pearson_each_is_clopper_pearson_per_delta():
    k, n = np.array([0, 5, 999, 1000]), np.array([1000, 1000, 1000, 1000])
    deltas = np.array([1e-3, 1e-4, 0.05, 0.2])
    lower, upper = clopper_pearson_each(k, n, deltas)
    for i in range(4):
        lo, hi = clopper_pearson(k[i], n[i], deltas[i])
        assert lower[i] == pytest.approx(float(lo), abs=1e-15) and upper[i] == pytest.approx(float(hi), abs=1e-15)
    with pytest.raises(ValueError):
        clopper_pearson_each(k, n, np.array([0.0, 0.1, 0.1, 0.1]))


def test_bad_input_names_the_parameter():
    with pytest.raises(ValueError, match="mu"):
        binomial_rays(0.1, 0.2, 0.7, 0.01)
    with pytest.raises(ValueError, match="delta"):
        binomial_rays(0.1, 0.2, 0.01, 1.5)
    with pytest.raises(ValueError, match="statements"):
        union_hoeffding_rays(0.01, 0.01, 0)
    with pytest.raises(ValueError, match="rays"):
        union_hoeffding_rays(1e-6, 1e-9, 10)


def test_stage_two_classes_round_up_within_a_step_and_never_past_hoeffding():
    """A table's second batches in few classes: never fewer rays than a cell needs, at most CLASS_STEP more, capped."""

    from virtspec_mi.budgets.binomial import (CLASS_STEP, stage_two_classes, table_pilot_rays,
                                              union_hoeffding_rays_array)

    need = np.array([1, 100, 1000, 1001, 1090, 5000, 10**7])
    delta = np.full(len(need), 1e-4)
    cap = union_hoeffding_rays_array(0.01, delta)
    classes = stage_two_classes(need, 0.01, delta)
    assert classes.dtype == np.int64 and np.all((classes >= np.minimum(need, cap)) & (classes <= cap))
    assert np.all(classes[need < cap] <= np.ceil(need[need < cap] * CLASS_STEP)) and classes[-1] == cap[-1]
    assert classes[2] == classes[3]  # 1000 and 1001 rays: one class (one sweep)
    assert table_pilot_rays(0.01) == 4000 and table_pilot_rays(0.003) == 13334
