"""
Real ports: a port wall of given depth, elliptical and rectangular openings
===========================================================================

A :class:`~virtspec_mi.instruments.sphere.geometry.Port` is by default a *knife edge*:
a circular hole of radius r whose rim is the rim of its spherical cap (no wall). This
module holds what a real port adds, each validated where it enters:

- **depth** d (mm, ≥ 0): the port is a hole drilled through a wall of that thickness, a
  cylinder of radius r along the port's axis from the rim plane (x·c = R cos α) to the
  plane x·c = R cos α + d. A specimen, standard or detector sits at the *outer* end of
  the cylinder (a specimen in a deep port is recessed by d); light that enters the
  cylinder may meet its wall, which absorbs with probability 1 − ρe and otherwise
  re-emits Lambertian about its inward normal (towards the axis). d = 0 is the knife
  edge, walked exactly as before (the same kernel, bit for bit).
- **edge_reflectance** ρe in [0, 1] of that cylinder wall (default: the sphere's wall
  reflectance ρw(λ), a wall coated like the sphere).
- **shape**: ``"circle"`` (radius r), ``"ellipse"`` or ``"rectangle"`` (full ``width``
  along the port's first in-plane axis e₁ and ``height`` along e₂, mm). A non-circular
  port is the set of wall points whose projection onto the port's tangent plane falls in
  the shape (a knife edge: its depth must be 0); its ``radius`` is the circumscribed
  circle's (used for the overlap check); its cap fraction is the exact area of that set
  over the sphere's (:func:`shaped_fraction`, one quadrature in azimuth). The frame
  (:func:`port_frame`): e₁ is the sphere's +x projected onto the port's tangent plane
  (+y when the axis is within 25° of ±x), e₂ = c × e₁. A non-circular port cannot hold a
  specimen or a standard (its rim is not planar): only the ``detector``, ``specular``,
  ``open`` roles and the ``entrance`` of a reflectance reading may be non-circular.
- **aperture**, **mask_reflectance**: a holder mask (a clip) in front of what the port
  holds, a flat annulus from the aperture (0 < aperture < r) to the port's radius in the
  holder's plane, Lambertian of reflectance ρm (default ρw(λ)), facing the sphere.
- **proud** s (mm, ≥ 0): what the port holds stands s into the sphere, on a post of its
  own radius from the rim plane to the plane x·c = R cos α − s; the post's side reflects
  ``edge_reflectance`` (Lambertian); a crossing of that plane outside the disk flies on.
- **field_of_view** γ (a detector, 0 < γ ≤ 90 degrees): a ray reaching the detector
  counts when its direction is within γ of the port's axis, else it is lost (the
  detector's housing); 90 is the whole hemisphere (stored as ``None``).

References
----------
Goebel (1967) (port fractions); Prahl, *Inverse Adding-Doubling* (users ask for
non-circular ports: scottprahl/iad issue 2); the area of a region of the sphere over its
tangent-plane projection: dA = R/√(R² − ρ²) dx dy.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from virtspec_mi.base.checks import number
from virtspec_mi.instruments.sphere.real import port_frame

__all__ = ["SHAPES", "check_port_extras", "port_frame", "shaped_fraction", "shaped_area", "contains",
           "extras_text", "EXTRA_KEYS"]

SHAPES: tuple[str, ...] = ("circle", "ellipse", "rectangle")
"""The shapes of a port's opening."""

EXTRA_KEYS: tuple[str, ...] = ("depth", "edge_reflectance", "shape", "width", "height", "aperture",
                               "mask_reflectance", "field_of_view", "proud")
"""The keys of a port's text beyond role, polar, azimuth and radius."""


def _finite(name: str, value: Any) -> float:
    result = number(name, value)
    if not math.isfinite(result):
        raise ValueError(f"{name} must be a finite number (got {value!r})")
    return result


