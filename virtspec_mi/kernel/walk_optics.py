"""
Optical pieces of random walks: Fresnel interfaces and Henyey–Greenstein scattering
===================================================================================

Small Dr.Jit functions shared by random-walk specimens (``turbid_slab``, layered
leaf models). They work on per-lane arrays, have no state and draw no random numbers
themselves (the caller passes uniforms from its :func:`virtspec_mi.kernel.walk.walk_rng`),
so they can be called inside ``@dr.syntax`` symbolic loops.

Directions are *propagation* directions (where the light goes) in a frame whose z
axis is the normal of the plane interfaces.

- :func:`free_path`: an exponential free path −ln(1 − ξ)/μt (∞ when μt = 0).
- :func:`sample_hg`: a new direction after Henyey–Greenstein scattering.
- :func:`cross_interface`: a Fresnel coin flip at a plane interface z = const:
  specular reflection with probability F (unpolarised), else refraction (Snell);
  total internal reflection gives F = 1.

References
----------
L.G. Henyey, J.L. Greenstein (1941), *Diffuse radiation in the galaxy*, ApJ 93, 70–83.
L. Wang, S.L. Jacques, L. Zheng (1995), *MCML — Monte Carlo modeling of light
transport in multi-layered tissues*, Comput. Methods Programs Biomed. 47, 131–146:
eq. (3.3) free path, eq. (3.28) HG sampling, eqs. (3.30)–(3.36) Fresnel at a boundary.
"""

from __future__ import annotations

from typing import Any

__all__ = ["free_path", "sample_hg", "cross_interface"]

_G_ISOTROPIC = 1e-4
"""|g| below which HG sampling uses the isotropic formula (avoids 0/0)."""


def free_path(u: Any, mu_t: Any) -> Any:
    """Exponential free path −ln(1 − u)/μt for u ∈ [0, 1) (MCML eq. 3.3); ∞ where μt = 0."""

    import drjit as dr

    return dr.select(mu_t > 0.0, -dr.log(1.0 - u) / mu_t, dr.inf)  # never 0/0 (u = 0, μt = 0)


def sample_hg(direction: Any, g: Any, u1: Any, u2: Any) -> Any:
    """
    Scatter ``direction`` by the Henyey–Greenstein phase function with anisotropy g.

    cos θ = (1 + g² − ((1 − g²)/(1 − g + 2gξ₁))²)/(2g) (MCML eq. 3.28; 2ξ₁ − 1 for
    |g| < 10⁻⁴), azimuth 2πξ₂ about ``direction``; g = ±1 gives exact forward /
    backward scattering. Returns a unit ``mi.Vector3f``.
    """

    import drjit as dr
    import mitsuba as mi

    ratio = (1.0 - g * g) / dr.fma(2.0 * g, u1, 1.0 - g)
    anisotropic = (1.0 + g * g - ratio * ratio) / (2.0 * g)
    anisotropic = dr.select(dr.isnan(anisotropic), g, anisotropic)  # g = 1, ξ₁ = 0: 0/0 → forward
    isotropic = dr.abs(g) < _G_ISOTROPIC
    cos_theta = dr.clip(dr.select(isotropic, dr.fma(2.0, u1, -1.0), anisotropic), -1.0, 1.0)
    sin_theta = dr.safe_sqrt(dr.fma(-cos_theta, cos_theta, 1.0))
    sin_phi, cos_phi = dr.sincos(dr.two_pi * u2)
    local = mi.Vector3f(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta)
    return dr.normalize(mi.Frame3f(direction).to_world(local))


def cross_interface(direction: Any, eta: Any, u: Any) -> tuple[Any, Any]:
    """
    Meet the plane interface z = const with propagation ``direction``.

    ``eta`` is the relative index n₋/n₊ of the medium below the interface (z < const)
    over the medium above it. With probability F (unpolarised Fresnel reflectance of
    the angle of incidence; F = 1 beyond the critical angle) the ray is reflected
    specularly, otherwise refracted. Returns ``(new_direction, reflected)``. An
    index-matched interface (η = 1) never reflects, at any angle.
    """

    import drjit as dr
    import mitsuba as mi

    # mi.fresnel takes the direction towards the side the light comes from, with
    # "exterior" above the +z normal and η = interior/exterior.
    towards = -direction
    fresnel, cos_theta_t, _, eta_ti = mi.fresnel(towards.z, eta)
    fresnel = dr.select(eta == 1.0, 0.0, fresnel)
    reflected = u < fresnel
    new = dr.select(reflected, mi.reflect(towards), mi.refract(towards, cos_theta_t, eta_ti))
    return new, reflected
