"""
``microfacet``: a rough conductor whose sampling agrees with its evaluation
===========================================================================

A single-scattering microfacet reflector (light from above only; nothing is
transmitted) whose sample weight is computed from the same masking–shadowing term as
its ``eval()``, so that a ray-counting instrument measures exactly

    E(μ) = ∫ f(ω_i, ω_o) cos θ_o dω_o,   f = D(m) G₂(ω_i, ω_o) F / (4 cos θ_i cos θ_o),

the quantity renderers tabulate for energy compensation (Kulla & Conty 2017). Mitsuba's
``roughconductor`` with Beckmann does not: its visible-normal sampler is normalised
with the exact Smith G₁ while ``eval()`` and its weight use Walter's rational fit, so
a count measures G₁,exact(ω_i)/G₁,fit(ω_i) × E.

**Sampling.** m is drawn from the distribution of visible normals of ω_i with the
*exact* Smith normalisation, D_ωi(m) = G₁(ω_i) ⟨ω_i·m⟩ D(m)/cos θ_i (Heitz & d'Eon 2014;
GGX by the spherical-cap construction of Dupuy & Benyoub 2023, any α > 0; Beckmann by
Mitsuba's ``MicrofacetDistribution``, which clamps α ≥ 10⁻⁴), and ω_o = reflect(ω_i, m).
Its density is p(ω_o) = G₁(ω_i) D(m)/(4 cos θ_i), so the weight f cos θ_o / p is

    w = G₂(ω_i, ω_o) F / G₁(ω_i) / c,

which is ≤ 1 for every model below (so the kernel's Russian roulette keeps the ray with
probability w, an exact Bernoulli trial with mean E/c), and the instrument's count
estimates E/c: a table multiplies it by the constant c (:attr:`Microfacet.count_scale`).

Parameters
----------
distribution : str, default ``"ggx"``
    ``ggx`` (Trowbridge–Reitz) or ``beckmann``.
alpha : float, default 0.5
    Roughness α of the slope distribution, 0 < α ≤ 10 (exposed to ``mi.traverse`` as
    ``alpha``; a new value reuses the compiled kernel).
shadowing : str, default ``"separable"``
    The masking–shadowing term G₂ (Λ the Smith function of the chosen G₁):
    ``separable`` G₁(ω_i)G₁(ω_o) (Walter et al. 2007, eq. 23; Mitsuba's
    ``roughconductor``); ``height_correlated`` 1/(1 + Λ(ω_i) + Λ(ω_o)) (Heitz 2014,
    eq. 99; Cycles and Filament); ``unreal`` (GGX only) the approximation of Unreal
    Engine 4's ``PreintegratedGF``, G₂ = 2/(2(1 − α) + α/cos θ_i + α/cos θ_o)
    (``Vis_SmithJointApprox``), which is ≤ G₁(ω_i) for α ≤ 1 (Unreal's roughness ≤ 1),
    so w ≤ 1: with ``unreal`` α must satisfy 0 < α ≤ 1. Proof: it is
    1/(1 + Λ̃(ω_i) + Λ̃(ω_o)) with Λ̃(μ) = α(1 − μ)/(2μ) ≥ 0, and Λ̃ ≥ Λ_GGX because
    (μ(1 − α) + α)² − (α² + (1 − α²)μ²) = 2α(1 − α)μ(1 − μ) ≥ 0.
g1 : str, default ``"exact"``
    The Smith G₁ of ``beckmann``: ``exact`` 1/(1 + Λ), Λ(a) = (erf(a) − 1)/2 +
    e^(−a²)/(2a√π), a = 1/(α tan θ) (Walter et al. 2007, eq. 25), or ``walter`` the
    rational fit of eq. (27) (what Mitsuba evaluates). The fit exceeds the exact G₁ by
    up to 0.313 % (a ≈ 1.34), so with ``walter`` the weight would reach 1.0031: it is
    divided by c = :data:`WALTER_SCALE` = 1.0032 and the table multiplies the count by c.
    GGX has one G₁ (``exact``).
fresnel : str, default ``"one"``
    The Fresnel factor F: ``one`` (F = 1, the albedo E), ``fc`` F = F_c = (1 − ω_i·m)⁵ or
    ``one_minus_fc`` F = 1 − F_c: the two halves of the split-sum integrals of Karis
    (2013) — Filament's DFG.x is ∫ F_c f cos (with DFG.y = E), Unreal's A and B are
    ∫ (1 − F_c) f cos and ∫ F_c f cos; or ``split``: both halves on the same rays —
    the ray is kept with probability w (F = 1) and, by the 1-D sample, *reflected* with
    probability w F_c or sent *below* the surface (mirrored, a bookkeeping
    "transmission") with probability w (1 − F_c), weight 1 either way. The instrument's
    reflected count then estimates ∫ F_c f cos, the transmitted one ∫ (1 − F_c) f cos and
    their sum E: a table certifies all three on one set of rays (``parts=True``).

References
----------
Walter, B., Marschner, S.R., Li, H., Torrance, K.E. (2007). Microfacet models for
refraction through rough surfaces. EGSR: eqs. (20), (23), (25), (27), (33), (34).
Heitz, E. (2014). Understanding the masking-shadowing function in microfacet-based
BRDFs. JCGT 3(2): eqs. (43), (72), (86), (99).
Heitz, E., d'Eon, E. (2014). Importance sampling microfacet-based BSDFs using the
distribution of visible normals. Computer Graphics Forum 33(4).
Dupuy, J., Benyoub, A. (2023). Sampling visible GGX normals with spherical caps.
Computer Graphics Forum 42(8): Listing 3.
Karis, B. (2013). Real shading in Unreal Engine 4. SIGGRAPH course *Physically Based
Shading in Theory and Practice*: eq. (8) (the split sum).
Kulla, C., Conty, A. (2017). Revisiting physically based shading at Imageworks.
SIGGRAPH course (E(μ), E_avg).
"""

