"""
``prospect_d``: the PROSPECT-D leaf as a Lambertian reflector and transmitter
=============================================================================

The plate model of PROSPECT-D (Féret et al. 2017; :mod:`.prospect_model`) gives a leaf's
directional-hemispherical reflectance R(λ) and transmittance T(λ) for a beam from a cone
of 40° about the normal. The model assumes the leaf scatters both ways as a Lambertian
surface; this plugin is that assumption made a specimen: a ray at wavelength λ is
reflected with probability R(λ) into a cosine-distributed direction on its own side,
transmitted with probability T(λ) into one on the other side, else absorbed (unit
weights, like the other specimens). So the instrument measures R and T of the model —
within its certificate — at any θi (the model does not depend on θi) and for back-lit rays
(the leaf is taken as symmetric). It is the peer of ``abm_b``/``abm_u`` with PROSPECT's
inputs: ``vm.compare`` of one against the other, and fits (:mod:`virtspec_mi.applications.fitting`).

R and T are computed (NumPy, float64) on the coefficients' 1 nm grid when the specimen is
loaded or a parameter changes, and read per ray by linear interpolation at the ray's
wavelength (channel 0 of ``si.wavelengths``, float32): the tables are data, one compiled
kernel serves every leaf.

Parameters
----------
N : float, default 1.5
    Leaf structure parameter, the number of plates, 1 ≤ N ≤ 4.
Cab : float, default 40
    Chlorophylls a + b, µg cm⁻², 0 … 150.
Car : float, default 8
    Carotenoids, µg cm⁻², 0 … 40.
Anth : float, default 0
    Anthocyanins, µg cm⁻², 0 … 40.
Cbrown : float, default 0
    Brown pigments, arbitrary units, 0 … 4.
Cw : float, default 0.01
    Equivalent water thickness, cm, 0 … 0.1.
Cm : float, default 0.009
    Leaf mass per area (dry matter), g cm⁻², 0 … 0.05.
data : string, default ""
    Path of the coefficient table (eight columns: wavelength, n, K_Cab, K_Car, K_Anth,
    K_Cbrown, K_Cw, K_Cm); empty = ``$VIRTSPEC_PROSPECT_DATA``, else the table shipped
    with virtspec-mi (Féret et al. 2017, MIT; :func:`.prospect_model.prospect_coefficients`).

Every number is exposed to ``mi.traverse`` (``specimen.bsdf.Cab`` …; short form
``specimen.Cab``) and range-checked on update (``ValueError`` naming the parameter and its
range; the leaf is left as it was), so sweeps and fits reuse the compiled kernel.
``wavelength_range`` is the coefficients' (400–2500 nm): the instrument refuses others.

References
----------
Féret, Gitelson, Noble & Jacquemoud (2017), RSE 193:204–215; Jacquemoud & Baret (1990),
RSE 34:75–91 (the Lambertian plates).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from virtspec_mi.plugins.bsdfs.prospect_model import (
    PROSPECT_DEFAULTS,
    PROSPECT_PARAMETERS,
    check_prospect_parameters,
    prospect_coefficients,
    prospect_d,
)
from virtspec_mi.plugins.bsdfs.sampled_only import SampledOnlyBSDF
from virtspec_mi.plugins.specimen import Parameter

__all__ = ["ProspectD"]


class ProspectD(SampledOnlyBSDF):
    """PROSPECT-D's R(λ) and T(λ) as a Lambertian reflector/transmitter (see the module docstring)."""

    PLUGIN = "prospect_d"
    PARAMETERS = tuple(Parameter(name, low, high, unit or "1", meaning)
                       for name, (_, low, high, unit, meaning) in PROSPECT_PARAMETERS.items())

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        self.coefficients = prospect_coefficients(props.get("data", "") or None)
        grid = self.coefficients.wavelengths
        steps = np.diff(grid)
        if not np.allclose(steps, steps[0]):
            raise ValueError(f"prospect_d: the coefficient table ({self.coefficients.source}) must have evenly "
                             "spaced wavelengths")
        self._start, self._step = float(grid[0]), float(steps[0])
        self.wavelength_range = (float(grid[0]), float(grid[-1]))
        values = {}
        for name in PROSPECT_PARAMETERS:
            value = props.get(name, PROSPECT_DEFAULTS[name]) if name in props else PROSPECT_DEFAULTS[name]
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"prospect_d: '{name}' must be a number (got {value!r})")
            values[name] = float(value)
        self.values: dict[str, float] = {}
        self._apply(values)
        both_sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        self.m_components = [mi.BSDFFlags.DiffuseReflection | both_sides,
                             mi.BSDFFlags.DiffuseTransmission | both_sides]
        self.m_flags = self.m_components[0] | self.m_components[1]

    def _apply(self, values: dict[str, float]) -> None:
        check_prospect_parameters(values)  # ValueError before anything changes
        reflectance, transmittance = prospect_d(coefficients=self.coefficients, **values)
        self.values = dict(values)
        self.reflectance, self.transmittance = reflectance, transmittance
        self._r = mi.Float(reflectance.astype(np.float32))
        self._rt = mi.Float((reflectance + transmittance).astype(np.float32))
        dr.eval(self._r, self._rt)

    def exposed_parameters(self) -> dict[str, float]:
        """``N``, ``Cab``, ``Car``, ``Anth``, ``Cbrown``, ``Cw``, ``Cm``, for ``mi.traverse``."""

        return dict(self.values)

    def set_parameters(self, values: dict[str, float]) -> None:
        """New values (checked as at load time; ``ValueError`` leaves the leaf as it was)."""

        unknown = sorted(set(values) - set(PROSPECT_PARAMETERS))
        if unknown:
            raise ValueError(f"prospect_d: no parameter {unknown[0]!r} (known: {', '.join(PROSPECT_PARAMETERS)})")
        if values:
            self._apply({**self.values, **values})

    def _lookup(self, wavelength: mi.Float) -> tuple[mi.Float, mi.Float]:
        last = dr.width(self._r) - 1
        x = (wavelength - self._start) * (1.0 / self._step)
        j = mi.UInt32(dr.clip(dr.floor(x), 0, last - 1))
        f = dr.clip(x - mi.Float(j), 0.0, 1.0)
        return tuple(dr.lerp(dr.gather(mi.Float, t, j), dr.gather(mi.Float, t, j + 1), f) for t in (self._r, self._rt))

    def sample(self, ctx, si, sample1, sample2, active=True):
        r, rt = self._lookup(si.wavelengths[0])
        reflect = sample1 < r
        exits = sample1 < rt
        lit_above = mi.Frame3f.cos_theta(si.wi) >= 0.0
        up = reflect == lit_above  # reflected light stays on the lit side
        wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.Vector3f(wo.x, wo.y, dr.select(up, wo.z, -wo.z))
        bs.pdf = dr.select(exits, 1.0, 0.0)
        bs.eta = 1.0
        bs.sampled_component = dr.select(reflect, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(reflect, mi.UInt32(+mi.BSDFFlags.DiffuseReflection),
                                    mi.UInt32(+mi.BSDFFlags.DiffuseTransmission))
        weight = dr.select(mi.Bool(active) & exits, 1.0, 0.0)
        return bs, mi.Spectrum(weight)

    def to_string(self) -> str:
        listed = ", ".join(f"{name}={value:g}" for name, value in self.values.items())
        return f"ProspectD[{listed}]"
