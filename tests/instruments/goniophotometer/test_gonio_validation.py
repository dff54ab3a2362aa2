"""
Goniophotometer readings against independent references, each within its certificate:

- Lambertian (``diffuse``): f = ρ/π in every bin; equal-projected-solid-angle bins get
  equal shares.
- ``simple_dielectric``, collimated: every reflected ray in the mirror bin, every
  refracted one in the Snell bin (exact).
- Mitsuba's ``roughconductor`` (GGX, visible-normal sampling): bin fractions against a
  NumPy quadrature of the microfacet BRDF written here (Walter et al. 2007: GGX D,
  separable Smith G with the GGX G1, the exact conductor Fresnel term for a complex
  index η + ik; not Mitsuba's ``eval``).
- ``turbid_slab``, semi-infinite, index-matched, isotropic, albedo a: the diffusely
  reflected distribution against Chandrasekhar's H-function solution (Chandrasekhar
  1960, *Radiative Transfer*, Ch. IV §§26–27 and Ch. V: for isotropic scattering the
  reflected intensity I(μ, μ0) = (a/4) F μ0 H(μ) H(μ0)/(μ + μ0) for an incident flux πF
  normal to the beam, i.e. the BRDF f = a H(μ) H(μ0) / (4π (μ + μ0)); H solved here by
  iterating 1/H(μ) = √(1 − a) + (a/2) ∫₀¹ μ' H(μ')/(μ + μ') dμ'), all orders of scattering.

Every comparison holds each bin to the reading's own certificate (``bins_mu``: all K bin
fractions at once at 1 − δ; or the simultaneous Clopper–Pearson band), with fixed seeds.

References
----------
Walter, B., Marschner, S., Li, H., Torrance, K. (2007). Microfacet models for refraction
through rough surfaces. EGSR, eqs. (33), (34), (20)–(23).
Chandrasekhar, S. (1960). Radiative Transfer. Dover, Ch. IV–V.
Born, M., Wolf, E. Principles of Optics, Sect. 14.2 (Fresnel for absorbing media).
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm

NODES, WEIGHTS = np.polynomial.legendre.leggauss(24)


def _gauss(low: float, high: float) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes and weights on [low, high]."""

    return (high - low) / 2 * NODES + (high + low) / 2, (high - low) / 2 * WEIGHTS


def _bin_integrals(brdf, bins) -> np.ndarray:
    """p_k = ∫_bin f cos θo dωo = ∫∫ f · ½ d(sin²θo) dφo, per reflection bin (Gauss–Legendre)."""

    out = np.zeros(bins.shape)
    for i, (t0, t1) in enumerate(zip(bins.theta_edges[:-1], bins.theta_edges[1:])):
        if t0 >= 90:
            continue
        u, wu = _gauss(np.sin(np.radians(t0)) ** 2, np.sin(np.radians(t1)) ** 2)
        for j, (p0, p1) in enumerate(zip(bins.phi_edges[:-1], bins.phi_edges[1:])):
            phi, wp = _gauss(np.radians(p0), np.radians(p1))
            uu, pp = np.meshgrid(u, phi, indexing="ij")
            out[i, j] = np.sum(brdf(np.arcsin(np.sqrt(uu)), pp) * wu[:, None] * wp[None, :]) / 2
    return out


# --- Lambertian -------------------------------------------------------------------------


def test_diffuse_brdf_is_rho_over_pi_in_every_bin_and_projected_bins_get_equal_shares(mi):
    rho = 0.6
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "spectrum", "value": rho}})
    reading = vm.gonio(scene, theta_i=35, beam="collimated", theta_o_bins=6, phi_o_bins=8, binning="projected",
                       hemispheres="reflection", mu=0.01, seed=11)
    f = reading.brdf[0, 0]
    assert np.all(reading.brdf_lower[0, 0] <= rho / np.pi) and np.all(rho / np.pi <= reading.brdf_upper[0, 0])
    expected = rho * reading.solid_angles / np.pi  # = rho / K: equal shares
    assert np.allclose(expected, rho / reading.size)
    assert np.max(np.abs(reading.fraction[0, 0] - expected)) < reading.bins_mu[0, 0]
    assert np.max(np.abs(f - rho / np.pi)) < 0.1 * rho / np.pi  # and close: ~50 k rays per 48 bins
    # DKW: the CDF of theta_o is rho sin^2(theta) on the projected edges
    cdf = reading.cdf_theta_o[0, 0]
    truth = rho * np.sin(np.radians(reading.bins.theta_edges)) ** 2
    assert np.max(np.abs(cdf - truth)) < reading.cdf_mu[0, 0]


