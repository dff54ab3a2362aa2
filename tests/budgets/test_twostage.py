"""Tests of virtspec_mi.budgets.twostage: pilot-sized second batches and their exact law."""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.budgets import bounds
from virtspec_mi.budgets import twostage
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.settings import Settings


@pytest.mark.parametrize("rho, anchor", [(0.05, 19_393), (0.2, 50_524), (0.5, 70_401)])
def test_expected_rays_reproduce_anchors(rho, anchor):
    # The two-stage design at its defaults (2,000-ray pilot, delta1 = 0.001, exact N2): E[N] 19,393 / 50,524 /
    # 70,401, the smallest-passing-N2 figures computed independently when the rule was designed.
    # Ours sizes N2 as "N and every larger N pass" (so the max over R, T, A stays certified),
    # which is at most one period (100 rays) above the smallest passing N: within 0.5 %.
    law = twostage.two_stage_law(rho, 0.005, 0.01)  # defaults: n1 = 2000, delta1 = 0.001
    assert law.expected_rays == pytest.approx(anchor, rel=0.005)
    assert law.expected_rays == pytest.approx(law.expected_second_rays + 2000)
    assert law.miss_probability <= 0.01
    assert law.expected_rays < bounds.hoeffding_rays(0.005, 0.01) / 1.4  # the target at every rho


def test_second_stage_is_the_exact_rule_over_the_pilot_interval():
    mu, delta, n1, d1 = 0.05, 0.2, 200, 0.02
    counts = np.array([[30, 170, 0], [100, 0, 100], [0, 0, 200]])
    n2 = twostage.stage_two_rays(counts, n1, mu, delta, d1)
    for row, n in zip(counts, n2):
        expected = []
        for k in row:
            lo, hi = clopper_pearson(k, n1, d1)
            expected.append(bounds.exact_rays(mu, delta - d1, float(lo), float(hi)))
        assert n == max(expected)
        lo, hi = clopper_pearson(row[0], n1, d1)
        assert bounds.max_miss_probability(int(n), mu, float(lo), float(hi)) <= delta - d1
    # near rho = 1/2 it is the fixed exact rule at delta - delta1; near 0 far fewer rays
    assert n2[1] == bounds.exact_rays(mu, delta - d1) or n2[1] <= bounds.exact_rays(mu, delta - d1)
    assert n2[2] < n2[0] < n2[1]
    # joint: each quantity's interval at delta1/2 and sizing at (delta - delta1)/2
    joint = twostage.stage_two_rays(counts[:, :2], n1, mu, delta, d1, joint=True)
    assert np.all(joint >= n2[:, None].min())
    lo, hi = clopper_pearson(30, n1, d1 / 2)
    assert joint[0] == bounds.exact_rays(mu, (delta - d1) / 2, float(lo), float(hi))


def test_seeds_and_defaults():
    assert twostage.stage_two_seed(0) != 0
    assert twostage.stage_two_seed(twostage.stage_two_seed(123)) == 123  # a bijection of seeds
    assert 0 <= twostage.stage_two_seed(2**32 - 1) < 2**32
    assert twostage.default_pilot_rays(0.005) == 2000 and twostage.default_pilot_rays(0.05) == 200
    assert twostage.default_pilot_delta(0.01) == 0.001


@pytest.mark.parametrize("call, message", [
    # pilot_delta >= delta is refused once, where it enters (the settings; stage_two_rays takes their values)
    (lambda: Settings(mu=0.05, delta=0.2, pilot_delta=0.2, bound="two-stage"), "pilot_delta must satisfy"),
    (lambda: twostage.stage_two_rays([[11, 0, 0]], 10, 0.05, 0.2, 0.02), "pilot_counts must satisfy"),
    (lambda: twostage.two_stage_law(0.3, 0.05, 0.2, other="capped"), "other must be"),
    (lambda: twostage.two_stage_law(0.3, 0.05, 0.2, pilot_delta=0.3), "pilot_delta must satisfy"),
    (lambda: twostage.two_stage_law(0.3, 0.05, 0.2, pilot_rays=0), "pilot_rays must satisfy 1 <= pilot_rays"),
    (lambda: twostage.two_stage_law(0.3, 0.5, 0.2), "mu must satisfy 0 < mu < 0.5"),
])
def test_bad_input(call, message):
    with pytest.raises(ValueError, match=message):
        call()
