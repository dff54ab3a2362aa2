"""
The models of the ``microfacet`` plugin, by name (no Mitsuba needed)
====================================================================

The choices :mod:`virtspec_mi.plugins.bsdfs.microfacet` offers — distribution,
masking–shadowing G₂, Smith G₁, Fresnel factor — their statements in words (a table's
provenance) and the one check of a combination (:func:`check_model`), in a module that
imports no Mitsuba, so the exchange formats can name and check a model before a variant
is set.

References
----------
Walter, B., Marschner, S.R., Li, H., Torrance, K.E. (2007). Microfacet models for
refraction through rough surfaces. EGSR: eqs. (23), (25), (27).
Heitz, E. (2014). Understanding the masking-shadowing function in microfacet-based
BRDFs. JCGT 3(2): eq. (99).
"""

from __future__ import annotations

__all__ = ["DISTRIBUTIONS", "SHADOWINGS", "G1S", "FRESNELS", "WALTER_SCALE", "ALPHA_RANGE", "model_statement",
           "check_model"]

DISTRIBUTIONS: tuple[str, ...] = ("ggx", "beckmann")
"""Microfacet distributions."""

SHADOWINGS: dict[str, str] = {
    "separable": "separable Smith G2 = G1(wi) G1(wo) (Walter et al. 2007, eq. 23)",
    "height_correlated": "height-correlated Smith G2 = 1/(1 + Lambda(wi) + Lambda(wo)) (Heitz 2014, eq. 99)",
    "unreal": ("Unreal Engine 4's approximation G2 = 2/(2(1 - alpha) + alpha/cos_i + alpha/cos_o) "
               "(Vis_SmithJointApprox)"),
}
"""Masking–shadowing terms, and what each is."""

G1S: dict[str, str] = {
    "exact": "exact Smith G1",
    "walter": "Walter et al. (2007) eq. 27 rational fit of the Beckmann G1",
}
"""Smith G₁ functions (``walter``: Beckmann only)."""

FRESNELS: dict[str, str] = {
    "one": "F = 1",
    "fc": "F = Fc = (1 - wi.m)^5",
    "one_minus_fc": "F = 1 - Fc",
    "split": "F = 1, split on the same rays: reflected with probability w Fc, sent below with probability "
             "w (1 - Fc) (reflected counts integrate Fc f cos, transmitted counts (1 - Fc) f cos)",
}
"""Fresnel factors."""

WALTER_SCALE: float = 1.0032
"""
c for ``g1="walter"``: above the largest ratio G₁,fit/G₁,exact (1.003127 at a ≈ 1.336 on a
grid of 3·10⁴ points of a ∈ (0, 3]; both are 1 − O(e^(−a²)) beyond, the fit exactly 1 for
a ≥ 1.6), so that every weight G₂/G₁,exact(ω_i)/c is ≤ 1.
"""

ALPHA_RANGE: tuple[float, float] = (0.0, 10.0)
"""0 < α ≤ 10."""

def model_statement(distribution: str, shadowing: str, g1: str, fresnel: str) -> str:
    """The model in words (a table's provenance, a header's comment)."""

    g1_words = G1S[g1] if distribution == "beckmann" else "exact Smith G1"
    return (f"{distribution} microfacet reflector, {SHADOWINGS[shadowing]}, {g1_words}, {FRESNELS[fresnel]}; "
            "the instrument counts the integral of f cos (virtspec-mi plugin 'microfacet': visible normals "
            "sampled with the exact Smith normalisation, weight G2 F / G1_exact(wi))")


def check_model(distribution: str, shadowing: str, g1: str, fresnel: str) -> None:
    """``ValueError`` naming the parameter for an unknown or unsupported combination."""

    for name, value, allowed in (("distribution", distribution, DISTRIBUTIONS), ("shadowing", shadowing, SHADOWINGS),
                                 ("g1", g1, G1S), ("fresnel", fresnel, FRESNELS)):
        if value not in allowed:
            raise ValueError(f"microfacet: '{name}' must be one of {', '.join(allowed)} (got {value!r})")
    if g1 == "walter" and distribution != "beckmann":
        raise ValueError("microfacet: g1='walter' is the Beckmann fit (distribution='beckmann'); GGX has g1='exact'")
    if shadowing == "unreal" and distribution != "ggx":
        raise ValueError("microfacet: shadowing='unreal' is Unreal Engine 4's GGX approximation (distribution='ggx')")
