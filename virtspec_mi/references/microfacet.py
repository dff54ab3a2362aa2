"""
Independent reference: directional albedo of microfacet surfaces by quadrature
==============================================================================

Deterministic float64 values of the directional albedo E(μ) of single-scattering
microfacet BSDFs, against which the certified tables of
:mod:`virtspec_mi.applications.tables.albedo` are tested. Nothing here uses Mitsuba, Dr.Jit or
random numbers, and nothing reuses the code under test; only the unpolarised Fresnel
reflectance of :func:`virtspec_mi.references.quadrature.fresnel_reflectance_cos` (itself an
independent reference) is shared.

The model (Walter et al. 2007, eqs. 20, 33; Heitz 2014, eqs. 2, 15) is written over the
microfacet normal m. Light arrives from ω_i (cos θ_i = μ > 0). The distribution of
*visible* normals (Heitz 2014, eq. 2; Heitz & d'Eon 2014)

    D_ωi(m) = G₁(ω_i, m) ⟨ω_i·m⟩ D(m) / μ

is a probability density over m (its integral is 1 by the definition of the Smith G₁),
and the single-scattering energies are

    E_R(μ) = ∫ D_ωi(m) F(ω_i·m) G₁(ω_r, m) dm,        ω_r = 2(ω_i·m)m − ω_i,
    E_T(μ) = ∫ D_ωi(m) (1 − F(ω_i·m)) G₁(ω_t, m) dm,   ω_t refracted through m (η),

with G₁(ω_o, m) = 0 when ω_o falls on the wrong side (below the macro-surface for a
reflection, above it for a refraction, or behind the facet). This is exactly the
energy a sampler of visible normals keeps when its weight is G₁(ω_o) and it picks
reflection with probability F (Heitz & d'Eon 2014, Sect. 4): the *separable* Smith
shadowing–masking G = G₁(ω_i)G₁(ω_o) of Walter et al. (2007), eq. (23), in
importance transport (no η² radiance scaling). With F = 1 (``eta=None``) E = E_R is
the conductor albedo of the energy-compensation literature (Kulla & Conty 2017).

Distributions (α the roughness of the slope distribution):

- ``ggx`` (Trowbridge–Reitz): D = 1/(π α² cos⁴θ_m (1 + tan²θ_m/α²)²),
  Λ(a) = (−1 + √(1 + 1/a²))/2 with a = 1/(α tan θ), G₁ = 1/(1 + Λ)
  = 2/(1 + √(1 + α² tan²θ)) (Walter et al. 2007, eqs. 33, 34);
- ``beckmann``: D = exp(−tan²θ_m/α²)/(π α² cos⁴θ_m), exact Smith
  Λ(a) = (erf(a) − 1)/2 + exp(−a²)/(2a√π) (Walter et al. 2007, eq. 25; Heitz 2014,
  eq. 86); ``masking="rational"`` uses instead, for the outgoing G₁ only, the rational
  fit of Walter et al. (2007), eq. (27) — G₁ ≈ (3.535a + 2.181a²)/(1 + 2.276a + 2.577a²)
  for a < 1.6, else 1 — which is what Mitsuba 3's ``roughconductor`` and
  ``roughdielectric`` evaluate (their visible-normal sampler follows the exact
  distribution). The two differ by at most 0.35 % in G₁.

Quadrature
----------
The integral over m is a tensor Gauss–Legendre rule in (u, φ_m) where u is the
cumulative distribution of D(m) cos θ_m in θ_m (``ggx``: tan²θ_m = α² u/(1 − u);
``beckmann``: tan²θ_m = −α² ln(1 − u)), which removes the peak of D at small α,
written as u = 1 − s² (s ∈ [0, 1]) to remove the integrable (1 − u)^(−1/2) of
near-horizontal facets, which refract light (D_ωi ∝ ⟨ω_i·m⟩/cos θ_m), and φ_m over
[0, π] (the integrand is even in φ_m because ω_i lies in the xz plane). The
integrand vanishes continuously where ω_o reaches the horizon (G₁ → 0) and where
ω_i·m → 0, so the rule converges algebraically (about as n⁻²): :func:`directional_albedo`
returns the value with ``nodes`` and the tests compare it with ``2 × nodes``.

References
----------
Walter, B., Marschner, S.R., Li, H., Torrance, K.E. (2007). Microfacet models for
refraction through rough surfaces. Eurographics Symposium on Rendering: eqs. (20),
(21), (23), (25), (27), (33), (34).
Heitz, E. (2014). Understanding the masking-shadowing function in microfacet-based
BRDFs. Journal of Computer Graphics Techniques 3(2): eqs. (2), (15), (86).
Heitz, E., d'Eon, E. (2014). Importance sampling microfacet-based BSDFs using the
distribution of visible normals. Computer Graphics Forum 33(4).
Kulla, C., Conty, A. (2017). Revisiting physically based shading at Imageworks.
SIGGRAPH course *Physically Based Shading in Theory and Practice* (E(μ), E_avg).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import erf

from virtspec_mi.references.quadrature import fresnel_reflectance_cos

__all__ = ["DISTRIBUTIONS", "MASKINGS", "Albedo", "smith_lambda", "smith_g1", "directional_albedo",
           "average_albedo"]

DISTRIBUTIONS: tuple[str, ...] = ("ggx", "beckmann")
"""Microfacet distributions of the reference."""

MASKINGS: tuple[str, ...] = ("exact", "rational")
"""Outgoing G₁: the exact Smith function, or Walter et al.'s rational Beckmann fit (eq. 27)."""


