"""
Tests of :mod:`virtspec_mi.references.slab`: the NumPy slab references, against closed forms.

The clear slab's reflectance is held to the incoherent two-face sum at normal incidence,
R = 2R₁/(1 + R₁) (no absorption, the same index below as above), to the single face where
the slab is opaque, and to zero where no face reflects; its diffuse average to the
hemispherical Fresnel reflectance of a single face computed here by an independent
quadrature. The walk is held to those closed forms, to Beer–Lambert and to energy
conservation, within Hoeffding bounds at a fixed seed (δ = 1e-6 per comparison).

References
----------
L. Wang, S.L. Jacques, L. Zheng (1995), MCML, Comput. Methods Programs Biomed. 47, 131–146:
eqs. (3.3), (3.28), (3.30)–(3.36); Born & Wolf, Principles of Optics, Sect. 1.5.2.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy import integrate

from virtspec_mi.references.quadrature import fresnel_reflectance_cos
from virtspec_mi.references.slab import (
    SlabCounts,
    _scatter_hg,
    clear_slab_diffuse_reflectance,
    clear_slab_reflectance,
    walk_slab,
)

RAYS = 20_000
DELTA = 1e-6


def hoeffding(rays: int, delta: float = DELTA) -> float:
    """Two-sided Hoeffding half-width of a fraction of ``rays`` Bernoulli trials, at level 1 - δ."""

    return math.sqrt(math.log(2.0 / delta) / (2.0 * rays))


def test_counts_fractions():
    counts = SlabCounts(rays=10, specular=1, diffuse_reflected=2, regular=3, diffuse_transmitted=1, absorbed=2,
                        capped=1)
    assert counts.reflectance == pytest.approx(0.3)
    assert counts.transmittance == pytest.approx(0.4)
    with pytest.raises(dataclasses.FrozenInstanceError):
        counts.rays = 11  # type: ignore[misc]


def test_clear_slab_at_normal_incidence_is_the_two_face_sum():
    r1 = ((1.5 - 1.0) / (1.5 + 1.0)) ** 2  # 0.04
    assert float(clear_slab_reflectance(1.0, 1.5)) == pytest.approx(2.0 * r1 / (1.0 + r1), rel=1e-12)


def test_clear_slab_without_contrast_reflects_nothing():
    cosines = np.linspace(0.05, 1.0, 7)
    assert np.all(clear_slab_reflectance(cosines, 1.0) == 0.0)
    assert clear_slab_reflectance(cosines, 1.3, 1.3, 1.3).max() == 0.0
    assert clear_slab_diffuse_reflectance(1.2, 1.2, 1.2) == 0.0


def test_opaque_or_matched_bottom_leaves_the_top_face_alone():
    cosines = np.linspace(0.05, 1.0, 9)
    top = fresnel_reflectance_cos(cosines, 1.5)
    np.testing.assert_allclose(clear_slab_reflectance(cosines, 1.5, optical_thickness=1e6), top, rtol=1e-12)
    # the medium below has the slab's index: no bottom face
    np.testing.assert_allclose(clear_slab_reflectance(cosines, 1.5, 1.0, 1.5), top, rtol=1e-12)


def test_absorption_lowers_the_reflectance_monotonically():
    values = [float(clear_slab_reflectance(0.7, 1.5, 1.0, 1.0, tau)) for tau in (0.0, 0.1, 1.0, 10.0)]
    assert all(a > b for a, b in zip(values, values[1:]))
    assert values[-1] == pytest.approx(float(fresnel_reflectance_cos(0.7, 1.5)), rel=1e-6)


def test_diffuse_average_of_an_opaque_slab_is_the_face_hemispherical_reflectance():
    """2∫F(μ)μ dμ of one air→1.5 face, by adaptive quadrature here: ≈ 0.0918 (the diffuse Fresnel value)."""

    expected, _ = integrate.quad(lambda mu: 2.0 * mu * float(fresnel_reflectance_cos(mu, 1.5)), 0.0, 1.0,
                                 epsabs=1e-12)
    assert expected == pytest.approx(0.0918, abs=5e-4)
    assert clear_slab_diffuse_reflectance(1.5, optical_thickness=1e6) == pytest.approx(expected, rel=1e-8)


def test_diffuse_average_with_total_internal_reflection_matches_adaptive_quadrature():
    """A lower-index slab (kinks at the critical cosines): Gauss–Legendre split at them equals scipy's quad."""

    expected, _ = integrate.quad(lambda mu: 2.0 * mu * float(clear_slab_reflectance(mu, 1.0, 1.5, 1.3, 0.2)),
                                 0.0, 1.0, points=[math.sqrt(1 - (1 / 1.5) ** 2), math.sqrt(1 - (1.3 / 1.5) ** 2)],
                                 epsabs=1e-12, limit=200)
    assert clear_slab_diffuse_reflectance(1.0, 1.5, 1.3, 0.2) == pytest.approx(expected, rel=1e-7)


