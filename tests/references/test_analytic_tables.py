"""
Tests of :mod:`virtspec_mi.references.analytic_tables`: tables of known BSDFs, against closed forms.

A Lambertian table on equal-projected bins gives every bin the same share ρ/(bins); the
quadrature of a Lambertian model reproduces the exact table; the modified Phong lobe at
normal incidence integrates to ρ_s exactly (its integrand is a polynomial of degree n/2 in
sin²θ, which Gauss–Legendre with ``nodes`` > n/4 integrates exactly); the multinomial counts
keep every ray and sit within a Hoeffding bound of the fractions at a fixed seed.

References
----------
Lafortune & Willems (1994), KU Leuven CW 197 (the normalised modified Phong lobe);
Nicodemus et al. (1977), NBS Monograph 160 (projected solid angle).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.references.analytic_tables import (
    equal_projected_edges,
    lambertian_table,
    phong_model,
    quadrature_table,
    sample_counts,
    uniform_edges,
)


def test_equal_projected_edges_are_uniform_in_sin_squared():
    edges = equal_projected_edges(4, transmission=False)
    np.testing.assert_allclose(np.sin(np.radians(edges)) ** 2, [0.0, 0.25, 0.5, 0.75, 1.0], atol=1e-15)
    assert edges[0] == 0.0 and edges[-1] == 90.0
    both = equal_projected_edges(3)
    assert both.size == 7 and both[3] == 90.0 and both[-1] == 180.0
    np.testing.assert_allclose(both[4:], 180.0 - both[2::-1])


def test_edges_refuse_no_bins():
    with pytest.raises(ValueError, match=r"per_hemisphere must be >= 1 \(got 0\)"):
        equal_projected_edges(0)
    with pytest.raises(ValueError, match=r"bins must be >= 1 \(got 0\)"):
        uniform_edges(0.0, 90.0, 0)
    np.testing.assert_allclose(uniform_edges(10.0, 40.0, 3), [10.0, 20.0, 30.0, 40.0])


def test_lambertian_table_gives_every_equal_bin_the_same_share():
    table = lambertian_table([0.6, 0.3], [0.2, 0.5], wavelength=[450.0, 650.0], theta_i=[0.0, 30.0, 60.0])
    assert table.fraction.shape == (2, 3, 8, 4)
    reflected, transmitted = table.fraction[..., :4, :], table.fraction[..., 4:, :]
    np.testing.assert_allclose(reflected[0], 0.6 / 16, rtol=1e-12)
    np.testing.assert_allclose(transmitted[1], 0.5 / 16, rtol=1e-12)
    np.testing.assert_allclose(table.fraction.sum(axis=(2, 3)), [[0.8] * 3, [0.8] * 3], rtol=1e-12)


def test_lambertian_folded_table_keeps_the_totals():
    table = lambertian_table(0.7, 0.1, folded=True)
    assert table.phi_folded and table.phi_o_upper[-1] == 180.0
    assert table.fraction.sum() == pytest.approx(0.8, rel=1e-12)


@pytest.mark.parametrize("rho, tau", [(-0.1, 0.0), (0.0, -0.2), (0.7, 0.4)])
def test_lambertian_table_refuses_impossible_albedos(rho, tau):
    with pytest.raises(ValueError, match="reflectance and transmittance must be >= 0"):
        lambertian_table(rho, tau)


@pytest.mark.parametrize("folded", [False, True])
def test_quadrature_of_a_lambertian_model_is_the_exact_table(folded):
    model = phong_model(specular=0.0, diffuse=0.45, diffuse_transmission=0.25)
    edges = equal_projected_edges(5)
    phi = uniform_edges(0.0, 180.0 if folded else 360.0, 6)
    kwargs = dict(wavelength=[500.0, 600.0], theta_i=[0.0, 45.0], theta_o_edges=edges, phi_o_edges=phi,
                  folded=folded)
    quadrature = quadrature_table(model, nodes=3, **kwargs)
    np.testing.assert_allclose(quadrature.fraction, lambertian_table(0.45, 0.25, **kwargs).fraction, rtol=1e-12)


def test_phong_lobe_at_normal_incidence_integrates_to_its_albedo():
    model = phong_model(specular=0.3, exponent=20.0, diffuse=0.0, diffuse_transmission=0.0)
    table = quadrature_table(model, theta_i=[0.0], nodes=8)
    assert table.fraction.sum() == pytest.approx(0.3, rel=1e-12)
    # the lobe peaks about the mirror direction (θo = 0 at normal incidence): the first ring holds the most
    rings = table.fraction[0, 0].sum(axis=1)
    assert rings[0] == rings.max() and np.all(rings[8:] == 0.0)


def test_phong_lobe_loses_energy_at_grazing_incidence_and_albedos_follow_the_wavelength():
    model = phong_model(specular=lambda lam: 0.001 * lam - 0.2, exponent=10.0, diffuse=0.0,
                        diffuse_transmission=0.0)
    table = quadrature_table(model, wavelength=[400.0, 500.0], theta_i=[0.0, 80.0], nodes=8)
    totals = table.fraction.sum(axis=(2, 3))
    np.testing.assert_allclose(totals[:, 0], [0.2, 0.3], rtol=1e-9)
    assert np.all(totals[:, 1] < totals[:, 0]) and np.all(totals[:, 1] > 0.0)


def test_quadrature_refuses_a_model_that_creates_energy():
    with pytest.raises(ValueError, match="not energy conserving"):
        quadrature_table(lambda lam, ti, theta, phi: np.full(np.broadcast(theta, phi).shape, 1.0))


def test_sample_counts_keep_every_ray_and_follow_the_fractions():
    table = lambertian_table([0.6, 0.2], 0.3, wavelength=[450.0, 650.0], theta_i=[0.0, 50.0])
    rays = 50_000
    counts = sample_counts(table, rays, seed=4)
    assert counts.shape == table.fraction.shape and counts.dtype == np.int64
    assert np.all(counts.sum(axis=(2, 3)) <= rays)
    np.testing.assert_array_equal(counts, sample_counts(table, rays, seed=4))
    assert not np.array_equal(counts, sample_counts(table, rays, seed=5))
    # every bin's count is a binomial fraction: Hoeffding at δ = 1e-6 per bin
    assert np.max(np.abs(counts / rays - table.fraction)) <= math.sqrt(math.log(2e6) / (2 * rays))


def test_sample_counts_refuse_no_rays():
    with pytest.raises(ValueError, match=r"rays must be >= 1 \(got 0\)"):
        sample_counts(lambertian_table(0.5), 0)
