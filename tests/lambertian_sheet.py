"""
A test specimen: a Lambertian sheet (diffuse reflectance rho and transmittance tau, the same from both sides)
=============================================================================================================

The double-sphere exchange model's specimen (:mod:`virtspec_mi.instruments.sphere.double_theory`), as a
Mitsuba BSDF for the tests: ``sample()`` reflects with probability rho and transmits with probability tau,
each into the cosine-weighted hemisphere of its side, and absorbs the rest (weight 0). Registered as
``test_lambertian_sheet`` by :func:`register` (under the current variant).
"""

from __future__ import annotations

from typing import Any

__all__ = ["NAME", "register", "sheet"]

NAME = "test_lambertian_sheet"


def sheet(rho: float, tau: float) -> dict[str, Any]:
    """The sheet's plugin dict."""

    return {"type": NAME, "rho": float(rho), "tau": float(tau)}


def register() -> None:
    """Register the sheet with Mitsuba (after ``vm.mitsuba()``)."""

    import drjit as dr
    import mitsuba as mi

    from virtspec_mi.plugins.bsdfs.sampled_only import SampledOnlyBSDF  # eval and pdf: zero (sampled only)

    class Sheet(SampledOnlyBSDF):
        def __init__(self, props: Any) -> None:
            super().__init__(props)
            self.rho, self.tau = float(props.get("rho", 0.4)), float(props.get("tau", 0.4))
            self.m_flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.DiffuseTransmission
            self.m_components = [mi.BSDFFlags.DiffuseReflection, mi.BSDFFlags.DiffuseTransmission]

        def sample(self, ctx, si, sample1, sample2, active=True):
            up = mi.Frame3f.cos_theta(si.wi) > 0
            local = mi.warp.square_to_cosine_hemisphere(sample2)
            reflect = sample1 < self.rho
            transmit = ~reflect & (sample1 < self.rho + self.tau)
            flip = dr.select(reflect == up, 1.0, -1.0)
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.Vector3f(local.x, local.y, local.z * flip)
            bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(local)
            bs.eta = 1.0
            bs.sampled_type = dr.select(reflect, mi.UInt32(+mi.BSDFFlags.DiffuseReflection),
                                        mi.UInt32(+mi.BSDFFlags.DiffuseTransmission))
            bs.sampled_component = dr.select(reflect, mi.UInt32(0), mi.UInt32(1))
            return bs, mi.Spectrum(dr.select(reflect | transmit, 1.0, 0.0))

        def to_string(self) -> str:
            return f"LambertianSheet[rho={self.rho}, tau={self.tau}]"

    mi.register_bsdf(NAME, lambda props: Sheet(props))