# --- smooth dielectric: exact -----------------------------------------------------------


@pytest.mark.parametrize("theta_i, phi_i", [(30.0, 20.0), (65.0, 250.0)])
def test_simple_dielectric_collimated_mirror_and_snell_bins_hold_every_ray(mi, theta_i, phi_i):
    eta = 2.419
    theta_t = np.degrees(np.arcsin(np.sin(np.radians(theta_i)) / eta))
    mirror_phi = (phi_i + 180.0) % 360.0
    theta_edges = [0, theta_i - 1, theta_i + 1, 90, 180 - theta_t - 1, 180 - theta_t + 1, 180]
    phi_edges = [0, mirror_phi - 1, mirror_phi + 1, 360]
    reading = vm.gonio(vm.instrument_scene({"type": "simple_dielectric"}), theta_i=theta_i, phi_i=phi_i,
                       beam="collimated", theta_o_bins=theta_edges, phi_o_bins=phi_edges, rays=20_000)
    counts = reading.bin_counts[0, 0]
    reflected, transmitted = int(reading.result.reflected[0, 0]), int(reading.result.transmitted[0, 0])
    assert reflected > 0 and transmitted > 0
    assert counts[1, 1] == reflected and counts[4, 1] == transmitted
    assert counts.sum() == reflected + transmitted


# --- GGX rough conductor ----------------------------------------------------------------


def _fresnel_conductor(cos_i: np.ndarray, eta: complex) -> np.ndarray:
    """Unpolarised Fresnel reflectance of a conductor of complex index η (from air), exact."""

    cos_i = np.asarray(cos_i, dtype=complex)
    cos_t = np.sqrt(1 - (1 - cos_i**2) / eta**2)
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return (np.abs(r_s) ** 2 + np.abs(r_p) ** 2) / 2


def _ggx_brdf(alpha: float, eta: complex, wi: np.ndarray):
    """Walter et al. (2007) microfacet BRDF f(wi, wo) = F(wi·h) D(h) G1(wi) G1(wo) / (4 |cos θi| |cos θo|)."""

    def d(cos_h):
        tan2 = (1 - cos_h**2) / cos_h**2
        return 1 / (np.pi * alpha**2 * cos_h**4 * (1 + tan2 / alpha**2) ** 2)

    def g1(cos_v):
        tan2 = (1 - cos_v**2) / cos_v**2
        return 2 / (1 + np.sqrt(1 + alpha**2 * tan2))

    def brdf(theta_o, phi_o):
        wo = np.stack([np.sin(theta_o) * np.cos(phi_o), np.sin(theta_o) * np.sin(phi_o), np.cos(theta_o)], axis=-1)
        h = wo + wi
        h /= np.linalg.norm(h, axis=-1, keepdims=True)
        cos_h, cos_ih = h[..., 2], np.sum(h * wi, axis=-1)
        return _fresnel_conductor(cos_ih, eta) * d(cos_h) * g1(wi[2]) * g1(wo[..., 2]) / (4 * wi[2] * wo[..., 2])

    return brdf


def test_roughconductor_ggx_bin_fractions_match_an_independent_quadrature(mi):
    alpha, eta, k, theta_i = 0.3, 0.2, 3.0, 30.0
    scene = vm.instrument_scene({"type": "roughconductor", "distribution": "ggx", "alpha": alpha,
                                 "eta": eta, "k": k})
    reading = vm.gonio(scene, theta_i=theta_i, beam="collimated", theta_o_bins=9, phi_o_bins=12,
                       hemispheres="reflection", mu=0.01, seed=5)
    wi = np.array([np.sin(np.radians(theta_i)), 0.0, np.cos(np.radians(theta_i))])
    expected = _bin_integrals(_ggx_brdf(alpha, complex(eta, k), wi), reading.bins)
    assert 0.5 < expected.sum() < 1.0  # it has something to compare (albedo of a single-scattering GGX metal)
    miss = np.abs(reading.fraction[0, 0] - expected)
    assert np.max(miss) < reading.bins_mu[0, 0], np.unravel_index(np.argmax(miss), miss.shape)
    assert np.all(reading.brdf_lower[0, 0] <= expected / reading.solid_angles + 1e-12)
    assert np.all(expected / reading.solid_angles <= reading.brdf_upper[0, 0] + 1e-12)
    # DKW: the CDFs of theta_o and phi_o everywhere (the sharpest of the three: alpha off by 10 % fails it)
    _check_cdfs(reading, expected)