def fates(counts: SlabCounts) -> int:
    return (counts.specular + counts.diffuse_reflected + counts.regular + counts.diffuse_transmitted
            + counts.absorbed + counts.capped)


def test_walk_is_reproducible_and_accounts_for_every_ray():
    a = walk_slab(2_000, 1.0, 4.0, 0.6, 1.0, eta=1.4, seed=3)
    assert a == walk_slab(2_000, 1.0, 4.0, 0.6, 1.0, eta=1.4, seed=3)
    assert a != walk_slab(2_000, 1.0, 4.0, 0.6, 1.0, eta=1.4, seed=4)
    assert fates(a) == a.rays == 2_000 and a.capped == 0


def test_walk_through_nothing_is_all_regular_transmission():
    counts = walk_slab(500, 0.0, 0.0, 0.0, 1.0, cos_theta_i=0.6)
    assert counts.regular == 500 and fates(counts) == 500


def test_walk_of_a_clear_slab_matches_the_exact_reflectance():
    cos_i = math.cos(math.radians(40.0))
    counts = walk_slab(RAYS, 0.7, 0.0, 0.0, 1.0, eta=1.33, eta_below=1.52, cos_theta_i=cos_i, seed=1)
    expected = float(clear_slab_reflectance(cos_i, 1.33, 1.0, 1.52, 0.7))
    assert counts.diffuse_reflected == counts.diffuse_transmitted == 0
    assert abs(counts.reflectance - expected) <= hoeffding(RAYS)


def test_walk_of_a_clear_slab_under_diffuse_light_matches_the_average():
    counts = walk_slab(RAYS, 0.0, 0.0, 0.0, 1.0, eta=1.0, eta_above=1.5, eta_below=1.5, beam="diffuse", seed=2)
    assert abs(counts.reflectance - clear_slab_diffuse_reflectance(1.0, 1.5, 1.5)) <= hoeffding(RAYS)


def test_walk_of_an_absorbing_slab_without_faces_is_beer_lambert():
    cos_i = 0.5
    counts = walk_slab(RAYS, 0.8, 0.0, 0.0, 1.0, cos_theta_i=cos_i, seed=5)
    assert counts.specular == counts.diffuse_reflected == 0
    assert abs(counts.regular / RAYS - math.exp(-0.8 / cos_i)) <= hoeffding(RAYS)
    assert counts.regular + counts.absorbed == RAYS


def test_conservative_walk_absorbs_nothing_and_semi_infinite_transmits_nothing():
    conservative = walk_slab(3_000, 0.0, 10.0, 0.8, 0.5, eta=1.4, seed=6)
    assert conservative.absorbed == 0 and conservative.capped == 0
    assert conservative.specular + conservative.diffuse_reflected + conservative.regular \
        + conservative.diffuse_transmitted == 3_000
    semi = walk_slab(3_000, 1.0, 9.0, 0.0, math.inf, eta=1.5, seed=7)
    assert semi.regular == semi.diffuse_transmitted == 0 and semi.capped == 0
    assert semi.absorbed > 0 and fates(semi) == 3_000


def test_step_cap_counts_the_rays_left():
    counts = walk_slab(1_000, 0.0, 50.0, 0.0, 1.0, max_steps=3, seed=8)
    assert counts.capped > 0 and fates(counts) == 1_000


@pytest.mark.parametrize("g", [0.0, 0.5, -0.7, 0.95])
def test_henyey_greenstein_turns_by_a_mean_cosine_of_g(g):
    """Directions stay unit; ⟨cos θ⟩ = g (|cos θ| ≤ 1: Hoeffding half-width √(2 ln(2/δ)/n))."""

    rng = np.random.default_rng(11)
    n = 40_000
    u = rng.normal(size=(n, 3))
    u[:10, :] = [0.0, 0.0, 1.0]  # the special case along z
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    out = _scatter_hg(u, g, rng.random(n), rng.random(n))
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), 1.0, rtol=1e-12)
    mean_cos = float(np.mean(np.sum(u * out, axis=1)))
    assert abs(mean_cos - g) <= 2.0 * hoeffding(n)
