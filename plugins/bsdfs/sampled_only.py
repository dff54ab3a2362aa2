"""
``SampledOnlyBSDF``: the base of specimens that exist only through ``sample()``
===============================================================================

The instrument's specimens (``simple_dielectric``, ``turbid_slab``, ``abm_b``,
``abm_u``) decide each ray's fate in ``sample()`` and have no evaluable density: every
lobe is either a delta or the outcome of a random walk. This base class gives them the
rest of Mitsuba's BSDF interface once: ``eval`` and ``pdf`` are zero, and there are no
differentiable parameters to traverse. It is not a plugin itself.

References
----------
Mitsuba 3, ``mi.BSDF`` (Python BSDF plugins).
"""

from __future__ import annotations

import mitsuba as mi

__all__ = ["SampledOnlyBSDF"]


class SampledOnlyBSDF(mi.BSDF):
    """A ``mi.BSDF`` whose subclasses implement ``sample()`` only (see the module docstring)."""

    def eval(self, ctx, si, wo, active=True):
        return mi.Spectrum(0.0)

    def pdf(self, ctx, si, wo, active=True):
        return mi.Float(0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return mi.Spectrum(0.0), mi.Float(0.0)

    def traverse(self, callback) -> None:
        pass

    def parameters_changed(self, keys) -> None:
        pass