def _check_cdfs(reading, expected: np.ndarray) -> None:
    """The reading's CDFs of θo and φo within its DKW μ of those of the expected bin fractions."""

    cdf_theta = np.concatenate([[0.0], np.cumsum(expected.sum(axis=1))])
    cdf_phi = np.concatenate([[0.0], np.cumsum(expected.sum(axis=0))])
    assert np.max(np.abs(reading.cdf_theta_o[0, 0] - cdf_theta)) < reading.cdf_mu[0, 0]
    assert np.max(np.abs(reading.cdf_phi_o[0, 0] - cdf_phi)) < reading.cdf_mu[0, 0]


# --- semi-infinite isotropic slab: Chandrasekhar's H function -------------------------


def chandrasekhar_h(albedo: float, mu: np.ndarray, nodes: int = 200, sweeps: int = 500) -> np.ndarray:
    """
    Chandrasekhar's H(μ) for isotropic scattering of single-scattering albedo a, by
    iterating 1/H(μ) = √(1 − a) + (a/2) ∫₀¹ μ' H(μ')/(μ + μ') dμ' on Gauss–Legendre nodes,
    then the same equation at ``mu`` (Nyström interpolation).
    """

    x, w = _gauss_n(nodes)
    h = np.ones_like(x)
    for _ in range(sweeps):
        new = 1 / (np.sqrt(1 - albedo) + albedo / 2 * np.sum(w * x * h / (x[:, None] + x[None, :]), axis=1))
        if np.max(np.abs(new - h)) < 1e-14:
            h = new
            break
        h = new
    mu = np.asarray(mu, dtype=np.float64)
    return 1 / (np.sqrt(1 - albedo) + albedo / 2 * np.sum(w * x * h / (mu[..., None] + x), axis=-1))


def _gauss_n(n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = np.polynomial.legendre.leggauss(n)
    return (x + 1) / 2, w / 2


def test_chandrasekhar_h_is_right():
    # the zeroth moment alpha_0 = int H dmu solves alpha_0 = 1 + (a/4) alpha_0^2 (integrate the H equation):
    # alpha_0 = 2 (1 - sqrt(1 - a)) / a; and the plane albedo of a semi-infinite medium is
    # 1 - H(mu0) sqrt(1 - a) (Chandrasekhar 1960, Ch. IV-V)
    x, w = _gauss_n(200)
    for a in (0.5, 0.9, 0.99):
        assert np.sum(w * chandrasekhar_h(a, x)) == pytest.approx(2 * (1 - np.sqrt(1 - a)) / a, rel=1e-6)
    a, mu0 = 0.8, 0.6
    h0 = chandrasekhar_h(a, np.array([mu0]))[0]
    f = lambda mu: a * chandrasekhar_h(a, mu) * h0 / (4 * np.pi * (mu + mu0))  # noqa: E731
    xs, ws = _gauss_n(200)
    assert 2 * np.pi * np.sum(ws * f(xs) * xs) == pytest.approx(1 - h0 * np.sqrt(1 - a), rel=1e-6)


def test_turbid_slab_semi_infinite_reflection_matches_chandrasekhar(mi):
    albedo, theta_i = 0.9, 30.0
    scene = vm.instrument_scene({"type": "turbid_slab", "mu_a": 1 - albedo, "mu_s": albedo, "g": 0.0,
                                 "thickness": float("inf"), "eta": 1.0})
    reading = vm.gonio(scene, theta_i=theta_i, beam="collimated", theta_o_bins=9, phi_o_bins=6,
                       binning="projected", hemispheres="reflection", fold_phi=True, mu=0.01, seed=7)
    mu0 = np.cos(np.radians(theta_i))
    h0 = chandrasekhar_h(albedo, np.array([mu0]))[0]
    brdf = lambda theta, phi: albedo * chandrasekhar_h(albedo, np.cos(theta)) * h0 / (  # noqa: E731
        4 * np.pi * (np.cos(theta) + mu0))
    expected = _bin_integrals(brdf, reading.bins) * 2  # folded: each bin stands for both halves
    assert expected.sum() == pytest.approx(1 - h0 * np.sqrt(1 - albedo), rel=1e-6)
    miss = np.abs(reading.fraction[0, 0] - expected)
    assert np.max(miss) < reading.bins_mu[0, 0]
    assert abs(reading.result.reflectance[0, 0] - expected.sum()) < reading.cdf_mu[0, 0]
    _check_cdfs(reading, expected)