@dataclass(frozen=True)
class Albedo:
    """Directional albedo parts at one (μ, α[, η]): E = reflected + transmitted."""

    reflected: float
    transmitted: float

    @property
    def total(self) -> float:
        return self.reflected + self.transmitted


def _check(distribution: str, alpha: float, masking: str) -> None:
    if distribution not in DISTRIBUTIONS:
        raise ValueError(f"distribution must be one of {', '.join(DISTRIBUTIONS)} (got {distribution!r})")
    if masking not in MASKINGS:
        raise ValueError(f"masking must be one of {', '.join(MASKINGS)} (got {masking!r})")
    if not (np.isfinite(alpha) and alpha > 0):
        raise ValueError(f"alpha must be a finite number > 0 (got {alpha!r})")


def smith_lambda(a: ArrayLike, distribution: str) -> NDArray[np.float64]:
    """
    Smith Λ(a), a = 1/(α tan θ) (a = ∞ at normal incidence: Λ = 0).

    References
    ----------
    Walter et al. (2007), eqs. (25), (34); Heitz (2014), eqs. (72), (86).
    """

    a = np.asarray(a, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if distribution == "ggx":
            value = (-1.0 + np.sqrt(1.0 + 1.0 / (a * a))) / 2.0
        else:
            value = (erf(a) - 1.0) / 2.0 + np.exp(-a * a) / (2.0 * a * np.sqrt(np.pi))
    return np.where(np.isinf(a), 0.0, value)


def smith_g1(cos_v: ArrayLike, v_dot_m: ArrayLike, alpha: float, distribution: str,
             masking: str = "exact") -> NDArray[np.float64]:
    """
    Smith G₁ of a direction v (cos θ_v relative to the macro-normal) seen by facet m.

    0 where v·m and cos θ_v have different signs (a facet seen from behind), else
    1/(1 + Λ(a)) with a = 1/(α |tan θ_v|), or Walter et al.'s rational fit for
    ``beckmann`` with ``masking="rational"``.

    References
    ----------
    Walter et al. (2007), eqs. (23), (27); Heitz (2014), eq. (15).
    """

    cos_v = np.asarray(cos_v, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        tan = np.sqrt(np.maximum(0.0, 1.0 - cos_v * cos_v)) / np.abs(cos_v)
        a = 1.0 / (alpha * tan)
    if distribution == "beckmann" and masking == "rational":
        with np.errstate(invalid="ignore"):
            g1 = np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a))
    else:
        g1 = 1.0 / (1.0 + smith_lambda(a, distribution))
    g1 = np.where(tan == 0.0, 1.0, g1)
    visible = np.asarray(v_dot_m) * cos_v > 0.0
    return np.where(visible & np.isfinite(g1), g1, 0.0)


