"""
``simple_dielectric``: the paper's simplified Fresnel dielectric
=================================================================

A smooth dielectric interface that *chooses* each ray's fate: with probability
F(θ, η) (unpolarised Fresnel reflectance) the ray is reflected specularly, otherwise
it is refracted; the weight is always 1, so a virtual spectrophotometer counting
rays measures R = F(θ, η) and T = 1 − F(θ, η) exactly in expectation.

The paper (Sect. 5.1) writes the test as "if F ≤ ξ the ray is reflected", which
would reflect with probability 1 − F; this plugin reflects when ξ < F, and the test
suite checks that the measured reflectance equals the Fresnel reflectance.

The model ignores wavelength: :attr:`SimpleDielectric.wavelength_independent` is
``True``.

Parameters
----------
eta : float, default 2.419
    Relative index of refraction (interior / exterior), 10⁻⁶ ≤ η ≤ 10⁶ (:data:`ETA_RANGE`;
    booleans, NaN and infinities are refused). 2.419 is diamond
    (the paper's specimen). η = 1 is no interface: R = 0 exactly, even at grazing
    incidence. Exposed to ``mi.traverse`` as ``eta`` (an opaque value: a new η reuses
    the compiled kernel, except a change to or from η = 1 or across
    :data:`NEAR_ONE`, branches of their own).

Notes
-----
Near η = 1 Mitsuba's float32 ``mi.fresnel`` cancels catastrophically (1 − sin²θi/η² and
cos θi − η cos θt lose every digit of η − 1): at η = 1 ± 10⁻⁶ it gives F wrong by up to
0.68 near grazing incidence, and float32 cannot even hold η − 1 below 6·10⁻⁸. For
0 < |η − 1| < :data:`~virtspec_mi.kernel.walk_optics.NEAR_ONE` the plugin therefore
evaluates the same Fresnel equations in a cancellation-free form from η − 1 (kept apart,
computed in float64 on the host; :func:`virtspec_mi.kernel.walk_optics.fresnel_near_one`,
which the random walks' interfaces use too):
with n the index seen by the ray, a = n² − 1 = (n − 1)(n + 1) and c = |cos θi|,
cos²θt = (a + c²)/n², r_s = −a/(c + n cos θt)², r_p = a(c²(n² + 1) − 1)/(n²(n c + cos θt)²).
Compared with a float64 Fresnel over a grid of η (|η − 1| from 10⁻¹² to 0.1) and θ
(10⁶ angles over [0°, 90°], from both sides) it agrees within 10⁻⁴ everywhere except
within 10⁻⁴ degrees of a critical angle, where F itself has an infinite slope; there is
no η ≠ 1 left to refuse (``tests/plugins/bsdfs/test_simple_dielectric.py``). Away from η = 1
``mi.fresnel`` is used, as before (within 10⁻³ of float64 on the same grid).

References
----------
Baranoski, Rokne & Xu (2001), Sect. 5.1; Fresnel equations as in ``mi.fresnel``
(M. Born & E. Wolf, *Principles of Optics*, 7th ed., Sect. 1.5.2).
"""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi

from virtspec_mi.base.checks import check_float32
from virtspec_mi.kernel.walk_optics import NEAR_ONE, fresnel_near_one
from virtspec_mi.plugins.bsdfs.sampled_only import SampledOnlyBSDF
from virtspec_mi.plugins.specimen import Parameter

__all__ = ["SimpleDielectric", "ETA_RANGE"]

ETA_RANGE: tuple[float, float] = (1e-6, 1e6)
"""
Relative indices η accepted. Mitsuba's float32 Fresnel arithmetic (η², 1/η²) is exact
enough here (tested at both ends, θi = 0, 30, 89, 90°); beyond it gives NaN directions
(η ≤ 10⁻²⁰) or wrong grazing reflectances (η ≥ 10¹⁴).
"""


class SimpleDielectric(SampledOnlyBSDF):
    """Coin-flip Fresnel dielectric with unit weights (see the module docstring)."""

    wavelength_independent: bool = True
    PARAMETERS = (Parameter("eta", *ETA_RANGE, "1", "relative refractive index (specimen / outside)"),)

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        self._set_eta(props.get("eta", 2.419))
        both_sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        self.m_components = [
            mi.BSDFFlags.DeltaReflection | both_sides,
            mi.BSDFFlags.DeltaTransmission | both_sides | mi.BSDFFlags.NonSymmetric,
        ]
        self.m_flags = self.m_components[0] | self.m_components[1]

    def _set_eta(self, eta: Any) -> None:
        low, high = ETA_RANGE
        self.eta = check_float32("simple_dielectric: 'eta'", eta,
                                 f"be a number > 0 with {low:g} <= eta <= {high:g}", lambda value: low <= value <= high)
        self._eta = dr.opaque(mi.Float, self.eta)  # data, not code: a new eta reuses the compiled kernel
        self._near_one = 0.0 < abs(self.eta - 1.0) < NEAR_ONE

    def exposed_parameters(self) -> dict[str, float]:
        """``eta``, for ``mi.traverse``."""

        return {"eta": self.eta}

    def set_parameters(self, values: dict[str, float]) -> None:
        """A new ``eta`` (checked as at load time; ``ValueError`` leaves the specimen as it was)."""

        unknown = sorted(set(values) - {"eta"})
        if unknown:
            raise ValueError(f"simple_dielectric: no parameter {unknown[0]!r} (known: eta)")
        if "eta" in values:
            self._set_eta(values["eta"])

    def sample(self, ctx, si, sample1, sample2, active=True):
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        fresnel, cos_theta_t, eta_it, eta_ti = mi.fresnel(cos_theta_i, self._eta)
        if self._near_one:  # the same equations without cancellation (module docstring)
            fresnel, cos_theta_t = fresnel_near_one(cos_theta_i, self.eta - 1.0)
        if self.eta == 1.0:
            # No interface at all: F = 0 at every angle (float32 Fresnel would round the
            # grazing limit cos θ → 0 up to F = 1).
            fresnel = mi.Float(0.0)
        reflect = sample1 < fresnel
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = dr.select(reflect, mi.reflect(si.wi), mi.refract(si.wi, cos_theta_t, eta_ti))
        bs.pdf = dr.select(reflect, fresnel, 1.0 - fresnel)
        bs.eta = dr.select(reflect, 1.0, eta_it)
        bs.sampled_component = dr.select(reflect, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(
            reflect,
            mi.UInt32(+mi.BSDFFlags.DeltaReflection),
            mi.UInt32(+mi.BSDFFlags.DeltaTransmission),
        )
        return bs, dr.select(active, mi.Spectrum(1.0), mi.Spectrum(0.0))

    def to_string(self) -> str:
        return f"SimpleDielectric[eta={self.eta}]"
