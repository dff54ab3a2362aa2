"""Tests of virtspec_mi.budgets.rules: the ray-budget rules as objects (one entry per rule)."""

from __future__ import annotations

import math

import pytest

from virtspec_mi.budgets import bounds
from virtspec_mi.budgets.rules import BUDGETS
from virtspec_mi.settings import Settings

MU, DELTA = 0.005, 0.01


def test_every_rule_is_one_entry_and_the_setting_names_them():
    assert list(BUDGETS) == ["hoeffding", "chebyshev", "exact", "two-stage"]
    assert [name for name, budget in BUDGETS.items() if budget.adaptive] == ["two-stage"]
    for name in BUDGETS:
        assert Settings(bound=name).budget is BUDGETS[name]


@pytest.mark.parametrize("name, rays", [("hoeffding", 105_967), ("chebyshev", 1_000_000), ("exact", 66_501)])
def test_a_fixed_rule_certifies_mu_at_its_rays_and_no_less(name, rays):
    budget = BUDGETS[name]
    assert budget.rays(MU, DELTA) == rays
    assert budget.certified(rays, DELTA, MU) <= MU
    fewer = budget.certified(rays // 10, DELTA, MU)
    assert fewer > MU and fewer == budget.tolerance(rays // 10, DELTA)
    assert Settings(bound=name).most_rays_per_reading == rays


def test_closed_form_tolerances_are_the_paper_inverses():
    assert BUDGETS["hoeffding"].tolerance(1000, DELTA) == pytest.approx(math.sqrt(math.log(2 / DELTA) / 2000))
    assert BUDGETS["chebyshev"].tolerance(1000, DELTA) == pytest.approx(1 / (2 * math.sqrt(1000 * DELTA)))


@pytest.mark.parametrize("rays", [1, 50, 1000, 20_000])
def test_exact_tolerance_is_the_smallest_certified_mu(rays):
    mu = bounds.exact_mu(rays, DELTA)
    assert mu <= bounds.hoeffding_mu(rays, DELTA)
    if mu < 0.5:
        assert bounds.max_miss_probability(rays, mu) <= DELTA
        assert bounds.max_miss_probability(rays, mu * (1 - 1e-4)) > DELTA


def test_exact_tolerance_above_the_bisection_size_is_hoeffding_but_mu_when_the_rule_sized_it():
    assert bounds.exact_mu(100_000, DELTA) == bounds.hoeffding_mu(100_000, DELTA)
    assert BUDGETS["exact"].certified(66_501, DELTA, MU) == MU


def test_two_stage_sizes_from_a_pilot_and_reserves_its_largest_spend():
    budget = BUDGETS["two-stage"]
    with pytest.raises(ValueError, match="sizes each reading from a pilot"):
        budget.rays(MU, DELTA)
    settings = Settings(bound="two-stage")
    assert settings.adaptive and settings.pilot_rays_per_reading == 2000
    assert settings.most_rays_per_reading == bounds.hoeffding_rays(MU, DELTA - DELTA / 10)
    assert budget.tolerance(1000, DELTA) == bounds.exact_mu(1000, DELTA)
    assert not Settings(bound="two-stage", rays=1000).adaptive
