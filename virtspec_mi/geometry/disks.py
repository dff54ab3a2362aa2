"""
Bench geometry: disks and the incidence rotation
=====================================================

The instrument is two disks (Fig. 1 of the paper): an emitter of radius r₁ whose
centre sits at distance D from the centre of a specimen of radius r₂. All geometry
here is written in the specimen's local frame: specimen centre at the origin,
normal +z (the "upper" hemisphere).

Incidence (θi, φi) rotates the emitter about the specimen centre: a point (x, y) of
the emitter disk goes to ``D·ω + x·e_u + y·e_v`` with

    ω   = (sin θ cos φ, sin θ sin φ, cos θ)      (towards the emitter)
    e_u = (cos θ cos φ, cos θ sin φ, −sin θ)
    e_v = (−sin φ, cos φ, 0)

i.e. the point (x, y, D) rotated by θ about y, then by φ about z
(:func:`~virtspec_mi.kernel.incidence.incidence_frame`, defined in the kernel, which
computes it; re-exported here).

Disk sampling (eqs. 3 and 4) runs in the kernel: :mod:`virtspec_mi.kernel.disk`.

References
----------
Baranoski et al. (2001), Sect. 3.2, eqs. (3) and (4), Fig. 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
import numpy as np

from virtspec_mi.base.checks import check_positive
from virtspec_mi.kernel.incidence import incidence_frame

__all__ = [
    "PAPER_EMITTER_RADIUS",
    "PAPER_SPECIMEN_RADIUS",
    "PAPER_DISTANCE",
    "InstrumentGeometry",
    "incidence_frame",
    "backlit_fraction",
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
