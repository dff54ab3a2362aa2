"""
Shared pieces of random-walk specimens
======================================

Layered and turbid specimens (``abm_b``/``abm_u``, ``turbid_slab``) run an analog
random walk inside ``BSDF.sample``. They share two conventions with the
``spectrophotometer`` integrator:

- **Random numbers.** ``sample()`` receives only ``sample1`` and ``sample2``; the
  walk draws its numbers from a PCG32 seeded by the bits of those three uniforms
  (:func:`walk_rng`), so the walk is a pure function of the instrument's counter-based
  stream and counts stay independent of chunking.
- **Capped walks.** A walk stopped by a step cap has no fate. The BSDF reports it by
  setting ``bs.sampled_component = CAPPED_COMPONENT`` (weight 0); the integrator counts
  such rays in ``Result.capped``, apart from reflected, transmitted and absorbed, so a
  cap is never silently folded into a tally.

References
----------
Baranoski et al. (2001), Sect. 3 (each ray is reflected, transmitted or absorbed).
"""

from __future__ import annotations

from typing import Any

__all__ = ["CAPPED_COMPONENT", "walk_rng"]

CAPPED_COMPONENT: int = 0xFFFFFFFF
"""``BSDFSample3f.sampled_component`` of a walk that reached its step cap."""


def walk_rng(sample1: Any, sample2: Any) -> Any:
    """A per-lane ``mi.PCG32`` seeded from the bits of ``sample1`` and ``sample2``."""

    import drjit as dr
    import mitsuba as mi

    u0 = dr.reinterpret_array(mi.UInt32, mi.Float(sample1))
    u1 = dr.reinterpret_array(mi.UInt32, mi.Float(sample2.x))
    u2 = dr.reinterpret_array(mi.UInt32, mi.Float(sample2.y))
    rng = mi.PCG32()
    rng.seed(mi.sample_tea_64(u0, u1), mi.sample_tea_64(u2, u0 ^ u1))
    return rng
