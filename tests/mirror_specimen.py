"""
Test specimens built on a mirror: register a ``sample()`` that changes the mirror's
outgoing direction, weight or component per ray, without writing the rest of a BSDF.
"""

from __future__ import annotations

from typing import Any, Callable


def register_mirror(mi: Any, name: str, change: Callable[..., tuple[Any, Any]]) -> str:
    """
    Register ``name``: a delta-reflecting specimen whose ``sample`` builds the mirror
    sample (``wo`` = reflect(wi), pdf 1, weight 1) and returns ``change(bs, weight,
    sample1, si, props)``. Returns ``name``.
    """

    import drjit as dr

    from virtspec_mi.plugins.bsdfs.sampled_only import SampledOnlyBSDF

    class Mirror(SampledOnlyBSDF):
        def __init__(self, props):
            super().__init__(props)
            self.props = {key: props.get(key) for key in props.keys()}
            self.m_flags = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.reflect(si.wi)
            bs.pdf = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DeltaReflection)
            return change(bs, mi.Spectrum(1.0), sample1, si, self.props)

    mi.register_bsdf(name, lambda props: Mirror(props))
    return name
