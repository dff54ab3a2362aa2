"""
Tests of virtspec_mi.applications.coverage: the coverage harness on specimens of known reflectance.

Cheap setting mu = 0.05, delta = 0.2, K = 1000 readings per (specimen, bound) in one
take_readings call. Each check is a two-sided exact binomial test of the miss count
against Binomial(K, q) at level 1e-4, so a correct instrument fails one check with
probability <= 1e-4 for a random seed (<= 2.4e-3 over the 24 checks here; the seeds
are fixed, so the outcome is deterministic). The power checks run an instrument that
silently spends half the certified rays and require the same test to reject it.
"""

from __future__ import annotations

import pytest

from virtspec_mi.applications import coverage as validation
from virtspec_mi.budgets import twostage
from virtspec_mi.settings import Settings

BOUNDS = ["hoeffding", "chebyshev", "exact", "two-stage"]
LEVEL = 1e-4


@pytest.mark.parametrize("bound", BOUNDS)
@pytest.mark.parametrize("specimen", validation.SPECIMENS, ids=lambda s: s.name)
def test_miss_count_follows_the_exact_law(specimen, bound):
    result = validation.coverage(specimen, bound, seed=11)
    assert result.passed(LEVEL), result
    assert result.within_delta
    if specimen.reflectance == 0.0:
        assert result.misses == 0 and result.miss_probability == 0.0
    else:
        assert result.miss_probability * result.readings > 2  # the test has something to detect


@pytest.mark.parametrize("bound", ["exact", "two-stage"])
def test_joint_certification_passes(bound):
    specimen = validation.SPECIMENS[2]  # diamond at 80 deg: R = 0.43, the hardest
    result = validation.coverage(specimen, bound, seed=12, joint=True)
    assert result.passed(LEVEL), result
    assert result.miss_probability <= 0.2 / 2 + 1e-12 or bound == "two-stage"
    assert result.rays > validation.coverage(specimen, bound, seed=12).rays  # delta/2 costs rays


@pytest.mark.parametrize("bound", BOUNDS)
def test_harness_detects_half_the_rays(monkeypatch, bound):
    specimen = validation.SPECIMENS[2]  # diamond at 80 deg
    if bound == "two-stage":
        full = twostage.stage_two_rays
        monkeypatch.setattr(twostage, "stage_two_rays", lambda *a, **k: full(*a, **k) // 2)
    else:
        full = Settings.rays_per_reading
        monkeypatch.setattr(Settings, "rays_per_reading", property(lambda s: full.fget(s) // 2))
    result = validation.coverage(specimen, bound, seed=13)
    assert not result.passed(LEVEL), result
    assert result.misses > result.miss_probability * result.readings
