"""
Analytic BSDF tables: goniophotometer tables of known models, by NumPy quadrature
=================================================================================

Independent references for the ``tabulated`` BSDF (kept apart from the code they
check, like :mod:`virtspec_mi.references.quadrature`): the bin fractions

    p_k = ∫_bin f(ωi, ωo) |cos θo| dωo = ∫∫_bin f · ½ d(sin²θo) dφo

of an analytic BSDF f, computed with Gauss–Legendre nodes in sin²θo and φo inside
every bin (exact for a Lambertian f), for any wavelengths, θi and bin edges, as a
:class:`~virtspec_mi.plugins.bsdfs.bsdf_table.BSDFTable`; :func:`sample_counts` draws the exact
integer counts a goniophotometer with N rays would give (multinomial), so a table in
the contract layout can be built without the instrument.

Models
------
- :func:`lambertian_table`: f = ρ/π above, τ/π below (p_k = ρ Ω_k/π exactly);
- :func:`phong_model`: a diffuse reflector/transmitter plus the energy-conserving
  modified Phong lobe f_s = ρ_s (n+2)/(2π) cosⁿα about the mirror direction (α: angle
  between ωo and the mirror direction, cos α ≤ 0 → 0), whose hemispherical total is
  ≤ ρ_s at every θi (Lafortune & Willems 1994).

References
----------
Lafortune, E.P. & Willems, Y.D. (1994), *Using the modified Phong reflectance model for
physically based rendering*, KU Leuven CW 197; Nicodemus et al. (1977), NBS Monograph
160.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np

from virtspec_mi.plugins.bsdfs.bsdf_table import BSDFTable, projected_solid_angles

__all__ = [
    "equal_projected_edges",
    "uniform_edges",
    "lambertian_table",
    "phong_model",
    "quadrature_table",
    "sample_counts",
]

Model = Callable[[float, float, np.ndarray, np.ndarray], np.ndarray]
"""f(wavelength nm, θi deg, θo rad, φo − φi rad) in sr⁻¹ (arrays of θo, φo)."""


def equal_projected_edges(per_hemisphere: int, transmission: bool = True) -> np.ndarray:
    """θo edges (deg) uniform in sin²θo: every bin of a Lambertian specimen gets the same share."""

    if per_hemisphere < 1:
        raise ValueError(f"per_hemisphere must be >= 1 (got {per_hemisphere})")
    upper = np.degrees(np.arcsin(np.sqrt(np.arange(per_hemisphere + 1) / per_hemisphere)))
    upper[-1] = 90.0
    if not transmission:
        return upper
    return np.concatenate([upper, 180.0 - upper[-2::-1]])


def uniform_edges(low: float, high: float, bins: int) -> np.ndarray:
    """``bins`` equal bins between ``low`` and ``high`` degrees (edges)."""

    if bins < 1:
        raise ValueError(f"bins must be >= 1 (got {bins})")
    return np.linspace(low, high, bins + 1)


def _table(fraction: np.ndarray, wavelength: Sequence[float], theta_i: Sequence[float], theta_o_edges: np.ndarray,
           phi_o_edges: np.ndarray, phi_i: float, folded: bool, source: str) -> BSDFTable:
    theta_o_edges = np.asarray(theta_o_edges, dtype=np.float64)
    phi_o_edges = np.asarray(phi_o_edges, dtype=np.float64)
    return BSDFTable(
        wavelength=np.atleast_1d(np.asarray(wavelength, dtype=np.float64)),
        theta_i=np.atleast_1d(np.asarray(theta_i, dtype=np.float64)),
        theta_o_lower=theta_o_edges[:-1], theta_o_upper=theta_o_edges[1:],
        phi_o_lower=phi_o_edges[:-1], phi_o_upper=phi_o_edges[1:],
        fraction=fraction, phi_i=phi_i, phi_folded=folded, attrs={"source": source},
    )


def lambertian_table(reflectance: float | Sequence[float], transmittance: float | Sequence[float] = 0.0, *,
                     wavelength: Sequence[float] = (551.0,), theta_i: Sequence[float] = (0.0,),
                     theta_o_edges: np.ndarray | None = None, phi_o_edges: np.ndarray | None = None,
                     phi_i: float = 0.0, folded: bool = False) -> BSDFTable:
    """
    The exact table of a Lambertian reflector (ρ/π) and transmitter (τ/π); ρ and τ are
    numbers or one per wavelength, the same at every θi.
    """

    wavelength = np.atleast_1d(np.asarray(wavelength, dtype=np.float64))
    theta_i = np.atleast_1d(np.asarray(theta_i, dtype=np.float64))
    theta_o_edges = equal_projected_edges(4) if theta_o_edges is None else np.asarray(theta_o_edges, dtype=np.float64)
    phi_o_edges = uniform_edges(0.0, 180.0 if folded else 360.0, 4) if phi_o_edges is None else np.asarray(phi_o_edges)
    rho = np.broadcast_to(np.asarray(reflectance, dtype=np.float64), wavelength.shape)
    tau = np.broadcast_to(np.asarray(transmittance, dtype=np.float64), wavelength.shape)
    if np.any(rho < 0) or np.any(tau < 0) or np.any(rho + tau > 1):
        raise ValueError("reflectance and transmittance must be >= 0 with reflectance + transmittance <= 1")
    omega = projected_solid_angles(theta_o_edges[:-1], theta_o_edges[1:], phi_o_edges[:-1], phi_o_edges[1:], folded)
    reflected = (theta_o_edges[1:] <= 90.0)[:, None]
    albedo = np.where(reflected[None], rho[:, None, None], tau[:, None, None])  # (λ, θo, 1)
    fraction = albedo[:, None] * omega[None, None] / math.pi
    fraction = np.broadcast_to(fraction, (wavelength.size, theta_i.size, *omega.shape))
    return _table(fraction, wavelength, theta_i, theta_o_edges, phi_o_edges, phi_i, folded, "lambertian (exact)")


def phong_model(specular: float | Callable[[float], float] = 0.3, exponent: float = 20.0,
                diffuse: float | Callable[[float], float] = 0.2,
                diffuse_transmission: float | Callable[[float], float] = 0.1) -> Model:
    """
    f = ρ_d/π + ρ_s (n+2)/(2π) max(0, cos α)ⁿ above, τ_d/π below (α: angle to the
    mirror direction); each albedo a number or a function of the wavelength (nm).
    """

    def value(parameter, wavelength: float) -> float:
        return float(parameter(wavelength)) if callable(parameter) else float(parameter)

    def model(wavelength: float, theta_i: float, theta_o: np.ndarray, phi: np.ndarray) -> np.ndarray:
        rho_s, rho_d = value(specular, wavelength), value(diffuse, wavelength)
        tau_d = value(diffuse_transmission, wavelength)
        ti = math.radians(theta_i)
        # mirror direction (θi, φ = 180° relative): cos α = ωo · ω_mirror
        cos_alpha = np.cos(theta_o) * math.cos(ti) - np.sin(theta_o) * math.sin(ti) * np.cos(phi)
        lobe = rho_s * (exponent + 2.0) / (2.0 * math.pi) * np.maximum(cos_alpha, 0.0) ** exponent
        return np.where(theta_o < math.pi / 2, rho_d / math.pi + lobe, tau_d / math.pi)

    return model


def quadrature_table(model: Model, *, wavelength: Sequence[float] = (551.0,), theta_i: Sequence[float] = (0.0,),
                     theta_o_edges: np.ndarray | None = None, phi_o_edges: np.ndarray | None = None,
                     phi_i: float = 0.0, folded: bool = False, nodes: int = 8) -> BSDFTable:
    """
    The table of an analytic BSDF ``model`` (see :data:`Model`; φ relative to the
    incidence azimuth): p_k by ``nodes`` × ``nodes`` Gauss–Legendre points per bin in (sin²θo, φo).
    A folded table integrates both mirror halves.
    """

    wavelength = np.atleast_1d(np.asarray(wavelength, dtype=np.float64))
    theta_i = np.atleast_1d(np.asarray(theta_i, dtype=np.float64))
    theta_o_edges = equal_projected_edges(8) if theta_o_edges is None else np.asarray(theta_o_edges, dtype=np.float64)
    phi_o_edges = uniform_edges(0.0, 180.0 if folded else 360.0, 12) if phi_o_edges is None else np.asarray(phi_o_edges, dtype=np.float64)
    x, w = np.polynomial.legendre.leggauss(nodes)
    x, w = (x + 1.0) / 2.0, w / 2.0  # on [0, 1]
    lower, upper = np.radians(theta_o_edges[:-1]), np.radians(theta_o_edges[1:])
    s_low, s_high = np.sin(lower) ** 2, np.sin(upper) ** 2
    s = s_low[:, None] + (s_high - s_low)[:, None] * x[None, :]  # (θ bins, nodes) in sin²θ
    theta = np.where((upper <= math.pi / 2)[:, None], np.arcsin(np.sqrt(np.clip(s, 0, 1))),
                     math.pi - np.arcsin(np.sqrt(np.clip(s, 0, 1))))
    ds = np.abs(s_high - s_low) / 2.0  # ½ |Δ sin²θ|
    p_low, p_high = np.radians(phi_o_edges[:-1]), np.radians(phi_o_edges[1:])
    phi_abs = p_low[:, None] + (p_high - p_low)[:, None] * x[None, :]  # (φ bins, nodes)
    dphi = p_high - p_low
    # model azimuth: relative to the mirror-free frame (φ = 0 towards the emitter)
    phi_rel = phi_abs if folded else phi_abs - math.radians(phi_i)
    fraction = np.zeros((wavelength.size, theta_i.size, theta.shape[0], phi_abs.shape[0]))
    T = theta[:, None, :, None]
    for a, lam in enumerate(wavelength):
        for b, ti in enumerate(theta_i):
            values = model(float(lam), float(ti), T, phi_rel[None, :, None, :])
            if folded:
                values = values + model(float(lam), float(ti), T, -phi_rel[None, :, None, :])
            integral = np.einsum("tpij,i,j->tp", values, w, w)
            fraction[a, b] = integral * ds[:, None] * dphi[None, :]
    if np.any(fraction.sum(axis=(2, 3)) > 1.0):
        raise ValueError("model: the bin fractions sum to more than 1 (not energy conserving)")
    return _table(fraction, wavelength, theta_i, theta_o_edges, phi_o_edges, phi_i, folded,
                  f"quadrature ({nodes}x{nodes} Gauss-Legendre per bin)")


def sample_counts(table: BSDFTable, rays: int, seed: int = 0) -> np.ndarray:
    """
    Exact integer counts per bin that a goniophotometer with ``rays`` rays per (λ, θi)
    would record for ``table`` (one multinomial draw per row, the absorbed rays the
    remainder), shape of ``table.fraction``.
    """

    if rays < 1:
        raise ValueError(f"rays must be >= 1 (got {rays})")
    rng = np.random.default_rng(seed)
    n_wavelength, n_theta_i = table.shape[:2]
    flat = table.fraction.reshape(n_wavelength * n_theta_i, -1)
    counts = np.empty(flat.shape, dtype=np.int64)
    for row, p in enumerate(flat):
        probabilities = np.append(p, max(0.0, 1.0 - p.sum()))
        counts[row] = rng.multinomial(rays, probabilities / probabilities.sum())[:-1]
    return counts.reshape(table.fraction.shape)
