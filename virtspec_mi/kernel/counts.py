"""
Exact ray counts by name: the fates and the counts record
=========================================================

Every ray of a reading has one :class:`Fate`; a reading's counts are exact integers
(``int64``) held by name in :class:`Counts` — never columns by position. The kernel
produces them (:mod:`virtspec_mi.kernel.tracer`), the engine sums and reshapes them and
the result (:mod:`virtspec_mi.results.readings`) derives every quantity from them.

References
----------
Baranoski et al. (2001), eq. (2) (ρ = m/N) and Sect. 3 (each ray is reflected,
transmitted or absorbed).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from enum import IntEnum
from typing import Any, Callable

import numpy as np

__all__ = ["Fate", "QUANTITIES", "WEIGHT_ROUNDING", "DIRECTION_TOLERANCE", "Counts"]


class Fate(IntEnum):
    """What happened to one ray (the kernel's per-ray code)."""

    ABSORBED = 0
    REFLECTED = 1
    """Left into the upper hemisphere of the specimen (wo·n > 0)."""
    TRANSMITTED = 2
    """Left into the lower hemisphere (wo·n < 0)."""
    CAPPED = 3
    """A random walk stopped by the specimen's step cap: no fate, in none of R, T, A."""
    INVALID = 4
    """
    The BSDF returned an invalid outgoing direction (NaN or infinite components, or a
    length off 1 by more than :data:`DIRECTION_TOLERANCE`) with a weight that could let
    the ray survive: no fate, in none of R, T, A (``invalid_directions``).
    """


QUANTITIES: tuple[str, ...] = ("reflectance", "transmittance", "absorptance")
"""The certified quantities ρ, τ, α, from the reflected, transmitted and absorbed counts."""

WEIGHT_ROUNDING: float = 1e-4
"""
Rounding tolerance ε of BSDF sample weights. A weight w is a survival probability; one in
(1, 1 + ε] or [−ε, 0) is the numerical error of a weight of 1 or 0 and is used as 1 or 0,
counted in ``rounded_weights``; each such ray moves the estimate by at most ε/N. The
largest such error of Mitsuba 3.9.1's built-ins is 1 + 6.15·10⁻⁵, from the rational fit of
the Beckmann Smith G₁ (roughconductor, roughdielectric; float32 rounding alone stays below
10⁻⁶): ``tools/builtin_weights.py`` surveys them. Weights beyond, or NaN, are real
violations (``weight_violations``): the specimen is not energy conserving.
"""


DIRECTION_TOLERANCE: float = 1e-3
"""
Largest departure of a BSDF's outgoing direction from unit length, | |wo| − 1 |, that the
instrument accepts. Sampled directions are unit vectors up to float32 rounding (about
10⁻⁷; a few 10⁻⁶ after the hundreds of steps of a random walk); a direction beyond, or
with a NaN or infinite component, cannot be judged reflected or transmitted (NaN
compares false with everything) and counts in ``invalid_directions``.
"""


@dataclass(frozen=True, eq=False)
class Counts:
    """
    Exact counts of one or many readings, every field an ``int64`` array of one shape.

    ``absorbed = rays − reflected − transmitted − capped − invalid_directions``: capped
    walks and invalid directions (:attr:`Fate.INVALID`) are in no fate. ``specular_reflected`` and
    ``regular_transmitted`` are the reflected and transmitted rays whose sampled event
    was a delta event (parts of ``reflected`` / ``transmitted``). ``largest_weight``
    (float64) is the largest real violating weight seen per reading (NaN if none, or if
    every violating weight was NaN).
    """

    rays: np.ndarray
    reflected: np.ndarray
    transmitted: np.ndarray
    capped: np.ndarray
    invalid_directions: np.ndarray
    weight_violations: np.ndarray
    rounded_weights: np.ndarray
    specular_reflected: np.ndarray
    regular_transmitted: np.ndarray
    largest_weight: np.ndarray

    @classmethod
    def zeros(cls, shape: Any) -> "Counts":
        """Counts of ``shape`` readings that have traced nothing yet."""

        return cls(**{f.name: np.full(shape, np.nan) if f.name == "largest_weight"
                      else np.zeros(shape, dtype=np.int64) for f in fields(cls)})

    @property
    def absorbed(self) -> np.ndarray:
        return self.rays - self.reflected - self.transmitted - self.capped - self.invalid_directions

    def count(self, fate: Fate) -> np.ndarray:
        """The number of rays of each reading with ``fate``."""

        return {Fate.ABSORBED: self.absorbed, Fate.REFLECTED: self.reflected,
                Fate.TRANSMITTED: self.transmitted, Fate.CAPPED: self.capped,
                Fate.INVALID: self.invalid_directions}[Fate(fate)]

    def map(self, function: Callable[[np.ndarray], np.ndarray]) -> "Counts":
        """The same counts with ``function`` applied to every field (select, reshape …)."""

        return replace(self, **{f.name: function(getattr(self, f.name)) for f in fields(self)})

    @classmethod
    def concatenate(cls, parts: "list[Counts]") -> "Counts":
        """The readings of ``parts`` one after the other (1-d counts)."""

        if len(parts) == 1:
            return parts[0]
        return cls(**{f.name: np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(cls)})

    def put(self, index: Any, other: "Counts") -> None:
        """Write ``other``'s counts into readings ``index`` of these (in place)."""

        for item in fields(self):
            getattr(self, item.name)[index] = getattr(other, item.name)

    def add(self, index: Any, other: "Counts") -> None:
        """Add ``other``'s counts into readings ``index`` of these (in place; the largest weight: the larger)."""

        for item in fields(self):
            mine = getattr(self, item.name)
            if item.name == "largest_weight":
                mine[index] = np.fmax(mine[index], other.largest_weight)  # fmax keeps a weight over NaN (none)
            else:
                mine[index] += getattr(other, item.name)

    def as_dict(self) -> dict[str, np.ndarray]:
        """Every field by name (``absorbed`` included)."""

        return {**{f.name: getattr(self, f.name) for f in fields(self)}, "absorbed": self.absorbed}

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The stored fields, in order."""

        return tuple(f.name for f in fields(cls))
