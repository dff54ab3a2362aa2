"""
A specimen turned over: the ``virtspec_flipped`` BSDF
=====================================================

The instrument lights its specimen from the upper hemisphere of the specimen frame
(θi ∈ [0°, 90°]). A BSDF file such as WINDOW's Klems XML also needs the *back*
side: light arriving from below. :class:`FlippedBSDF` wraps any BSDF and mirrors its
frame through the surface, (x, y, z) → (x, y, −z), for the incident and the outgoing
direction, so that the instrument's upper-hemisphere beam reaches the wrapped BSDF
from below and its fates are judged on the turned-over side (a ray the wrapped BSDF
sends back below the surface counts as reflected). The mirror keeps the azimuth of
every direction (the convention of Radiance's back-side Klems vectors, ``bsdf_m.c``:
``bo_getvec`` negates z only); for an isotropic specimen it equals turning the
specimen over by 180° about any in-plane axis.

Registered on demand (:func:`register`) under the name ``virtspec_flipped``; the nested
BSDF is given as ``nested`` (a dict or a loaded BSDF object):
``{"type": "virtspec_flipped", "nested": {"type": "roughdielectric", ...}}``. A
one-sided BSDF (``diffuse``, ``roughconductor``) absorbs light from its back, as
Mitsuba defines it; the project's leaf specimens have their own ``side`` parameter
for the abaxial face.

References
----------
Ward, G. et al. The Radiance BSDF library, ``ray/src/common/bsdf_m.c`` (back-side Klems
vectors). Mitsuba 3 ``BSDF`` interface (``sample``, ``eval``, ``pdf``).
"""

from __future__ import annotations

from typing import Any

import mitsuba as mi

from virtspec_mi.plugins.specimen import Parameter, specimen_of

__all__ = ["PLUGIN_NAME", "FlippedBSDF"]

PLUGIN_NAME: str = "virtspec_flipped"
"""The plugin's name in scene dicts (registered with the others: :data:`virtspec_mi.runtime.PLUGINS`)."""


def _mirror(v: Any) -> Any:
    return mi.Vector3f(v.x, v.y, -v.z)


class FlippedBSDF(mi.BSDF):
    """The nested BSDF with its frame mirrored through the surface (see the module docstring)."""

    # the specimen protocol: the nested specimen's range, flag and check (its parameters are under 'nested')
    PARAMETERS: tuple[Parameter, ...] = ()
    wavelength_range: tuple[float, float] | None = None
    wavelength_independent: bool = False

    def __init__(self, props: Any) -> None:
        super().__init__(props)
        nested = None
        for name in props.keys():
            value = props[name]
            if isinstance(value, mi.BSDF):
                nested = value
        if nested is None:
            raise ValueError(f"{PLUGIN_NAME}: give the BSDF to turn over as 'nested'")
        self.nested = nested
        self.m_components = [nested.flags(i) for i in range(nested.component_count())]
        self.m_flags = nested.flags()
        own = specimen_of(nested)  # the nested specimen's protocol, as it declares it (a Mitsuba BSDF: the defaults)
        self.wavelength_independent = own.wavelength_independent
        self.wavelength_range = own.wavelength_range
        self._nested_specimen = own

    def check_wavelengths(self, wavelengths: Any) -> None:
        """The nested specimen's check."""

        self._nested_specimen.check_wavelengths(wavelengths)

    def _turned(self, si: Any) -> Any:
        turned = mi.SurfaceInteraction3f(si)
        turned.wi = _mirror(si.wi)
        return turned

    def sample(self, ctx: Any, si: Any, sample1: Any, sample2: Any, active: Any = True) -> Any:
        bs, weight = self.nested.sample(ctx, self._turned(si), sample1, sample2, active)
        bs.wo = _mirror(bs.wo)
        return bs, weight

    def eval(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
        return self.nested.eval(ctx, self._turned(si), _mirror(wo), active)

    def pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
        return self.nested.pdf(ctx, self._turned(si), _mirror(wo), active)

    def eval_pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
        return self.nested.eval_pdf(ctx, self._turned(si), _mirror(wo), active)

    def traverse(self, callback: Any) -> None:
        callback.put("nested", self.nested, mi.ParamFlags.Differentiable)

    def to_string(self) -> str:
        return f"FlippedBSDF[nested={self.nested}]"

