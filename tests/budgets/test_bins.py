"""Certificates of goniophotometer readings (virtspec_mi.budgets.bins): formulas and their inverses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.budgets import bins as gb
from virtspec_mi.budgets.bounds import hoeffding_rays
from virtspec_mi.budgets.rules import gonio_rays


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


def test_exact_union_needs_fewer_rays_and_certifies_its_mu():
    assert gb.union_exact_rays(0.02, 0.01, 100) < gb.union_rays(0.02, 0.01, 100)
    n = gb.union_exact_rays(0.005, 0.01, 1296)  # beyond the exact inverse's range: certified by the rule's N
    assert n < gb.union_rays(0.005, 0.01, 1296)
    assert gb.union_exact_mu(n, 0.01, 1296, mu=0.005) == 0.005
    assert gb.union_exact_mu(n - 1000, 0.01, 1296, mu=0.005) > 0.005


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
    (lambda: gonio_rays("bogus", 0.01, 0.01, 10), "guarantee"),
    (lambda: gonio_rays("union", 0.7, 0.01, 10), "mu"),
    (lambda: gonio_rays("union", 0.01, 1.5, 10), "delta"),
    (lambda: gonio_rays("union", 0.01, 0.01, 0), "bins"),
    (lambda: gonio_rays("relative", 0.01, 0.01, 10), "relative_tolerance"),
    (lambda: gonio_rays("relative", 0.01, 0.01, 10, 2.0, 0.1, 0.01), "relative_tolerance"),
    (lambda: gonio_rays("relative", 0.01, 0.01, 10, 0.1, -1.0, 0.01), "brdf_floor"),
    (lambda: gonio_rays("union", 1e-6, 0.01, 10), "union bound"),
])
def test_bad_inputs_name_the_parameter(call, name):
    with pytest.raises(ValueError, match=name):
        call()


# --- empirical check: miss rates of real readings against the bounds --------------------


def _miss_rates(mi, readings: int, rays: int | None, seed: int) -> dict[str, float]:
    """
    ``readings`` independent goniophotometer readings (one per wavelength: each has its own
    rays) of a Lambertian of ρ = 0.5 under a collimated beam, whose truth is known exactly:
    F(θ) = ρ sin²θ for the CDF of θo (absorbed rays at +∞), p_k = ρ Ω_k/π per bin. Returns
    the share of readings whose CDF misses by ≥ the DKW μ of N, whose bins miss by ≥ the
    union μ of N, and whose simultaneous Clopper–Pearson band misses a bin (N: the DKW
    budget at μ = 0.05, δ = 0.2; ``rays`` overrides the rays traced, not the μ claimed).
    """

    import virtspec_mi as vm

    rho, mu, delta = 0.5, 0.05, 0.2
    n = gb.dkw_rays(mu, delta)
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "spectrum", "value": rho}})
    wavelengths = 400.0 + 0.25 * np.arange(readings)
    reading = vm.gonio(scene, wavelengths=wavelengths, beam="collimated", rays=rays or n, delta=delta, seed=seed,
                       theta_o_bins=60, phi_o_bins=4, binning="projected", hemispheres="reflection")
    k = reading.size
    cdf = reading.cdf_theta_o[:, 0]
    truth = rho * np.sin(np.radians(reading.bins.theta_edges)) ** 2
    cdf_miss = np.max(np.abs(cdf - truth), axis=-1) >= gb.dkw_mu(n, delta)
    p = rho * reading.solid_angles / np.pi
    bins_miss = np.max(np.abs(reading.fraction[:, 0] - p), axis=(-2, -1)) >= gb.union_mu(n, delta, k)
    lower, upper = reading.brdf_lower[:, 0], reading.brdf_upper[:, 0]
    band_miss = np.any((rho / np.pi < lower) | (rho / np.pi > upper), axis=(-2, -1))
    return {"cdf": cdf_miss.mean(), "bins": bins_miss.mean(), "band": band_miss.mean(), "readings": readings}


def _check_miss_rates(mi, readings: int) -> None:
    from scipy import stats

    delta = 0.2
    rates = _miss_rates(mi, readings, None, seed=101)
    for name in ("cdf", "bins", "band"):  # never significantly above delta
        misses = int(round(rates[name] * readings))
        assert stats.binomtest(misses, readings, delta, alternative="greater").pvalue > 1e-4, (name, rates)
    assert rates["cdf"] > 0.05  # DKW-Massart is nearly tight: the check sees misses
    # power: half the rays, the same claimed mu: the CDF misses far more often than delta
    half = _miss_rates(mi, readings, gb.dkw_rays(0.05, delta) // 2, seed=202)
    misses = int(round(half["cdf"] * readings))
    assert stats.binomtest(misses, readings, delta, alternative="greater").pvalue < 1e-4, half


def test_miss_rates_respect_the_bounds_and_halving_n_breaks_them(mi):
    _check_miss_rates(mi, 400)


@pytest.mark.slow
def test_miss_rates_respect_the_bounds_and_halving_n_breaks_them_full(mi):
    _check_miss_rates(mi, 4000)
