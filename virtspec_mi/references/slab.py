"""
Independent references for turbid slabs, in NumPy
=================================================

Float64 references that the ``turbid_slab`` plugin is tested and benchmarked
against. Nothing here uses Mitsuba or Dr.Jit, and only the Fresnel formula of
:mod:`virtspec_mi.references.quadrature` is shared.

- :func:`walk_slab`: the same analog walk as the plugin (MCML: Fresnel entry,
  exponential free paths, analog absorption, Henyey–Greenstein scattering, Fresnel
  reflection/refraction with total internal reflection at both faces), vectorised
  over rays with NumPy's own random numbers — an independent Monte Carlo.
- :func:`clear_slab_reflectance`: the exact reflectance of a non-scattering slab
  (incoherent multiple reflections between its faces) at an incidence cosine, and
  :func:`clear_slab_diffuse_reflectance`, its cosine-weighted hemispherical average
  by Gauss–Legendre quadrature (the ``diffuse`` beam's expectation).

References
----------
L. Wang, S.L. Jacques, L. Zheng (1995), MCML, Comput. Methods Programs Biomed. 47,
131–146: eqs. (3.3), (3.28), (3.30)–(3.36).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from virtspec_mi.references.quadrature import fresnel_reflectance_cos

__all__ = ["SlabCounts", "walk_slab", "clear_slab_reflectance", "clear_slab_diffuse_reflectance"]


@dataclass(frozen=True)
class SlabCounts:
    """Fates of ``rays`` photons: specular / diffuse reflection, regular / diffuse transmission, absorbed, capped."""

    rays: int
    specular: int
    diffuse_reflected: int
    regular: int
    diffuse_transmitted: int
    absorbed: int
    capped: int

    @property
    def reflectance(self) -> float:
        return (self.specular + self.diffuse_reflected) / self.rays

    @property
    def transmittance(self) -> float:
        return (self.regular + self.diffuse_transmitted) / self.rays


def _refract(u: NDArray, cos_i: NDArray, eta: NDArray) -> NDArray:
    """Refract propagation directions ``u`` (rows) through a z-plane; η = n_out/n_in (no TIR here)."""

    sin_t2 = (1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin_t2))
    out = u / eta[:, None]
    out[:, 2] = np.sign(u[:, 2]) * cos_t
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def _interface(u: NDArray, eta: NDArray, xi: NDArray) -> tuple[NDArray, NDArray]:
    """Fresnel coin flip for propagation directions ``u`` meeting a z-plane, η = n_out/n_in."""

    cos_i = np.abs(u[:, 2])
    reflect = xi < fresnel_reflectance_cos(cos_i, eta)
    new = u.copy()
    new[reflect, 2] = -u[reflect, 2]
    go = ~reflect
    new[go] = _refract(u[go], cos_i[go], eta[go])
    return new, reflect


def _scatter_hg(u: NDArray, g: float, xi1: NDArray, xi2: NDArray) -> NDArray:
    """New propagation directions after Henyey–Greenstein scattering (MCML eqs. 3.28, 3.30)."""

    if abs(g) < 1e-4:
        cos_t = 2.0 * xi1 - 1.0
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_t = (1.0 + g * g - ((1.0 - g * g) / (1.0 - g + 2.0 * g * xi1)) ** 2) / (2.0 * g)
        cos_t = np.where(np.isnan(cos_t), g, cos_t)  # g = 1, xi1 = 0: 0/0 -> forward
    cos_t = np.clip(cos_t, -1.0, 1.0)
    sin_t = np.sqrt(1.0 - cos_t * cos_t)
    phi = 2.0 * np.pi * xi2
    cos_p, sin_p = np.cos(phi), np.sin(phi)
    ux, uy, uz = u[:, 0], u[:, 1], u[:, 2]
    out = np.empty_like(u)
    steep = np.abs(uz) > 0.99999
    # MCML's rotation formula, with its special case for directions along z.
    den = np.sqrt(np.where(steep, 1.0, 1.0 - uz * uz))
    out[:, 0] = sin_t * (ux * uz * cos_p - uy * sin_p) / den + ux * cos_t
    out[:, 1] = sin_t * (uy * uz * cos_p + ux * sin_p) / den + uy * cos_t
    out[:, 2] = -sin_t * cos_p * den + uz * cos_t
    sz = np.sign(uz[steep])
    out[steep, 0] = sin_t[steep] * cos_p[steep]
    out[steep, 1] = sin_t[steep] * sin_p[steep]
    out[steep, 2] = sz * cos_t[steep]
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def walk_slab(
    rays: int,
    mu_a: float,
    mu_s: float,
    g: float,
    thickness: float,
    eta: float = 1.0,
    eta_above: float = 1.0,
    eta_below: float = 1.0,
    *,
    beam: str = "collimated",
    cos_theta_i: float = 1.0,
    seed: int = 0,
    max_steps: int = 1_000_000,
) -> SlabCounts:
    """
    Analog Monte Carlo of ``rays`` photons through a turbid slab (the plugin's walk, in NumPy).

    ``beam="collimated"`` enters at incidence cosine ``cos_theta_i``; ``"diffuse"``
    draws cosine-distributed incidence directions. Units as in ``turbid_slab``
    (μa, μs per length unit, ``thickness`` in that unit; ``inf`` for semi-infinite).
    """

    rng = np.random.default_rng(seed)
    mu_t = mu_a + mu_s
    albedo = mu_s / mu_t if mu_t > 0 else 0.0
    if beam == "diffuse":
        cos_i = np.sqrt(rng.random(rays))
    else:
        cos_i = np.full(rays, float(cos_theta_i))
    sin_i = np.sqrt(1.0 - cos_i * cos_i)
    u = np.stack([sin_i, np.zeros(rays), -cos_i], axis=1)
    u, reflect = _interface(u, np.full(rays, eta / eta_above), rng.random(rays))
    specular = int(reflect.sum())
    alive = np.flatnonzero(~reflect)
    u = u[alive]
    depth = np.zeros(alive.size)
    scattered = np.zeros(alive.size, dtype=bool)
    counts = dict(diffuse_reflected=0, regular=0, diffuse_transmitted=0, absorbed=0)
    steps = 0
    while u.shape[0] and steps < max_steps:
        steps += 1
        with np.errstate(divide="ignore", invalid="ignore"):
            path = -np.log1p(-rng.random(u.shape[0])) / mu_t if mu_t > 0 else np.full(u.shape[0], np.inf)
            down = u[:, 2] < 0
            to_face = np.where(down, (thickness - depth) / -u[:, 2], depth / u[:, 2])
        to_face = np.where(u[:, 2] == 0, np.inf, to_face)
        hit = path >= to_face
        keep = np.ones(u.shape[0], dtype=bool)
        # Faces.
        h = np.flatnonzero(hit)
        if h.size:
            face_eta = np.where(down[h], eta_below / eta, eta_above / eta)
            new, refl = _interface(u[h], face_eta, rng.random(h.size))
            u[h] = new
            depth[h] = np.where(down[h], thickness, 0.0)
            out = h[~refl]
            top = ~down[out]
            sc = scattered[out]
            specular += int((top & ~sc).sum())
            counts["diffuse_reflected"] += int((top & sc).sum())
            counts["regular"] += int((~top & ~sc).sum())
            counts["diffuse_transmitted"] += int((~top & sc).sum())
            keep[out] = False
        # Interactions.
        m = np.flatnonzero(~hit)
        if m.size:
            depth[m] = depth[m] + path[m] * -u[m, 2]
            absorb = rng.random(m.size) >= albedo
            counts["absorbed"] += int(absorb.sum())
            keep[m[absorb]] = False
            s = m[~absorb]
            u[s] = _scatter_hg(u[s], g, rng.random(s.size), rng.random(s.size))
            scattered[s] = True
        u, depth, scattered = u[keep], depth[keep], scattered[keep]
    return SlabCounts(rays=rays, specular=specular, capped=int(u.shape[0]), **counts)


def clear_slab_reflectance(
    cos_theta_i: NDArray | float, eta: float, eta_above: float = 1.0, eta_below: float = 1.0,
    optical_thickness: float = 0.0,
) -> NDArray[np.float64]:
    """
    Exact reflectance of a non-scattering slab (absorption optical thickness τ = μa·d)
    at incidence cosine cos θi from above, incoherent multiple reflections:

        R = R₁ + (1 − R₁)² R₂ a² / (1 − R₁ R₂ a²),   a = exp(−τ/cos θt),

    with R₁ = F at the top face (the same from either side, by reciprocity), R₂ the
    internal Fresnel reflectance at the bottom face (total internal reflection
    included) and θt the refraction angle inside.
    """

    cos_i = np.asarray(cos_theta_i, dtype=np.float64)
    r1 = fresnel_reflectance_cos(cos_i, eta / eta_above)
    sin_t2 = (1.0 - cos_i * cos_i) * (eta_above / eta) ** 2
    cos_t = np.sqrt(np.clip(1.0 - sin_t2, 0.0, 1.0))
    r2 = fresnel_reflectance_cos(cos_t, eta_below / eta)
    with np.errstate(divide="ignore", over="ignore"):
        a2 = np.where(r1 < 1.0, np.exp(-2.0 * optical_thickness / np.maximum(cos_t, 1e-300)), 0.0)
        inner = np.where(r1 < 1.0, (1.0 - r1) ** 2 * r2 * a2 / (1.0 - r1 * r2 * a2), 0.0)
    return r1 + inner


def clear_slab_diffuse_reflectance(
    eta: float, eta_above: float = 1.0, eta_below: float = 1.0, optical_thickness: float = 0.0,
    nodes: int = 200,
) -> float:
    """Cosine-weighted hemispherical average 2∫R(μ)μ dμ of :func:`clear_slab_reflectance` (Gauss–Legendre)."""

    # Split at the critical cosine (the integrand has a kink there).
    edges = [0.0, 1.0]
    if eta < eta_above:
        edges.insert(1, float(np.sqrt(1.0 - (eta / eta_above) ** 2)))
    if eta_below < eta_above:  # total internal reflection at the bottom face beyond this
        edges.insert(1, float(np.sqrt(1.0 - (eta_below / eta_above) ** 2)))
    edges = sorted(set(edges))
    x, w = np.polynomial.legendre.leggauss(nodes)
    total = 0.0
    for low, high in zip(edges[:-1], edges[1:]):
        mu = 0.5 * (high - low) * x + 0.5 * (high + low)
        total += 0.5 * (high - low) * float(np.sum(w * 2.0 * mu * clear_slab_reflectance(
            mu, eta, eta_above, eta_below, optical_thickness)))
    return total