from __future__ import annotations

import math
from typing import Any

import drjit as dr
import mitsuba as mi

from virtspec_mi.base.checks import check_float32
from virtspec_mi.plugins.bsdfs.microfacet_model import ALPHA_RANGE, WALTER_SCALE, check_model
from virtspec_mi.plugins.specimen import Parameter

__all__ = ["Microfacet"]

_SQRT_PI = math.sqrt(math.pi)


class Microfacet(mi.BSDF):
    """A rough conductor sampled consistently with its evaluation (see the module docstring)."""

    wavelength_independent: bool = True
    PARAMETERS = (Parameter("alpha", *ALPHA_RANGE, "1", "roughness (lowest excluded; 1 at most with the 'unreal' "
                            "shadowing)"),)
    wavelength_range: tuple[float, float] | None = None  # the specimen protocol: any wavelength

    def check_wavelengths(self, wavelengths: Any) -> None:
        """The specimen protocol: no spectral parameter to check."""

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        self.distribution = str(props.get("distribution", "ggx"))
        self.shadowing = str(props.get("shadowing", "separable"))
        self.g1 = str(props.get("g1", "exact"))
        self.fresnel = str(props.get("fresnel", "one"))
        check_model(self.distribution, self.shadowing, self.g1, self.fresnel)
        self.count_scale = WALTER_SCALE if self.g1 == "walter" else 1.0
        self._set_alpha(props.get("alpha", 0.5))
        self.m_components = [mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide]
        if self.fresnel == "split":
            self.m_components.append(mi.BSDFFlags.GlossyTransmission | mi.BSDFFlags.FrontSide
                                     | mi.BSDFFlags.NonSymmetric)
        self.m_flags = self.m_components[0]
        for component in self.m_components[1:]:
            self.m_flags = self.m_flags | component

    # -- parameters --------------------------------------------------------------------

    def _set_alpha(self, alpha: Any) -> None:
        low, high = ALPHA_RANGE
        if self.shadowing == "unreal":  # the approximation is <= G1(wi) (w <= 1) for alpha <= 1 only
            high = 1.0
        self.alpha = check_float32("microfacet: 'alpha'", alpha, f"be a number with {low:g} < alpha <= {high:g}",
                                   lambda value: low < value <= high)
        self._alpha = dr.opaque(mi.Float, self.alpha)

    def traverse(self, callback: Any) -> None:
        self._exposed = dr.opaque(mi.Float64, self.alpha)
        callback.put("alpha", self._exposed, +mi.ParamFlags.NonDifferentiable)

    def parameters_changed(self, keys: Any = None) -> None:
        value = getattr(self, "_exposed", None)
        if value is not None:
            if dr.width(value) != 1:
                raise ValueError(f"microfacet: 'alpha' must be one number (got {dr.width(value)})")
            self._set_alpha(float(value[0]))

    # -- the model ---------------------------------------------------------------------

    def _lambda(self, cos_v: Any, exact: bool) -> Any:
        """Smith Λ of a direction with cosine ``cos_v`` > 0 (``exact=False``: the chosen G₁)."""

        alpha = self._alpha
        cos2 = dr.square(cos_v)
        tan2 = dr.maximum(1.0 - cos2, 0.0) / cos2
        if self.distribution == "ggx":
            return 0.5 * (dr.sqrt(1.0 + alpha * alpha * tan2) - 1.0)
        a = dr.rsqrt(alpha * alpha * tan2)  # 1/(α tan θ); +inf at normal incidence
        if self.g1 == "walter" and not exact:
            g1 = dr.select(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a))
            return dr.select(a >= 1.6, 0.0, 1.0 / g1 - 1.0)
        value = 0.5 * (dr.erf(a) - 1.0) + dr.exp(-a * a) / (2.0 * _SQRT_PI * a)
        return dr.select(a > 10.0, 0.0, dr.maximum(value, 0.0))

    def _d(self, m: Any) -> Any:
        """D(m) of the distribution (normalised: ∫ D cos θ_m dω = 1)."""

        alpha2 = self._alpha * self._alpha
        cos2 = dr.square(m.z)
        tan2 = dr.maximum(1.0 - cos2, 0.0) / cos2
        if self.distribution == "ggx":
            return 1.0 / (dr.pi * alpha2 * dr.square(cos2) * dr.square(1.0 + tan2 / alpha2))
        return dr.exp(-tan2 / alpha2) / (dr.pi * alpha2 * dr.square(cos2))

    def _fc(self, wi_dot_m: Any) -> Any:
        c = 1.0 - dr.clip(wi_dot_m, 0.0, 1.0)
        return dr.square(dr.square(c)) * c

    def _ratio(self, cos_i: Any, cos_o: Any, wi_dot_m: Any, wo_dot_m: Any, fresnel: str | None = None) -> Any:
        """G₂(ω_i, ω_o) F / G₁,exact(ω_i): the weight before the scale c (0 where invalid)."""

        fresnel = self.fresnel if fresnel is None else fresnel
        lam_i, lam_o = self._lambda(cos_i, False), self._lambda(cos_o, False)
        lam_exact = self._lambda(cos_i, True)
        if self.shadowing == "separable":
            g2 = 1.0 / ((1.0 + lam_i) * (1.0 + lam_o))
        elif self.shadowing == "height_correlated":
            g2 = 1.0 / (1.0 + lam_i + lam_o)
        else:
            alpha = self._alpha
            g2 = 2.0 / (2.0 * (1.0 - alpha) + alpha / cos_i + alpha / cos_o)
        ratio = g2 * (1.0 + lam_exact)
        if fresnel in ("fc", "one_minus_fc"):
            fc = self._fc(wi_dot_m)
            ratio = ratio * (fc if fresnel == "fc" else 1.0 - fc)
        valid = (cos_i > 0.0) & (cos_o > 0.0) & (wi_dot_m > 0.0) & (wo_dot_m > 0.0)
        return dr.select(valid, ratio, 0.0)

    def _visible_normal(self, wi: Any, sample2: Any) -> Any:
        if self.distribution == "ggx":  # Dupuy & Benyoub (2023), Listing 3: any α > 0
            alpha = self._alpha
            wi_std = dr.normalize(mi.Vector3f(wi.x * alpha, wi.y * alpha, wi.z))
            phi = 2.0 * dr.pi * sample2.x
            z = dr.fma(1.0 - sample2.y, 1.0 + wi_std.z, -wi_std.z)
            sin_theta = dr.sqrt(dr.clip(1.0 - z * z, 0.0, 1.0))
            s, c = dr.sincos(phi)
            h = mi.Vector3f(sin_theta * c, sin_theta * s, z) + wi_std
            return dr.normalize(mi.Vector3f(h.x * alpha, h.y * alpha, h.z))
        distr = mi.MicrofacetDistribution(mi.MicrofacetType.Beckmann, self._alpha, True)
        return distr.sample(wi, sample2)[0]

    # -- Mitsuba's BSDF interface ------------------------------------------------------------

    def sample(self, ctx, si, sample1, sample2, active=True):
        wi = si.wi
        cos_i = mi.Frame3f.cos_theta(wi)
        active = active & (cos_i > 0.0)
        m = self._visible_normal(wi, sample2)
        wo = mi.reflect(wi, m)
        wi_dot_m = dr.dot(wi, m)
        weight = self._ratio(cos_i, mi.Frame3f.cos_theta(wo), wi_dot_m, dr.dot(wo, m)) / self.count_scale
        bs = dr.zeros(mi.BSDFSample3f)
        bs.eta = 1.0
        if self.fresnel != "split":
            bs.wo = wo
            bs.pdf = self._pdf(wi, wo)
            bs.sampled_component = mi.UInt32(0)
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            return bs, dr.select(active, mi.Spectrum(weight), mi.Spectrum(0.0))
        # split: reflected with probability w Fc, sent below with probability w (1 - Fc), weight 1
        up_share = weight * self._fc(wi_dot_m)
        up, kept = sample1 < up_share, sample1 < weight
        below = kept & ~up
        bs.wo = dr.select(below, mi.Vector3f(wo.x, wo.y, -wo.z), wo)
        bs.pdf = self._pdf(wi, bs.wo)
        bs.sampled_component = dr.select(below, mi.UInt32(1), mi.UInt32(0))
        bs.sampled_type = dr.select(below, mi.UInt32(+mi.BSDFFlags.GlossyTransmission),
                                    mi.UInt32(+mi.BSDFFlags.GlossyReflection))
        return bs, dr.select(active & kept, mi.Spectrum(1.0), mi.Spectrum(0.0))

    def _pdf(self, wi: Any, wo: Any) -> Any:
        """Density of ω_o (``split``: of the outcome, a direction below being the mirror of one above)."""

        below = wo.z < 0.0
        up = dr.select(below, mi.Vector3f(wo.x, wo.y, -wo.z), wo)
        cos_i, cos_o = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(up)
        m = dr.normalize(wi + up)
        pdf = self._d(m) / ((1.0 + self._lambda(cos_i, True)) * 4.0 * cos_i)
        if self.fresnel == "split":  # times the probability of that outcome
            share = self._fc(dr.dot(wi, m))
            pdf = pdf * self._ratio(cos_i, cos_o, dr.dot(wi, m), dr.dot(up, m)) / self.count_scale
            pdf = pdf * dr.select(below, 1.0 - share, share)
        else:
            pdf = dr.select(below, 0.0, pdf)
        return dr.select((cos_i > 0.0) & (cos_o > 0.0) & (dr.dot(wi, m) > 0.0), pdf, 0.0)

    def eval(self, ctx, si, wo, active=True):
        """
        f cos θ_o = D G₂ F/(4 cos θ_i) (0 below the surface; ``split``: F = F_c above, and
        below, at the mirror of an upward direction, F = 1 − F_c).
        """

        wi = si.wi
        below = wo.z < 0.0
        up = dr.select(below, mi.Vector3f(wo.x, wo.y, -wo.z), wo) if self.fresnel == "split" else wo
        cos_i, cos_o = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(up)
        m = dr.normalize(wi + up)
        if self.fresnel == "split":
            ratio = dr.select(below, self._ratio(cos_i, cos_o, dr.dot(wi, m), dr.dot(up, m), "one_minus_fc"),
                              self._ratio(cos_i, cos_o, dr.dot(wi, m), dr.dot(up, m), "fc"))
        else:
            ratio = self._ratio(cos_i, cos_o, dr.dot(wi, m), dr.dot(up, m))
        value = ratio * self._d(m) / ((1.0 + self._lambda(cos_i, True)) * 4.0 * cos_i)
        return dr.select(active & (cos_i > 0.0) & (cos_o > 0.0), mi.Spectrum(value), mi.Spectrum(0.0))

    def pdf(self, ctx, si, wo, active=True):
        return dr.select(active, self._pdf(si.wi, wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def to_string(self) -> str:
        return (f"Microfacet[distribution={self.distribution}, alpha={self.alpha}, shadowing={self.shadowing}, "
                f"g1={self.g1}, fresnel={self.fresnel}]")
