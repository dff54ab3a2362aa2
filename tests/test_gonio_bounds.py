"""Certificates of goniophotometer readings (virtspec_mi.gonio_bounds): formulas and their inverses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi import gonio_bounds as gb
from virtspec_mi.bounds import hoeffding_rays


def test_dkw_needs_the_papers_n():
    assert gb.dkw_rays(0.005, 0.01) == hoeffding_rays(0.005, 0.01) == 105967


@pytest.mark.parametrize("k", [1, 10, 1296, 10**5])
def test_union_budget_formula_and_inverse(k):
    mu, delta = 0.01, 0.01
    n = gb.union_rays(mu, delta, k)
    assert n == math.ceil(math.log(2 * k / delta) / (2 * mu**2))
    assert gb.union_mu(n, delta, k) <= mu < gb.union_mu(n - 1, delta, k)


def test_union_grows_with_log_k_only():
    assert gb.union_rays(0.01, 0.01, 1000) < 2.5 * gb.union_rays(0.01, 0.01, 1)


def test_exact_union_needs_fewer_rays():
    assert gb.union_exact_rays(0.02, 0.01, 100) < gb.union_rays(0.02, 0.01, 100)


def test_bins_mu_is_the_smaller_certificate():
    n, delta = 10**6, 0.01
    assert gb.bins_mu(n, delta, 10) == pytest.approx(gb.union_mu(n, delta, 10))
    assert gb.bins_mu(n, delta, 10**12) == pytest.approx(2 * gb.dkw_mu(n, delta))


def test_relative_budget_and_inverse():
    n = gb.relative_rays(0.1, 0.05, 0.01, 500, 0.002)
    assert n == math.ceil(3 * math.log(2 * 500 / 0.01) / (0.1**2 * 0.05 * 0.002))
    assert gb.relative_tolerance(n, 0.05, 0.01, 500, 0.002) <= 0.1
    assert np.isnan(gb.relative_tolerance(10, 0.05, 0.01, 500, 0.002))  # vacuous: not certified


def test_brdf_intervals_cover_the_estimate_and_scale_with_solid_angle():
    lower, upper = gb.brdf_intervals(np.array([0, 50, 100]), 1000, np.array([0.1, 0.1, 0.2]), 0.01, 3)
    f = np.array([0, 50, 100]) / 1000 / np.array([0.1, 0.1, 0.2])
    assert np.all(lower <= f) and np.all(f <= upper) and lower[0] == 0


@pytest.mark.parametrize("call, name", [
    (lambda: gb.gonio_rays("bogus", 0.01, 0.01, 10), "guarantee"),
    (lambda: gb.gonio_rays("union", 0.7, 0.01, 10), "mu"),
    (lambda: gb.gonio_rays("union", 0.01, 1.5, 10), "delta"),
    (lambda: gb.gonio_rays("union", 0.01, 0.01, 0), "bins"),
    (lambda: gb.gonio_rays("relative", 0.01, 0.01, 10), "relative_tolerance"),
    (lambda: gb.gonio_rays("relative", 0.01, 0.01, 10, 2.0, 0.1, 0.01), "relative_tolerance"),
    (lambda: gb.gonio_rays("relative", 0.01, 0.01, 10, 0.1, -1.0, 0.01), "brdf_floor"),
    (lambda: gb.gonio_rays("union", 1e-6, 0.01, 10), "union bound"),
])
def test_bad_inputs_name_the_parameter(call, name):
    with pytest.raises(ValueError, match=name):
        call()