def check_port_extras(port: Any) -> None:
    """
    Validate (and normalise, on the frozen ``port``) depth, edge_reflectance, shape,
    width and height; a non-circular port's ``radius`` becomes its circumscribed radius.
    Each error names the parameter and its allowed range.
    """

    name = port.name
    depth = _finite(f"port {name!r} depth", port.depth)
    if not depth >= 0.0:
        raise ValueError(f"port {name!r}: depth must satisfy depth >= 0 mm (0: a knife edge; got {depth:g})")
    object.__setattr__(port, "depth", depth)
    if port.edge_reflectance is not None:
        rho = _finite(f"port {name!r} edge_reflectance", port.edge_reflectance)
        if not 0.0 <= rho <= 1.0:
            raise ValueError(f"port {name!r}: edge_reflectance must satisfy 0 <= edge_reflectance <= 1 "
                             f"(got {rho:g}; omit it for the sphere's wall reflectance)")
        object.__setattr__(port, "edge_reflectance", rho)
    if not isinstance(port.shape, str) or port.shape not in SHAPES:
        raise ValueError(f"port {name!r}: shape must be one of {', '.join(SHAPES)} (got {port.shape!r})")
    _check_mask(port)
    proud = _finite(f"port {name!r} proud", port.proud)
    if not proud >= 0.0:
        raise ValueError(f"port {name!r}: proud must satisfy proud >= 0 mm (0: in the rim plane; got {proud:g})")
    object.__setattr__(port, "proud", proud)
    if proud and (depth > 0.0 or port.aperture is not None):
        raise ValueError(f"port {name!r}: proud (a specimen standing into the sphere) excludes depth and aperture "
                         "(give depth for a recessed specimen, aperture for a mask in the rim plane)")
    if port.field_of_view is not None:
        gamma = _finite(f"port {name!r} field_of_view", port.field_of_view)
        if not 0.0 < gamma <= 90.0:
            raise ValueError(f"port {name!r}: field_of_view must satisfy 0 < field_of_view <= 90 degrees (the "
                             f"half-angle of the detector's cone; 90: the whole hemisphere; got {gamma:g})")
        if port.role != "detector":
            raise ValueError(f"port {name!r}: field_of_view is for a port with role detector (got role {port.role})")
        object.__setattr__(port, "field_of_view", None if gamma == 90.0 else gamma)
    if port.shape == "circle":
        if port.width is not None or port.height is not None:
            raise ValueError(f"port {name!r}: width and height are for shape ellipse or rectangle (a circular port "
                             "has a radius)")
        return
    sizes = []
    for key in ("width", "height"):
        value = getattr(port, key)
        if value is None:
            raise ValueError(f"port {name!r}: shape {port.shape} needs {key} > 0 mm")
        value = _finite(f"port {name!r} {key}", value)
        if not value > 0.0:
            raise ValueError(f"port {name!r}: {key} must be > 0 mm (got {value:g})")
        object.__setattr__(port, key, value)
        sizes.append(value / 2.0)
    if depth > 0.0:
        raise ValueError(f"port {name!r}: depth must be 0 for shape {port.shape} (a port wall is modelled for circular "
                         f"ports only; got depth {depth:g} mm)")
    a, b = sizes
    circumscribed = max(a, b) if port.shape == "ellipse" else math.hypot(a, b)
    if port.radius is not None and not math.isclose(float(port.radius), circumscribed, rel_tol=1e-12):
        raise ValueError(f"port {name!r}: radius is not given for shape {port.shape} (its size is width x height; "
                         f"its circumscribed radius is {circumscribed:g} mm, got radius {port.radius!r})")
    object.__setattr__(port, "radius", circumscribed)


def _check_mask(port: Any) -> None:
    """A holder mask: 0 < aperture < radius (a circular port), 0 <= mask_reflectance <= 1."""

    name = port.name
    if port.aperture is None:
        if port.mask_reflectance is not None:
            raise ValueError(f"port {name!r}: mask_reflectance is for a holder mask: give its aperture too")
        return
    if port.shape != "circle" or port.radius is None:
        raise ValueError(f"port {name!r}: aperture (a holder mask) needs a circular port with a radius")
    aperture = _finite(f"port {name!r} aperture", port.aperture)
    radius = _finite(f"port {name!r} radius", port.radius)
    if not 0.0 < aperture < radius:
        raise ValueError(f"port {name!r}: aperture must satisfy 0 < aperture < radius = {radius:g} mm (the mask's "
                         f"clear opening; omit it for no mask; got {aperture:g})")
    object.__setattr__(port, "aperture", aperture)
    if port.mask_reflectance is not None:
        rho = _finite(f"port {name!r} mask_reflectance", port.mask_reflectance)
        if not 0.0 <= rho <= 1.0:
            raise ValueError(f"port {name!r}: mask_reflectance must satisfy 0 <= mask_reflectance <= 1 (got {rho:g}; "
                             "omit it for the sphere's wall reflectance)")
        object.__setattr__(port, "mask_reflectance", rho)


