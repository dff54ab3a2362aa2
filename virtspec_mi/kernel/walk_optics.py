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
- :func:`fresnel_near_one`: the unpolarised Fresnel reflectance in a form free of
  cancellation for a relative index η near 1 (also ``simple_dielectric``'s).

Fresnel near η = 1
------------------
Mitsuba's float32 ``mi.fresnel`` cancels catastrophically near η = 1 (1 − sin²θi/η² and
cos θi − η cos θt lose every digit of η − 1): compared with a float64 Fresnel over 4·10⁵
angles in [0°, 90°] from both sides, its error is up to 6·10⁻⁵–3·10⁻⁴ for
10⁻² ≤ |η − 1| ≤ 0.1, 1.6·10⁻³ at 10⁻³, 1.8·10⁻² at 10⁻⁵ and 0.19–0.66 at 10⁻⁶ (grazing
incidence), and float32 cannot hold η − 1 below 6·10⁻⁸ at all. For
0 < |η − 1| < :data:`NEAR_ONE` the same equations are evaluated from η − 1 itself (given
apart by the caller, exact): with n the index seen by the ray, a = n² − 1 = (n − 1)(n + 1)
and c = |cos θi|, cos²θt = (a + c²)/n², r_s = −a/(c + n cos θt)²,
r_p = a(c²(n² + 1) − 1)/(n²(n c + cos θt)²); on the same grid it agrees with float64
within 1.3·10⁻⁵ everywhere (|η − 1| from 10⁻⁶ to 0.1) except within 10⁻³ degrees of a
critical angle, where F itself has an infinite slope (``tests/kernel/test_walk_optics.py``).
Beyond :data:`NEAR_ONE`, and at η = 1 exactly (F = 0), ``mi.fresnel`` is used as before,
bit for bit.

References
----------
L.G. Henyey, J.L. Greenstein (1941), *Diffuse radiation in the galaxy*, ApJ 93, 70–83.
L. Wang, S.L. Jacques, L. Zheng (1995), *MCML — Monte Carlo modeling of light
transport in multi-layered tissues*, Comput. Methods Programs Biomed. 47, 131–146:
eq. (3.3) free path, eq. (3.28) HG sampling, eqs. (3.30)–(3.36) Fresnel at a boundary.
"""

from __future__ import annotations

from typing import Any

__all__ = ["free_path", "sample_hg", "cross_interface", "NEAR_ONE", "fresnel_near_one"]

NEAR_ONE: float = 0.1
"""
For 0 < |η − 1| below this, Fresnel's equations are evaluated in the cancellation-free
form of :func:`fresnel_near_one` (``mi.fresnel`` loses the digits of η − 1 there).
"""

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


def fresnel_near_one(cos_theta_i: Any, eta_minus_one: Any) -> tuple[Any, Any]:
    """
    Unpolarised Fresnel reflectance F and cos θt (signed as ``mi.fresnel`` signs it) of a
    smooth interface of relative index η = 1 + ``eta_minus_one``, in a form free of
    cancellation for η near 1 (see the module docstring). ``eta_minus_one`` is exact: a
    host float (float64: 1/η − 1 is then computed on the host too) or a per-lane
    ``mi.Float``; the ray sees n = η from outside (cos θi ≥ 0), n = 1/η from inside.
    """

    import drjit as dr
    import mitsuba as mi

    d_out = eta_minus_one
    d_in = -eta_minus_one / (1.0 + eta_minus_one)  # 1/η − 1, without cancellation
    outside = cos_theta_i >= 0.0
    d = dr.select(outside, mi.Float(d_out), mi.Float(d_in))
    n = 1.0 + d
    a = d * (d + 2.0)  # n² − 1
    c = dr.abs(cos_theta_i)
    n2 = n * n
    cos2_t = (a + c * c) / n2
    total = cos2_t <= 0.0  # total internal reflection
    ct = dr.safe_sqrt(cos2_t)
    s_den = c + n * ct
    p_den = n * c + ct
    r_s = -a / (s_den * s_den)
    r_p = a * (c * c * (n2 + 1.0) - 1.0) / (n2 * p_den * p_den)
    fresnel = dr.select(total, 1.0, 0.5 * (r_s * r_s + r_p * r_p))
    return fresnel, dr.select(outside, -ct, ct)


def cross_interface(direction: Any, eta: Any, u: Any, eta_minus_one: Any = None) -> tuple[Any, Any]:
    """
    Meet the plane interface z = const with propagation ``direction``.

    ``eta`` is the relative index n₋/n₊ of the medium below the interface (z < const)
    over the medium above it. With probability F (unpolarised Fresnel reflectance of
    the angle of incidence; F = 1 beyond the critical angle) the ray is reflected
    specularly, otherwise refracted. Returns ``(new_direction, reflected)``. An
    index-matched interface (η = 1) never reflects, at any angle.

    ``eta_minus_one`` (optional): η − 1 of each lane computed without cancellation by the
    caller (e.g. (n₋ − n₊)/n₊); where 0 < |η − 1| < :data:`NEAR_ONE` it gives F and the
    refraction by :func:`fresnel_near_one`, elsewhere ``mi.fresnel``'s values are kept
    bit for bit. ``None``: the caller knows no lane is near 1 (nothing more is compiled).
    """

    import drjit as dr
    import mitsuba as mi

    # mi.fresnel takes the direction towards the side the light comes from, with
    # "exterior" above the +z normal and η = interior/exterior.
    towards = -direction
    fresnel, cos_theta_t, _, eta_ti = mi.fresnel(towards.z, eta)
    if eta_minus_one is not None:
        near = (dr.abs(eta_minus_one) < NEAR_ONE) & (eta_minus_one != 0.0)
        exact, cos_exact = fresnel_near_one(towards.z, eta_minus_one)
        fresnel = dr.select(near, exact, fresnel)
        cos_theta_t = dr.select(near, cos_exact, cos_theta_t)
        fresnel = dr.select(eta_minus_one == 0.0, 0.0, fresnel)
    fresnel = dr.select(eta == 1.0, 0.0, fresnel)
    reflected = u < fresnel
    new = dr.select(reflected, mi.reflect(towards), mi.refract(towards, cos_theta_t, eta_ti))
    return new, reflected
