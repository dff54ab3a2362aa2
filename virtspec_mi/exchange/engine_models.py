"""
Each engine's own microfacet model: what an albedo table on its grid measures
=============================================================================

A renderer's energy-compensation table is the albedo of *its* model; :func:`bsdf_model`
resolves the specimen a table measures (the ``microfacet`` plugin,
:mod:`virtspec_mi.plugins.bsdfs.microfacet`, whose count is exactly ∫ f cos), by default
the engine's own (:data:`ENGINE_SHADOWING`), and states it in words for the table's
provenance:

- ``cycles`` (Blender, ``intern/cycles/app/cycles_precompute.cpp``): GGX, height-correlated
  Smith G₂ (Heitz 2014, eq. 99), F = 1 — E and E_avg;
- ``filament`` (``libs/ibl/src/CubemapIBL.cpp``, ``DFV_Multiscatter``): GGX,
  height-correlated — DFG.x = ∫ F_c f cos, DFG.y = ∫ f cos;
- ``unreal`` (UE4 ``SystemTextures.cpp``, ``PreintegratedGF``): GGX with
  ``Vis_SmithJointApprox`` — A = ∫ (1 − F_c) f cos, B = ∫ F_c f cos;

(:data:`ENGINE_CHANNELS`; F_c = (1 − ω_i·h)⁵; both halves are counted on the same rays). On a user grid the default is the
separable G₂ of Mitsuba's ``roughconductor``. Glass stays Mitsuba's ``roughdielectric``
(separable GGX; *not* Cycles' glass model, which the provenance says); Beckmann glass is
refused, Mitsuba's Beckmann sampler and evaluation using different G₁.

References
----------
Heitz, E. (2014). Understanding the masking-shadowing function in microfacet-based
BRDFs. JCGT 3(2): eq. (99).
Karis, B. (2013). Real shading in Unreal Engine 4. SIGGRAPH course *Physically Based
Shading in Theory and Practice* (the split sum).
Walter, B. et al. (2007). Microfacet models for refraction through rough surfaces. EGSR: eq. (23).
"""

from __future__ import annotations

__all__ = ["ENGINE_SHADOWING", "ENGINE_CHANNELS", "bsdf_model"]

ENGINE_SHADOWING: dict[str, str] = {"cycles": "height_correlated", "filament": "height_correlated",
                                    "unreal": "unreal", "grid": "separable"}
"""The G₂ a table measures by default on each engine's grid (``grid``: a user grid)."""

ENGINE_CHANNELS: dict[str, tuple[str, dict[str, str]]] = {
    "cycles": ("one", {"E": "E"}),
    "filament": ("split", {"DFG.x": "E_R", "DFG.y": "E"}),
    "unreal": ("split", {"A": "E_T", "B": "E_R"}),
}
"""
Each engine's table: the plugin's ``fresnel`` and, per channel, the certified quantity
that holds it. ``split`` counts both split-sum halves on the same rays: reflected rays
E_R = ∫ F_c f cos, the rays sent below E_T = ∫ (1 − F_c) f cos, and E = E_R + E_T.
"""


def bsdf_model(model: str, distribution: str, engine: str, shadowing: str | None, g1: str,
               fresnel: str) -> tuple[dict[str, str], str, float]:
    """
    The specimen a table measures: (the ``microfacet`` plugin's parameters, the model in
    words, the count scale c). ``engine`` is ``cycles``, ``filament``, ``unreal`` or
    ``grid``; ``shadowing=None`` takes the engine's own (:data:`ENGINE_SHADOWING`).

    Raises
    ------
    ValueError
        Naming the parameter: an unknown value, a parameter glass does not take, Beckmann glass.
    """

    from virtspec_mi.plugins.bsdfs.microfacet_model import WALTER_SCALE, check_model, model_statement

    if model == "glass":
        if distribution != "ggx":
            raise ValueError("distribution must be 'ggx' for model='glass': Mitsuba's Beckmann roughdielectric samples "
                             "with the exact Smith G1 but weighs with Walter's fit, so its count is not the integral "
                             "of f cos the table would state")
        if shadowing not in (None, "separable") or g1 != "exact" or fresnel != "one":
            raise ValueError("shadowing, g1 and fresnel are conductor parameters (model='glass' is Mitsuba's "
                             "roughdielectric: separable GGX)")
        words = ("Mitsuba roughdielectric, GGX, separable Smith G2 = G1(wi) G1(wo) (Walter et al. 2007, eq. 23), "
                 "importance transport")
        if engine == "cycles":
            words += "; NOT Cycles' own glass model (height-correlated): Cycles' layout holding this model"
        return {}, words, 1.0
    shadowing = ENGINE_SHADOWING[engine] if shadowing is None else shadowing
    check_model(distribution, shadowing, g1, fresnel)
    words = model_statement(distribution, shadowing, g1, fresnel)
    if engine != "grid" and (distribution != "ggx" or shadowing != ENGINE_SHADOWING[engine]):
        words += f"; NOT the {engine} engine's own model (GGX, {ENGINE_SHADOWING[engine]}) on its grid"
    return ({"shadowing": shadowing, "g1": g1, "fresnel": fresnel}, words,
            WALTER_SCALE if g1 == "walter" else 1.0)