def _boundary(shape: str, a: float, b: float, phi: float) -> float:
    """Distance from the centre to the shape's edge at azimuth phi (semi-axes or half-widths a, b)."""

    c, s = abs(math.cos(phi)), abs(math.sin(phi))
    if shape == "ellipse":
        return a * b / math.sqrt((b * c) ** 2 + (a * s) ** 2)
    return min(a / c if c > 0 else math.inf, b / s if s > 0 else math.inf)


def shaped_fraction(port: Any, sphere_radius: float) -> float:
    """
    Exact share of the sphere's surface inside a port of any shape: with ρ(φ) the shape's
    edge at azimuth φ, the area is R ∫ (R − √(R² − ρ(φ)²)) dφ (a cap for a circle:
    2πRh), over 4πR²; the integral by adaptive quadrature (scipy, BSD) to 1e-12.
    """

    from scipy.integrate import quad

    R = float(sphere_radius)
    a, b = port.width / 2.0, port.height / 2.0
    corner = math.atan2(b, a)

    def height(phi: float) -> float:
        rho = _boundary(port.shape, a, b, phi)
        return rho * rho / (R + math.sqrt(max(0.0, R * R - rho * rho)))  # R − √(R² − ρ²), no cancellation

    points = [corner] if port.shape == "rectangle" else None
    quarter, _ = quad(height, 0.0, math.pi / 2.0, points=points, epsabs=0.0, epsrel=1e-12, limit=200)
    return 4.0 * R * quarter / (4.0 * math.pi * R * R)


def shaped_area(port: Any) -> float:
    """The opening's area in its tangent plane, mm² (π a b, or width × height)."""

    if port.shape == "ellipse":
        return math.pi * port.width * port.height / 4.0
    if port.shape == "rectangle":
        return port.width * port.height
    return math.pi * port.radius ** 2


def contains(port: Any, point: Any, sphere_radius: float) -> bool:
    """True when the wall point ``point`` lies in the port's opening (any shape)."""

    point = np.asarray(point, dtype=np.float64)
    c = port.axis
    if port.shape == "circle":
        return bool(point @ c >= sphere_radius * port.cos_half_angle(sphere_radius))
    e1, e2 = port_frame(c)
    x, y = point @ e1, point @ e2
    a, b = port.width / 2.0, port.height / 2.0
    if not point @ c > 0.0:
        return False
    if port.shape == "ellipse":
        return bool((x / a) ** 2 + (y / b) ** 2 <= 1.0)
    return bool(abs(x) <= a and abs(y) <= b)


def extras_text(port: Any) -> str:
    """The non-default extras of a port as ``key=value`` text (empty for a plain knife-edge circle)."""

    out = []
    if port.depth:
        out.append(f"depth={port.depth!r}")
    if port.edge_reflectance is not None:
        out.append(f"edge_reflectance={port.edge_reflectance!r}")
    if port.shape != "circle":
        out.append(f"shape={port.shape} width={port.width!r} height={port.height!r}")
    if port.aperture is not None:
        out.append(f"aperture={port.aperture!r}")
    if port.mask_reflectance is not None:
        out.append(f"mask_reflectance={port.mask_reflectance!r}")
    if port.field_of_view is not None:
        out.append(f"field_of_view={port.field_of_view!r}")
    if port.proud:
        out.append(f"proud={port.proud!r}")
    return (" " + " ".join(out)) if out else ""


def disk_view_factor(gap: float, radius: float, other: float | None = None) -> float:
    """
    View factor from a disk of ``radius`` to a coaxial parallel disk of radius ``other``
    (default the same) at distance ``gap`` (mm): ½[X − √(X² − 4(R₂/R₁)²)],
    R₁ = radius/gap, R₂ = other/gap, X = 1 + (1 + R₂²)/R₁² (Howell's catalogue, C-41);
    1 at ``gap = 0`` when ``other ≥ radius``. For a port cylinder of depth ``gap`` with black
    walls it is the share of Lambertian light, uniform over the rim disk, that reaches the
    outer end.
    """

    other = radius if other is None else other
    if gap == 0.0:
        return min(1.0, (other / radius) ** 2)
    r1, r2 = radius / gap, other / gap
    x = 1.0 + (1.0 + r2 * r2) / (r1 * r1)
    k = (r2 / r1) ** 2
    return 2.0 * k / (x + math.sqrt(x * x - 4.0 * k))  # ½(X − √(X² − 4k)) without cancellation


__all__.append("disk_view_factor")
