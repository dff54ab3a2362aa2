"""
An independent quadrature of microfacet albedos for the tests (not the package's
``virtspec_mi.references.microfacet``): every model the ``microfacet`` plugin
offers, written from the published formulas alone.

E(μ) = ∫ f cos θ_o dω_o with f = D G₂ F/(4 cos θ_i cos θ_o) and dω_o = 4 (ω_o·m) dω_m
(ω_o = reflect(ω_i, m), ω_o·m = ω_i·m) is ∫ D(m) (ω_i·m)/μ G₂ F dω_m; with
D(m) cos θ_m dω_m = du dφ/(2π) (u the cumulative distribution of D cos θ_m in θ_m) and
u = 1 − s², E = ∫₀¹∫₀^π (ω_i·m)/(μ cos θ_m) G₂ F 2s ds dφ/π by Gauss–Legendre in s and φ.
No G₁(ω_i) normalisation enters: a sampler normalised with the wrong G₁ would disagree.

References: Walter et al. (2007) eqs. (25), (27), (33), (34); Heitz (2014) eqs. (43), (99);
Karis (2013) (F_c); Unreal Engine 4 ``SystemTextures.cpp`` (``Vis_SmithJointApprox``).
"""

from __future__ import annotations

import numpy as np
from scipy.special import erfc


def smith_lambda(cos_v, alpha, distribution, g1="exact"):
    cos_v = np.asarray(cos_v, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        sin_v = np.sqrt(np.maximum(0.0, 1.0 - cos_v ** 2))
        if distribution == "ggx":
            out = 0.5 * (np.sqrt(1.0 + (alpha * sin_v / cos_v) ** 2) - 1.0)
        else:
            a = cos_v / (alpha * sin_v)
            if g1 == "walter":
                g = np.where(a < 1.6, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a), 1.0)
                out = 1.0 / g - 1.0
            else:
                out = 0.5 * (np.exp(-a * a) / (a * np.sqrt(np.pi)) - erfc(a))
    return np.where(sin_v == 0.0, 0.0, out)


def albedo(mu, alpha, distribution="ggx", shadowing="separable", g1="exact", fresnel="one", nodes=192):
    """E(μ) of the model (see the module docstring)."""

    x, w = np.polynomial.legendre.leggauss(nodes)
    s, ws = (x + 1.0) / 2.0, w / 2.0
    phi, wphi = (x + 1.0) * np.pi / 2.0, w * np.pi / 2.0
    s, phi = s[:, None], phi[None, :]
    if distribution == "ggx":
        tan2 = alpha * alpha * (1.0 - s * s) / (s * s)
    else:
        tan2 = -2.0 * alpha * alpha * np.log(s)
    cos_m = 1.0 / np.sqrt(1.0 + tan2)
    sin_m = np.sqrt(tan2) * cos_m
    m = np.stack(np.broadcast_arrays(sin_m * np.cos(phi), sin_m * np.sin(phi), cos_m))
    wi = np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])
    c = np.tensordot(wi, m, axes=1)
    cos_o = 2.0 * c * m[2] - mu
    valid = (c > 0.0) & (cos_o > 0.0)
    cos_o = np.where(valid, cos_o, 1.0)
    lam_i = smith_lambda(mu, alpha, distribution, g1)
    lam_o = smith_lambda(cos_o, alpha, distribution, g1)
    if shadowing == "separable":
        g2 = 1.0 / ((1.0 + lam_i) * (1.0 + lam_o))
    elif shadowing == "height_correlated":
        g2 = 1.0 / (1.0 + lam_i + lam_o)
    else:
        g2 = 2.0 / (2.0 * (1.0 - alpha) + alpha / mu + alpha / cos_o)
    fc = (1.0 - np.clip(c, 0.0, 1.0)) ** 5
    f = {"one": 1.0, "fc": fc, "one_minus_fc": 1.0 - fc}[fresnel]
    integrand = np.where(valid, c / (mu * cos_m) * g2 * f, 0.0) * 2.0 * s
    return float(np.sum(integrand * ws[:, None] * wphi[None, :]) / np.pi)


def albedo_with_error(mu, alpha, *model, nodes=192):
    """(E, 4 |E(n) − E(n/2)| + 10⁻⁷): the value and a generous estimate of its quadrature error."""

    fine = albedo(mu, alpha, *model, nodes=nodes)
    coarse = albedo(mu, alpha, *model, nodes=nodes // 2)
    return fine, 4.0 * abs(fine - coarse) + 1e-7


def average_albedo(alpha, *model, nodes=96, mu_nodes=48):
    """E_avg = 2 ∫₀¹ E(μ) μ dμ by Gauss–Legendre in μ."""

    x, w = np.polynomial.legendre.leggauss(mu_nodes)
    mus, wm = (x + 1.0) / 2.0, w / 2.0
    return 2.0 * float(sum(wk * mk * albedo(mk, alpha, *model, nodes=nodes) for mk, wk in zip(mus, wm)))
