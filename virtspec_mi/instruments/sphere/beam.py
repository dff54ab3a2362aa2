"""
A sphere's beam: its cross-section, its divergence, and the spill past the specimen
===================================================================================

By default a sphere's beam is the bench's: a collimated pencil that meets the specimen at
its centre (the kernel's first interaction). A :class:`BeamProfile` makes it a real beam,
**traced** from the entrance into the sphere by the sphere walk itself
(:mod:`virtspec_mi.instruments.sphere.real`):

- **shape** ``"point"``, ``"ellipse"`` or ``"rectangle"``: the cross-section
  perpendicular to the beam's axis, uniform over ``width`` × ``height`` (mm, full sizes;
  width along u, the specimen frame's x projected onto the cross-section plane, height
  along v = b × u, b the direction of travel). The axis passes through the specimen's
  centre.
- **divergence** β (degrees, 0 ≤ β < 30): each ray's direction is uniform over the solid
  angle of the cone of half-angle β about the axis, independently of its place in the
  cross-section (a partially collimated beam of uniform radiance).

Each ray starts on its line inside the sphere (where the line crosses the plane through
the sphere's centre normal to the specimen port's axis) and the walk finds what it meets:
the specimen (its BSDF sampled at the hit point, with the ray's own direction), the
opening around a smaller specimen (lost through the port), the wall round the port, or
the wall of a deep port. **Beam spill**: the rays whose first surface is not the
specimen, counted per reading (the count ``beam_spill``). A traced beam is for
reflectance readings with ``beam="collimated"``; the hemispherical reading beside it
stays the kernel's (the specimen's at the nominal angle, its centre), so the instrument
error includes what the beam's size, divergence and spill do. The clipping of the beam by
the entrance port is not modelled (the beam is taken as formed inside the sphere).

``BeamProfile("point")`` with β = 0 is the bench's beam: a sphere keeps no profile then,
and its readings are today's, bit for bit.

References
----------
Prokhorov, Mekhontsev & Hanssen (2003), Appl. Opt. 42(19), 3832 (sphere geometry errors,
beam size); Prahl, *Inverse Adding-Doubling* (users ask for rectangular beams:
scottprahl/iad issue 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from virtspec_mi.base.checks import number

__all__ = ["BEAM_SHAPES", "BeamProfile", "parse_beam_profile", "beam_profile_of"]

BEAM_SHAPES: tuple[str, ...] = ("point", "ellipse", "rectangle")
"""The cross-sections of a beam."""

MAX_DIVERGENCE: float = 30.0
"""The largest divergence half-angle accepted, degrees (exclusive)."""


@dataclass(frozen=True)
class BeamProfile:
    """
    A beam's cross-section and divergence (see the module docstring).

    Parameters
    ----------
    shape : str
        ``"point"`` (default), ``"ellipse"`` or ``"rectangle"``.
    width, height : float or None
        Full sizes of the cross-section, mm (> 0; only for an ellipse or a rectangle).
    divergence : float
        Half-angle of the cone of directions, degrees, 0 ≤ divergence < 30 (default 0).
    """

    shape: str = "point"
    width: float | None = None
    height: float | None = None
    divergence: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.shape, str) or self.shape not in BEAM_SHAPES:
            raise ValueError(f"beam_profile shape must be one of {', '.join(BEAM_SHAPES)} (got {self.shape!r})")
        for key in ("width", "height"):
            value = getattr(self, key)
            if self.shape == "point":
                if value is not None:
                    raise ValueError(f"beam_profile {key} is for shape ellipse or rectangle (a point beam has none)")
                continue
            if value is None:
                raise ValueError(f"beam_profile shape {self.shape} needs {key} > 0 mm")
            size = number(f"beam_profile {key}", value)
            if not (math.isfinite(size) and size > 0.0):
                raise ValueError(f"beam_profile {key} must be a finite number > 0 mm (got {value!r})")
            object.__setattr__(self, key, size)
        beta = number("beam_profile divergence", self.divergence)
        if not (math.isfinite(beta) and 0.0 <= beta < MAX_DIVERGENCE):
            raise ValueError(f"beam_profile divergence must satisfy 0 <= divergence < {MAX_DIVERGENCE:g} degrees "
                             f"(half-angle; got {self.divergence!r})")
        object.__setattr__(self, "divergence", beta)

    @property
    def trivial(self) -> bool:
        """True for the bench's beam: a point without divergence."""

        return self.shape == "point" and self.divergence == 0.0

    def half_sizes(self) -> tuple[float, float]:
        """(a, b): semi-axes or half-widths, mm (0, 0 for a point)."""

        return (0.0, 0.0) if self.shape == "point" else (self.width / 2.0, self.height / 2.0)

    def text(self) -> str:
        """``"shape=… width=… height=… divergence=…"`` (:func:`parse_beam_profile` reads it back)."""

        sizes = "" if self.shape == "point" else f" width={self.width!r} height={self.height!r}"
        return f"shape={self.shape}{sizes} divergence={self.divergence!r}"


def parse_beam_profile(text: str) -> BeamProfile:
    """A profile from its text, e.g. ``"shape=rectangle width=7 height=4 divergence=0.5"``."""

    items: dict[str, str] = {}
    for token in str(text).replace(";", " ").split():
        key, sep, value = token.partition("=")
        if not sep or key not in ("shape", "width", "height", "divergence"):
            raise ValueError(f"beam_profile: expected 'key=value' items with keys shape, width, height, divergence "
                             f"(got {token!r})")
        items[key] = value
    try:
        sizes = {k: float(items[k]) for k in ("width", "height", "divergence") if k in items}
    except ValueError as error:
        raise ValueError(f"beam_profile: width, height and divergence must be numbers ({error})") from None
    return BeamProfile(items.get("shape", "point"), **sizes)


def beam_profile_of(value: Any) -> BeamProfile | None:
    """A sphere's profile: ``None`` for none or the bench's beam (a point without divergence), else validated."""

    if value is None:
        return None
    if isinstance(value, str):
        value = parse_beam_profile(value)
    if not isinstance(value, BeamProfile):
        raise ValueError("beam_profile must be a virtspec_mi BeamProfile, its text 'shape=... width=... height=... "
                         f"divergence=...' or None (got {type(value).__name__})")
    return None if value.trivial else value
