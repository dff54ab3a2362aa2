"""
Instrument geometry: disks, incidence rotation and disk sampling
================================================================

The instrument is two disks (Fig. 1 of the paper): an emitter of radius r₁ whose
centre sits at distance D from the centre of a specimen of radius r₂. All geometry
here is written in the specimen's local frame: specimen centre at the origin,
normal +z (the "upper" hemisphere).

Incidence (θi, φi) rotates the emitter about the specimen centre: a point (x, y) of
the emitter disk goes to ``D·ω + x·e_u + y·e_v`` with

    ω   = (sin θ cos φ, sin θ sin φ, cos θ)      (towards the emitter)
    e_u = (cos θ cos φ, cos θ sin φ, −sin θ)
    e_v = (−sin φ, cos φ, 0)

i.e. the point (x, y, D) rotated by θ about y, then by φ about z.

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
Baranoski et al. (2001), Sect. 3.2, eqs. (3) and (4), Fig. 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.settings import check_positive

__all__ = [
    "PAPER_EMITTER_RADIUS",
    "PAPER_SPECIMEN_RADIUS",
    "PAPER_DISTANCE",
    "InstrumentGeometry",
    "incidence_frame",
    "backlit_fraction",
    "jittered_cell",
    "polar_warp",
    "sample_disk",
]

PAPER_EMITTER_RADIUS: float = 8.0
"""r₁ in mm (paper, Sect. 5.1)."""
PAPER_SPECIMEN_RADIUS: float = 12.5
"""r₂ in mm (paper, Sect. 5.1)."""
PAPER_DISTANCE: float = 100.0
"""D in mm (paper, Sect. 5.1)."""


@dataclass(frozen=True)
class InstrumentGeometry:
    """Emitter radius r₁, specimen radius r₂ and centre distance D (any one length unit)."""

    emitter_radius: float = PAPER_EMITTER_RADIUS
    specimen_radius: float = PAPER_SPECIMEN_RADIUS
    distance: float = PAPER_DISTANCE

    def __post_init__(self) -> None:
        for name in ("emitter_radius", "specimen_radius", "distance"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))

    @property
    def backlit_threshold(self) -> float:
        """θi (degrees) beyond which part of the emitter lies below the specimen plane: atan(D/r₁)."""

        return math.degrees(math.atan2(self.distance, self.emitter_radius))


def incidence_frame(theta_i: float, phi_i: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ω, e_u, e_v) for incidence angles in degrees (see the module docstring)."""

    t, p = math.radians(theta_i), math.radians(phi_i)
    ct, st, cp, sp = math.cos(t), math.sin(t), math.cos(p), math.sin(p)
    omega = np.array([st * cp, st * sp, ct])
    e_u = np.array([ct * cp, ct * sp, -st])
    e_v = np.array([-sp, cp, 0.0])
    return omega, e_u, e_v


def backlit_fraction(geometry: InstrumentGeometry, theta_i: float) -> float:
    """
    Fraction of the emitter's area below the specimen plane at incidence θi (degrees).

    A conical ray leaving that part strikes the specimen's back face. The emitter point
    ``D·ω + x·e_u + y·e_v`` has height ``D cos θ − x sin θ``: the part with
    ``x > a = D cot θ`` is a circular segment of the emitter disk.
    """

    r, t = geometry.emitter_radius, math.radians(theta_i)
    if math.sin(t) <= 0.0:
        return 0.0
    a = geometry.distance * math.cos(t) / math.sin(t)
    if a >= r:
        return 0.0
    segment = r * r * math.acos(a / r) - a * math.sqrt(r * r - a * a)
    return segment / (math.pi * r * r)


# --- Device code (Dr.Jit arrays of the current Mitsuba variant) ------------------------


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