def _gauss_legendre(count: int, low: float, high: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    x, w = np.polynomial.legendre.leggauss(count)
    half = (high - low) / 2.0
    return low + half * (x + 1.0), half * w


def directional_albedo(mu: float, alpha: float, distribution: str = "ggx", eta: float | None = None,
                       masking: str = "exact", nodes: int = 1024) -> Albedo:
    """
    Single-scattering directional albedo of a microfacet surface lit at cos θ_i = μ.

    Parameters
    ----------
    mu
        Incidence cosine, 0 < μ ≤ 1.
    alpha
        Roughness α > 0 of the microfacet distribution (not the "perceptual" roughness).
    distribution
        ``ggx`` or ``beckmann``.
    eta
        ``None``: a conductor with Fresnel = 1 (everything the facets see is
        reflected). A number: a dielectric of relative index η = n_t/n_i (η < 1: light
        inside the denser medium, total internal reflection included).
    masking
        ``exact`` or ``rational`` (Walter et al.'s Beckmann fit, for the outgoing G₁
        only; see the module docstring).
    nodes
        Gauss–Legendre nodes per dimension (u and φ_m).

    Returns
    -------
    Albedo
        ``reflected`` (E_R), ``transmitted`` (E_T; 0 for a conductor) and ``total``.

    References
    ----------
    Walter et al. (2007), eqs. (20), (21), (33); Heitz (2014), eq. (2).
    """

    _check(distribution, alpha, masking)
    if not 0.0 < mu <= 1.0:
        raise ValueError(f"mu must satisfy 0 < mu <= 1 (got {mu!r})")
    if eta is not None and not (np.isfinite(eta) and eta > 0):
        raise ValueError(f"eta must be a finite number > 0 or None (got {eta!r})")
    if not 8 <= int(nodes) <= 8192:
        raise ValueError(f"nodes must satisfy 8 <= nodes <= 8192 (got {nodes!r})")
    s, ws = _gauss_legendre(int(nodes), 0.0, 1.0)
    u, wu = 1.0 - s * s, 2.0 * s * ws  # u = 1 − s²: removes the (1 − u)^(−1/2) of grazing facets
    phi, wphi = _gauss_legendre(int(nodes), 0.0, np.pi)
    if distribution == "ggx":
        tan2 = alpha * alpha * u / (s * s)
    else:
        tan2 = -2.0 * alpha * alpha * np.log(s)
    cos_m = 1.0 / np.sqrt(1.0 + tan2)
    sin_m = np.sqrt(tan2) * cos_m
    sin_i = np.sqrt(max(0.0, 1.0 - mu * mu))
    wi = np.array([sin_i, 0.0, mu])
    g1_i = float(smith_g1(np.array(mu), np.array(1.0), alpha, distribution))  # exact: normalises D_wi
    reflected = transmitted = 0.0
    for row in range(0, len(u), 64):  # blocks of u rows bound the memory
        cm, sm, w_u = cos_m[row:row + 64, None], sin_m[row:row + 64, None], wu[row:row + 64, None]
        m = np.stack([sm * np.cos(phi)[None, :], sm * np.sin(phi)[None, :], np.broadcast_to(cm, (len(cm), len(phi)))])
        c = np.tensordot(wi, m, axes=1)  # ω_i·m
        # D(m) cos θ_m dω = du dφ/(2π): D_ωi dm = G₁(ω_i) ⟨ω_i·m⟩ / (μ cos θ_m) du dφ/(2π)
        weight = np.where(c > 0, g1_i * c / (mu * cm), 0.0) * w_u * wphi[None, :] / np.pi  # φ over [0, π], doubled
        fresnel = np.ones_like(c) if eta is None else fresnel_reflectance_cos(np.clip(c, 0.0, 1.0), eta)
        wr = 2.0 * c * m - wi[:, None, None]
        g1_r = smith_g1(wr[2], np.einsum("kij,kij->ij", wr, m), alpha, distribution, masking)
        reflected += float(np.sum(weight * fresnel * g1_r))
        if eta is not None:
            sin_t2 = (1.0 - c * c) / (eta * eta)
            cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin_t2))
            wt = -wi[:, None, None] / eta + (c / eta - cos_t) * m
            g1_t = smith_g1(wt[2], np.einsum("kij,kij->ij", wt, m), alpha, distribution, masking)
            transmitted += float(np.sum(weight * np.where(sin_t2 < 1.0, 1.0 - fresnel, 0.0) * g1_t))
    return Albedo(reflected, transmitted)


def average_albedo(alpha: float, distribution: str = "ggx", eta: float | None = None, masking: str = "exact",
                   nodes: int = 256, mu_nodes: int = 64) -> Albedo:
    """
    Cosine-weighted hemispherical average E_avg = 2 ∫₀¹ E(μ) μ dμ by Gauss–Legendre in μ.

    References
    ----------
    Kulla & Conty (2017) (E_avg); the directional albedo of :func:`directional_albedo`.
    """

    mus, weights = _gauss_legendre(int(mu_nodes), 0.0, 1.0)
    parts = [directional_albedo(float(m), alpha, distribution, eta, masking, nodes) for m in mus]
    reflected = 2.0 * float(np.sum(weights * mus * np.array([p.reflected for p in parts])))
    transmitted = 2.0 * float(np.sum(weights * mus * np.array([p.transmitted for p in parts])))
    return Albedo(reflected, transmitted)
