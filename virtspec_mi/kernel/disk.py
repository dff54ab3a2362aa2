"""
Disk sampling in the kernel: eqs. (3) and (4) and Shirley–Chiu
==============================================================

Disk sampling (all uniform by area; the tests check it statistically):

- ``random``: eq. (3), points uniform in the square [−r, r]², rejected outside the disk;
- ``jittered``: eq. (4), the polar warp (2πξ₁, r√ξ₂) of stratified (ξ₁, ξ₂). The
  emitter disk is stratified over an n × n grid, n = ⌊√N⌋: ray j < n² of a reading
  lies in cell j (rays past n², fewer than 2√N + 1, are unstratified). The specimen
  point of every ray is an independent polar-warped uniform point, so each ray's
  emitter/specimen pair is unbiased and the rays stay independent (Hoeffding's
  inequality holds for independent, non-identical Bernoulli trials);
- ``concentric``: Shirley–Chiu's concentric map (Mitsuba's ``disk`` sampling).

References
----------
Baranoski et al. (2001), Sect. 3.2, eqs. (3) and (4).
"""

from __future__ import annotations

from typing import Any

__all__ = ["jittered_cell", "polar_warp", "sample_disk"]


def jittered_cell(mi: Any, u1: Any, u2: Any, ray: Any, strata: Any) -> tuple[Any, Any]:
    """
    Stratify (u1, u2) into cell ``ray`` of a ``strata × strata`` grid (row-major);
    rays at or past ``strata²`` keep their unstratified (u1, u2).
    """

    import drjit as dr

    row = mi.UInt32(dr.floor(mi.Float64(ray) / mi.Float64(strata)))
    column = ray - row * strata
    inside = ray < strata * strata
    inv = dr.rcp(mi.Float(strata))
    return (
        dr.select(inside, (mi.Float(column) + u1) * inv, u1),
        dr.select(inside, (mi.Float(row) + u2) * inv, u2),
    )


def polar_warp(mi: Any, u1: Any, u2: Any, radius: Any) -> Any:
    """Eq. (4): (φ, r) = (2πξ₁, R√ξ₂) as a point (x, y) of the disk of radius R."""

    import drjit as dr

    sin_phi, cos_phi = dr.sincos(dr.two_pi * u1)
    r = radius * dr.sqrt(u2)
    return mi.Point2f(r * cos_phi, r * sin_phi)


def sample_disk(mi: Any, sampling: str, u1: Any, u2: Any, radius: Any, rejection: Any = None) -> Any:
    """
    A point of the disk of radius ``radius`` from uniforms (u1, u2) by ``sampling``.

    ``random`` needs ``rejection``: a callable ``rejection(radius)`` that runs the
    square-and-reject loop of eq. (3) with fresh random numbers (it cannot be a pure
    function of two uniforms). ``jittered`` expects (u1, u2) already stratified.
    """

    if sampling == "concentric":
        return mi.warp.square_to_uniform_disk_concentric(mi.Point2f(u1, u2)) * radius
    if sampling == "jittered":
        return polar_warp(mi, u1, u2, radius)
    if sampling == "random":
        return rejection(radius)
    raise ValueError(f"sampling must be one of jittered, random, concentric (got {sampling!r})")
