"""Tests of virtspec_mi.budgets.bounds: eqs. (15), (23), inverses, Table 1, exact miss probability."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from virtspec_mi.budgets import bounds
from virtspec_mi.budgets.rules import BUDGETS
from virtspec_mi.settings import Settings


def test_hoeffding_rays_paper_value():
    # eq. (23): ln(2/0.01) / (2 * 0.005**2) = 105,966.3... -> 105,967, i.e. 10**5.025
    assert bounds.hoeffding_rays(0.005, 0.01) == 105_967
    assert math.log10(bounds.hoeffding_rays(0.005, 0.01)) == pytest.approx(5.0252, abs=1e-4)


def test_chebyshev_rays_paper_value():
    # eq. (15): 1 / (4 mu^2 delta), exact powers of ten for Table 1
    assert bounds.chebyshev_rays(0.005, 0.001) == 10_000_000
    assert bounds.chebyshev_rays(0.005, 0.01) == 1_000_000
    assert bounds.chebyshev_rays(0.005, 0.1) == 100_000


@pytest.mark.parametrize("mu", [0.001, 0.005, 0.02, 0.1])
@pytest.mark.parametrize("delta", [1e-6, 0.001, 0.01, 0.2])
def test_inverses_round_trip(mu, delta):
    n = bounds.hoeffding_rays(mu, delta)
    # N rays guarantee at least mu; one ray fewer would not.
    assert bounds.hoeffding_mu(n, delta) <= mu
    assert bounds.hoeffding_mu(n - 1, delta) > mu if n > 1 else True
    n = bounds.chebyshev_rays(mu, delta)
    assert bounds.chebyshev_mu(n, delta) <= mu * (1 + 1e-12)


def test_hoeffding_tighter_than_chebyshev_as_delta_shrinks():
    # eq. (21): k_c / k_e -> infinity as delta -> 0
    ratios = [bounds.chebyshev_rays(0.005, d) / bounds.hoeffding_rays(0.005, d) for d in (0.1, 0.01, 1e-4)]
    assert ratios == sorted(ratios) and ratios[-1] > 100


def test_table_1_true_log10_and_truncation_note():
    rows = {row.delta: row for row in bounds.table_1()}
    assert f"{rows[0.001].hoeffding_log10:.2f}" == "5.18"
    assert f"{rows[0.01].hoeffding_log10:.2f}" == "5.03"  # the paper truncates to 5.02
    assert f"{rows[0.1].hoeffding_log10:.2f}" == "4.78"  # the paper truncates to 4.77
    text = bounds.format_table_1()
    assert "105,967" in text and "paper 5.02" in text and "paper 4.77" in text
    assert "paper 5.18" not in text


def test_miss_probability_matches_brute_force_binomial():
    n, rho, mu = 461, 0.3, 0.05
    m = np.arange(n + 1)
    brute = stats.binom.pmf(m, n, rho)[np.abs(m / n - rho) >= mu - 1e-12].sum()
    assert bounds.miss_probability(n, rho, mu) == pytest.approx(brute, rel=1e-9)


def test_miss_probability_below_delta_at_certified_n():
    # The bound is conservative: at N = 105,967 the exact worst case is ~0.0011, not 0.01.
    n = bounds.hoeffding_rays(0.005, 0.01)
    worst = max(bounds.miss_probability(n, p, 0.005) for p in np.linspace(0.45, 0.55, 41))
    assert 0.0009 < worst < 0.0013
    assert bounds.miss_probability(n, 0.0, 0.005) == 0.0


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: bounds.hoeffding_rays(0.0, 0.01), "mu must satisfy 0 < mu < 0.5"),
        (lambda: bounds.hoeffding_rays(0.5, 0.01), "mu must satisfy 0 < mu < 0.5"),
        (lambda: bounds.hoeffding_rays(0.005, 0.0), "delta must satisfy 0 < delta < 1"),
        (lambda: bounds.chebyshev_rays(0.005, 1.0), "delta must satisfy 0 < delta < 1"),
        (lambda: bounds.hoeffding_mu(0, 0.01), "rays must satisfy 1 <= rays"),
        (lambda: Settings(bound="magic"), "bound must be one of"),
        (lambda: BUDGETS["two-stage"].rays(0.005, 0.01), "sizes each reading from a pilot"),
        (lambda: bounds.exact_rays(0.005, 1.5), "delta must satisfy 0 < delta < 1"),
        (lambda: bounds.max_miss_probability(100, 0.05, 0.6, 0.4), "lo and hi must satisfy"),
    ],
)
def test_bad_input_names_parameter_and_range(call, message):
    with pytest.raises(ValueError, match=message):
        call()


# --- the exact binomial rule ----------------------------------------------------------


def test_exact_rays_at_the_defaults_is_66501():
    # 66,501, 0.63x the Hoeffding rays; 66,453 ... 66,500 fail (the failure probability is not monotone in N).
    n = bounds.exact_rays(0.005, 0.01)
    assert n == 66_501 and round(n / bounds.hoeffding_rays(0.005, 0.01), 2) == 0.63
    assert bounds.max_miss_probability(n, 0.005) <= 0.01
    assert bounds.max_miss_probability(66_500, 0.005) > 0.01  # not monotone in N:
    assert bounds.max_miss_probability(66_401, 0.005) <= 0.01  # an earlier N passes


def _dense_miss(n, mu, rho):
    """Brute force: P(|m/N - rho| >= mu) from the whole pmf, for many rho at once."""

    m = np.arange(n + 1)[:, None]
    return (stats.binom.pmf(m, n, rho) * (np.abs(m / n - rho) >= mu - 1e-12)).sum(axis=0)


def test_max_miss_probability_is_the_supremum_over_rho():
    n, mu = 181, 0.05
    sup = bounds.max_miss_probability(n, mu)
    # nothing on a dense grid exceeds the lattice supremum
    assert _dense_miss(n, mu, np.linspace(0.0, 1.0, 20001)).max() <= sup + 1e-12
    # and the supremum is attained at a jump point
    jumps = np.array([a / n + mu for a in range(n)] + [b / n - mu for b in range(1, n + 1)])
    assert _dense_miss(n, mu, jumps[(jumps >= 0) & (jumps <= 1)]).max() == pytest.approx(sup, rel=1e-9)
    # on a sub-interval, likewise
    lo, hi = 0.1, 0.3
    sub = bounds.max_miss_probability(n, mu, lo, hi)
    assert _dense_miss(n, mu, np.linspace(lo, hi, 4001)).max() <= sub + 1e-12
    assert sub < sup


@pytest.mark.parametrize("mu, delta", [(0.05, 0.2), (0.1, 0.1), pytest.param(0.02, 0.05, marks=pytest.mark.slow)])
def test_exact_rays_brute_force(mu, delta):
    """The rule's N and every N up to Hoeffding's pass; N - 1 does not (so no smaller N is 'all-pass')."""

    n = bounds._exact_rays(mu, delta, 0.0, 1.0)  # computed, not the shipped table
    top = bounds.hoeffding_rays(mu, delta)
    assert all(bounds.max_miss_probability(k, mu) <= delta for k in range(n, top + 1))
    assert bounds.max_miss_probability(n - 1, mu) > delta
    assert n < top


# --- issue 12: the bounds never divide by zero, overflow or hang --------------------------------


@pytest.mark.parametrize("call, message", [
    (lambda: bounds.hoeffding_rays(1e-300, 0.01), "the hoeffding bound for mu = 1e-300, delta = 0.01 needs more than "
                                                  "1.8e308 rays"),  # ZeroDivisionError before
    (lambda: bounds.chebyshev_rays(1e-200, 1e-300), "the chebyshev bound for mu = 1e-200"),  # OverflowError before
    (lambda: bounds.exact_rays(1e-300, 0.01), "the exact bound for mu = 1e-300"),
    (lambda: bounds.max_miss_probability(2**32 - 1, 0.005), r"at most 4,000,000 are evaluated"),
])
def test_extreme_inputs_are_refused_with_the_rule_and_the_limit(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_exact_rays_falls_back_to_hoeffding_where_the_exact_law_costs_too_much():
    assert bounds.exact_rays(1e-4, 0.01) == bounds.hoeffding_rays(1e-4, 0.01)  # N ~ 2.6e8: hours before
    assert bounds.exact_rays(1e-9, 0.3) == bounds.hoeffding_rays(1e-9, 0.3)
    # a narrow pilot interval is cheap: the exact law is still evaluated
    assert bounds.exact_rays(1e-4, 0.01, 0.0, 1e-4) < bounds.hoeffding_rays(1e-4, 0.01) / 10


def test_the_certificate_of_given_rays_at_a_tiny_mu():
    for name in ("hoeffding", "chebyshev", "exact"):
        assert BUDGETS[name].certified(1000, 0.01, 1e-300) == BUDGETS[name].tolerance(1000, 0.01)
