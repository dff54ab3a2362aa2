"""
An integrating sphere: wall, ports, baffle (the description, validated)
=======================================================================

:class:`Sphere` describes a physical integrating sphere the way a data sheet does: an
inner diameter, a diffuse wall of reflectance ρw (a constant or a spectrum), circular
ports on the sphere surface each with a role, and optionally a baffle. Everything is
exact geometry; :mod:`virtspec_mi.instruments.sphere.walk` walks rays through it
(:meth:`Sphere.layout` gives it the plain values it walks).

Geometry and conventions
------------------------
- **Sphere coordinates:** millimetres, the centre at the origin, radius R = diameter/2.
  A port's centre is given by its polar angle (from +z) and azimuth (from +x about +z),
  in degrees. The usual 8°/d layout puts the sample port at the bottom (polar 180°).
- **A port** of radius r is the spherical cap of half-angle α, sin α = r/R, about its
  centre direction c: the wall points x with x·c ≥ R cos α. Its exact share of the
  wall is the cap fraction f = h/(2R) = (1 − cos α)/2 (:meth:`Sphere.cap_fraction`);
  iadpython's convention is the projected disk r²/(4R²) (:meth:`Sphere.disk_fraction`),
  smaller by the factor (1 + cos α)/2 (2.9 % smaller for a 20 mm port on a 60 mm sphere).
- **A port plane** is the plane of the cap's rim, x·c = R cos α. A specimen (or a
  reference standard) *sits in its port*: a flat disk in the port plane, centred on
  the port axis, radius ≤ r. A ray crossing the port plane outside that disk leaves
  through the port.
- **Roles** (:data:`ROLES`): ``sample`` (the specimen for reflectance), ``entrance``
  (the beam's way in; the specimen for transmittance), ``reference`` (the reference
  standard in the comparison method; a wall plug in single-beam substitution),
  ``detector`` (a ray reaching its cap is detected), ``specular`` (open to a light trap
  in SCE, closed by a wall plug in SCI), ``open`` (any other hole: lost).
- **The baffle** is a flat disk (centre, unit normal, radius) inside the sphere, coated
  like the wall (reflectance ρw on both faces, Lambertian). It must lie wholly inside
  the sphere and on the sphere's side of the plane of every port that may hold a disk
  (``sample``, ``entrance``, ``reference``): a baffle through the specimen's plane is
  refused.
- **Wall reflectance** ρw: a number in [0, 1] or a spectrum (wavelengths in nm and
  values, linearly interpolated, held constant beyond its ends).

References
----------
Labsphere, *A guide to integrating sphere theory and applications* (port fractions,
sphere multiplier, substitution error). Goebel, D.G. (1967), Generalized integrating-
sphere theory, Applied Optics 6, 125–128.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from virtspec_mi.base.checks import number, value_tokens

__all__ = ["ROLES", "HOLDER_ROLES", "Port", "Baffle", "Sphere", "SPHERE_PARAMETERS", "is_sphere_parameter",
           "sphere_from_parameters", "parse_port", "parse_baffle", "parse_wall_reflectance"]

ROLES: tuple[str, ...] = ("sample", "entrance", "reference", "detector", "specular", "open")
"""The roles a port may have (see the module docstring)."""

HOLDER_ROLES: tuple[str, ...] = ("sample", "entrance", "reference")
"""Roles of ports that may hold a flat specimen or standard in their port plane."""


def _direction(polar: float, azimuth: float) -> np.ndarray:
    theta, phi = math.radians(polar), math.radians(azimuth)
    return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])


def _three(name: str, value: Any) -> tuple:
    """Three values (x, y, z): a sequence of three, or a string ``"x,y,z"``; ``ValueError`` naming ``name`` else."""

    if isinstance(value, str):
        value = tuple(value_tokens(name, value))
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 3:
        raise ValueError(f"{name} must be three numbers x, y, z in mm (got {value!r})")
    return tuple(value)


def _finite(name: str, value: Any) -> float:
    """A finite number (:func:`virtspec_mi.base.checks.number`, which refuses booleans, non-numbers and NaN)."""

    result = number(name, value)
    if not math.isfinite(result):
        raise ValueError(f"{name} must be a finite number (got {value!r})")
    return result


@dataclass(frozen=True)
class Port:
    """
    A circular port on the sphere surface.

    Parameters
    ----------
    name
        Its name (unique in a sphere).
    role
        One of :data:`ROLES`.
    polar, azimuth
        Direction of the port centre from the sphere centre, degrees (polar in [0, 180]).
    radius
        Radius of the opening, mm (> 0, less than the sphere radius); for an ellipse or a
        rectangle it is not given (it becomes the circumscribed radius).
    depth
        Thickness of the port wall, mm (≥ 0, default 0: a knife edge): a cylinder of
        radius r from the rim plane outwards; what sits in the port sits at its outer end
        (:mod:`virtspec_mi.instruments.sphere.ports`).
    edge_reflectance
        Reflectance of that cylinder wall, 0 … 1 (Lambertian; default ``None``: the
        sphere's wall reflectance ρw(λ)).
    shape
        ``"circle"`` (default), ``"ellipse"`` or ``"rectangle"`` (knife edges only).
    width, height
        Full sizes of an elliptical or rectangular opening along the port's in-plane axes
        e₁, e₂ (mm, > 0; :func:`~virtspec_mi.instruments.sphere.ports.port_frame`).
    aperture
        A holder mask (a clip) in front of what the port holds: a flat annulus from this
        radius to the port's, mm (0 < aperture < radius; default ``None``: no mask).
    mask_reflectance
        The mask's Lambertian reflectance towards the sphere, 0 … 1 (default ``None``:
        the sphere's wall reflectance ρw(λ)).
    field_of_view
        A detector's field of view: the half-angle (degrees, 0 < field_of_view <= 90) of
        the cone about the port's axis within which a ray reaching the detector counts;
        one outside it is lost (absorbed by the detector's housing). 90 (or ``None``,
        the default): the whole hemisphere, today's detector.
    proud
        How far what the port holds stands into the sphere, mm (≥ 0, less than R cos α;
        default 0: in the rim plane): the specimen (or standard) on a post of its own
        radius whose side reflects ``edge_reflectance`` (Lambertian).
    """

    name: str
    role: str
    polar: float
    azimuth: float
    radius: float | None = None
    depth: float = 0.0
    edge_reflectance: float | None = None
    shape: str = "circle"
    width: float | None = None
    height: float | None = None
    aperture: float | None = None
    mask_reflectance: float | None = None
    field_of_view: float | None = None
    proud: float = 0.0

    def __post_init__(self) -> None:
        from virtspec_mi.instruments.sphere.ports import check_port_extras

        check_port_extras(self)
        if not isinstance(self.name, str) or not self.name or any(c.isspace() for c in self.name):
            raise ValueError(f"port name must be a non-empty string without spaces (got {self.name!r})")
        if not isinstance(self.role, str) or self.role not in ROLES:
            raise ValueError(f"port {self.name!r}: role must be one of {', '.join(ROLES)} (got {self.role!r})")
        polar = _finite(f"port {self.name!r} polar", self.polar)
        if not 0.0 <= polar <= 180.0:
            raise ValueError(f"port {self.name!r}: polar must satisfy 0 <= polar <= 180 degrees (got {polar:g})")
        object.__setattr__(self, "polar", polar)
        object.__setattr__(self, "azimuth", _finite(f"port {self.name!r} azimuth", self.azimuth))
        if self.radius is None:
            raise ValueError(f"port {self.name!r}: radius (mm, > 0) is required for a circular port")
        radius = _finite(f"port {self.name!r} radius", self.radius)
        if not radius > 0.0:
            raise ValueError(f"port {self.name!r}: radius must be > 0 mm (got {radius:g})")
        object.__setattr__(self, "radius", radius)

    @property
    def axis(self) -> np.ndarray:
        """Unit vector from the sphere centre to the port centre."""

        return _direction(self.polar, self.azimuth)

    def half_angle(self, sphere_radius: float) -> float:
        """Half-angle α of the cap, radians: sin α = r/R."""

        return math.asin(self.radius / sphere_radius)

    def cos_half_angle(self, sphere_radius: float) -> float:
        """cos α = √(1 − r²/R²) (the port plane lies at R cos α from the centre)."""

        return math.sqrt(max(0.0, 1.0 - (self.radius / sphere_radius) ** 2))


@dataclass(frozen=True)
class Baffle:
    """A flat disk inside the sphere (mm, sphere coordinates), coated like the wall."""

    centre: tuple[float, float, float]
    normal: tuple[float, float, float]
    radius: float

    def __post_init__(self) -> None:
        centre = tuple(_finite("baffle centre", c) for c in _three("baffle centre", self.centre))
        normal = np.array([_finite("baffle normal", c) for c in _three("baffle normal", self.normal)])
        length = float(np.linalg.norm(normal))
        if not length > 0.0:
            raise ValueError("baffle normal must be a non-zero vector")
        radius = _finite("baffle radius", self.radius)
        if not radius > 0.0:
            raise ValueError(f"baffle radius must be > 0 mm (got {radius:g})")
        object.__setattr__(self, "centre", centre)
        unit = normal if abs(length - 1.0) < 1e-12 else normal / length  # a unit normal is kept bit for bit
        object.__setattr__(self, "normal", tuple(float(v) for v in unit))
        object.__setattr__(self, "radius", radius)

    def reach(self, axis: Any) -> float:
        """The farthest a point of the disk lies along the unit vector ``axis`` (mm): c·a + r·√(1 − (n·a)²)."""

        c, n, a = np.array(self.centre), np.array(self.normal), np.asarray(axis, dtype=np.float64)
        return float(c @ a + self.radius * math.sqrt(max(0.0, 1.0 - float(n @ a) ** 2)))

    def farthest_rim_distance(self) -> float:
        """Largest distance of a baffle rim point from the sphere centre."""

        c, n = np.array(self.centre), np.array(self.normal)
        tangential = c - (c @ n) * n
        return float(math.sqrt(c @ c + self.radius ** 2 + 2.0 * self.radius * np.linalg.norm(tangential)))


@dataclass(frozen=True, eq=False)
class Sphere:
    """
    An integrating sphere (see the module docstring). Two spheres are equal when they have
    the same diameter, wall, baffle and ports, whatever order the ports are listed in (a
    result file's sorted keys, an XML scene or a dict may list them differently).

    Parameters
    ----------
    diameter
        Inner diameter, mm (> 0).
    wall_reflectance
        ρw: a number in [0, 1], or ``(wavelengths_nm, values)`` with values in [0, 1].
    ports
        The ports (:class:`Port`), names unique, caps not overlapping.
    baffle
        Optional :class:`Baffle` (or its text ``"centre=x,y,z normal=x,y,z radius=r"``),
        wholly inside the sphere and clear of the holder ports' planes (and of the rim plane
        of every port with a wall).
    beam_profile
        Optional :class:`~virtspec_mi.instruments.sphere.beam.BeamProfile` (or its text
        ``"shape=rectangle width=7 height=4 divergence=0.5"``): a traced beam; ``None`` (and
        a point without divergence) is the bench's pencil beam.
    wall_specular
        The mirror share of the wall's and the baffle's reflection, 0 … 1 (default 0:
        Lambertian).
    wall_bsdf
        Optional Mitsuba BSDF plugin dict (or its JSON text) of the wall and the baffle,
        e.g. ``{"type": "roughplastic", "alpha": 0.3, "diffuse_reflectance": 0.97}``:
        sampled at each wall event in place of ρw and the Lambertian (its own spectrum).
    """

    diameter: float
    wall_reflectance: Any = 0.98
    ports: tuple[Port, ...] = ()
    baffle: Baffle | None = None
    name: str = field(default="", compare=False)
    beam_profile: Any = None
    wall_specular: float = 0.0
    wall_bsdf: Any = None

    def _identity(self) -> tuple:
        wall = self.wall_reflectance
        return (self.diameter, wall if isinstance(wall, float) else tuple(map(tuple, wall)), self.baffle,
                tuple(sorted(self.ports, key=lambda port: port.name)), self.beam_profile, self.wall_specular,
                None if self.wall_bsdf is None else json.dumps(self.wall_bsdf, sort_keys=True))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Sphere) and self._identity() == other._identity()

    def __hash__(self) -> int:
        return hash(self._identity())

    def __post_init__(self) -> None:
        diameter = _finite("diameter", self.diameter)
        if not diameter > 0.0:
            raise ValueError(f"diameter must be > 0 mm (got {diameter:g})")
        object.__setattr__(self, "diameter", diameter)
        object.__setattr__(self, "wall_reflectance", parse_wall_reflectance(self.wall_reflectance))
        if isinstance(self.ports, (str, bytes, Port)) or not hasattr(self.ports, "__iter__"):
            raise ValueError(f"ports must be a sequence of virtspec_mi.Port (got {self.ports!r})")
        ports = tuple(self.ports)
        for port in ports:
            if not isinstance(port, Port):
                raise ValueError(f"ports must be virtspec_mi.Port objects (got {type(port).__name__} {port!r})")
        object.__setattr__(self, "ports", ports)
        if isinstance(self.baffle, str):  # as the integrator's XML writes it: "centre=x,y,z normal=x,y,z radius=r"
            object.__setattr__(self, "baffle", parse_baffle(self.baffle))
        elif self.baffle is not None and not isinstance(self.baffle, Baffle):
            raise ValueError("baffle must be a virtspec_mi.Baffle, its text 'centre=x,y,z normal=x,y,z radius=r' "
                             f"(mm) or None (got {type(self.baffle).__name__} {self.baffle!r})")
        from virtspec_mi.instruments.sphere.beam import beam_profile_of

        object.__setattr__(self, "beam_profile", beam_profile_of(self.beam_profile))
        specular = _finite("wall_specular", self.wall_specular)
        if not 0.0 <= specular <= 1.0:
            raise ValueError(f"wall_specular must satisfy 0 <= wall_specular <= 1 (the mirror share of the wall's "
                             f"reflection; 0: Lambertian; got {specular:g})")
        object.__setattr__(self, "wall_specular", specular)
        object.__setattr__(self, "wall_bsdf", _wall_bsdf(self.wall_bsdf, specular))
        radius = diameter / 2.0
        names = [p.name for p in ports]
        if len(set(names)) != len(names):
            raise ValueError(f"ports must have distinct names (got {names})")
        for port in ports:
            if not port.radius < radius:
                raise ValueError(f"port {port.name!r}: radius must be < the sphere radius {radius:g} mm "
                                 f"(got {port.radius:g}): a port larger than the sphere")
        for i, a in enumerate(ports):
            for b in ports[i + 1:]:
                gap = math.acos(float(np.clip(a.axis @ b.axis, -1.0, 1.0)))
                if gap < a.half_angle(radius) + b.half_angle(radius):
                    raise ValueError(f"ports {a.name!r} and {b.name!r} overlap: their centres are "
                                     f"{math.degrees(gap):.3f} deg apart, their caps' half-angles add up to "
                                     f"{math.degrees(a.half_angle(radius) + b.half_angle(radius)):.3f} deg")
        for port in ports:
            if port.proud and not port.proud < radius * port.cos_half_angle(radius):
                raise ValueError(f"port {port.name!r}: proud must satisfy 0 <= proud < "
                                 f"{radius * port.cos_half_angle(radius):g} mm (the rim plane's distance from the "
                                 f"centre; got {port.proud:g})")
            if port.shape != "circle" and port.role in ("sample", "reference"):
                raise ValueError(f"port {port.name!r}: role {port.role} needs shape circle (a specimen or a standard "
                                 f"sits in it; a non-circular rim is not planar), got shape {port.shape}")
        for role in ("sample", "entrance", "reference", "specular"):
            if sum(p.role == role for p in ports) > 1:
                raise ValueError(f"ports: at most one port may have role {role!r}")
        if self.baffle is not None and not self.baffle.farthest_rim_distance() < radius:
            raise ValueError(f"baffle must lie inside the sphere: its rim reaches "
                             f"{self.baffle.farthest_rim_distance():g} mm from the centre (radius {radius:g} mm)")
        for port in ports if self.baffle is not None else ():
            plane = radius * port.cos_half_angle(radius) - port.proud
            reach = self.baffle.reach(port.axis)
            if (port.role in HOLDER_ROLES or port.depth > 0.0) and not reach < plane:
                raise ValueError(f"baffle must not cross the plane of port {port.name!r} (role {port.role}: where the "
                                 f"specimen or a standard sits): its rim reaches {reach:g} mm along the port's axis, "
                                 f"the plane lies at {plane:g} mm from the centre; move or shrink the baffle")

    @property
    def radius(self) -> float:
        """R = diameter/2, mm."""

        return self.diameter / 2.0

    def port(self, role: str) -> Port | None:
        """The port with ``role`` (the first, for ``detector``/``open``), or ``None``."""

        return next((p for p in self.ports if p.role == role), None)

    def cap_fraction(self, port: Port | str) -> float:
        """Exact share of the sphere surface of a port's cap: h/(2R) = (1 − cos α)/2."""

        port = self._named(port)
        if port.shape != "circle":
            from virtspec_mi.instruments.sphere.ports import shaped_fraction

            return shaped_fraction(port, self.radius)
        ratio = port.radius / self.radius
        return ratio * ratio / (2.0 * (1.0 + port.cos_half_angle(self.radius)))  # (1 − cos α)/2, no cancellation

    def disk_fraction(self, port: Port | str) -> float:
        """iadpython's convention: the projected disk, r²/(4R²)."""

        port = self._named(port)
        if port.shape != "circle":
            from virtspec_mi.instruments.sphere.ports import shaped_area

            return shaped_area(port) / (4.0 * math.pi * self.radius ** 2)
        return port.radius ** 2 / (4.0 * self.radius ** 2)

    @property
    def cap_fractions(self) -> dict[str, float]:
        """Every port's exact cap fraction, by name."""

        return {p.name: self.cap_fraction(p) for p in self.ports}

    def _named(self, port: Port | str) -> Port:
        if isinstance(port, Port):
            return port
        for item in self.ports:
            if item.name == port:
                return item
        raise ValueError(f"no port named {port!r} (ports: {[p.name for p in self.ports]})")

    def wall_reflectance_at(self, wavelengths: Sequence[float]) -> np.ndarray:
        """ρw at ``wavelengths`` (nm)."""

        wavelengths = np.asarray(wavelengths, dtype=np.float64)
        value = self.wall_reflectance
        if isinstance(value, float):
            return np.full(wavelengths.shape, value)
        grid, values = value
        return np.interp(wavelengths, grid, values)

    def port_plane_centre(self, port: Port | str) -> np.ndarray:
        """Centre of a port's rim disk (where a specimen in that port sits), mm."""

        port = self._named(port)
        return port.axis * self.radius * port.cos_half_angle(self.radius)

    def wall_point(self, origin: Sequence[float], direction: Sequence[float]) -> np.ndarray:
        """Where the ray ``origin + t·direction`` (origin inside the sphere) meets the wall."""

        o, d = np.asarray(origin, float), np.asarray(direction, float)
        d = d / np.linalg.norm(d)
        b, c = o @ d, o @ o - self.radius ** 2
        return o + (-b + math.sqrt(b * b - c)) * d

    def port_at(self, point: Sequence[float]) -> Port | None:
        """The port whose cap holds the wall point ``point``, or ``None`` (wall)."""

        point = np.asarray(point, float)
        for port in self.ports:
            if port.shape != "circle":
                from virtspec_mi.instruments.sphere.ports import contains

                if contains(port, point, self.radius):
                    return port
            elif point @ port.axis >= self.radius * port.cos_half_angle(self.radius):
                return port
        return None

    def parameters(self) -> dict[str, Any]:
        """
        The flat parameters of the ``integrating_sphere`` integrator that describe this
        sphere (for a scene dict: ``{"type": "integrating_sphere", **sphere.parameters()}``);
        :func:`sphere_from_parameters` reads them back.
        """

        rho = self.wall_reflectance
        out: dict[str, Any] = {
            "diameter": self.diameter,
            "wall_reflectance": rho if isinstance(rho, float) else ", ".join(
                f"{w!r}:{v!r}" for w, v in zip(*rho)),
        }
        from virtspec_mi.instruments.sphere.ports import extras_text

        for port in self.ports:
            out[f"port_{port.name}"] = (f"role={port.role} polar={port.polar!r} azimuth={port.azimuth!r} "
                                        f"radius={port.radius!r}" + extras_text(port))
        if self.baffle is not None:
            b = self.baffle
            out["baffle"] = (f"centre={','.join(repr(v) for v in b.centre)} normal={','.join(repr(v) for v in b.normal)} "
                             f"radius={b.radius!r}")
        if self.beam_profile is not None:
            out["beam_profile"] = self.beam_profile.text()
        if self.wall_specular:
            out["wall_specular"] = self.wall_specular
        if self.wall_bsdf is not None:
            out["wall_bsdf"] = json.dumps(self.wall_bsdf, sort_keys=True)
        return out

    def layout(self, holders: Sequence[Any], caps: Sequence[int | None], max_bounces: int,
               wavelengths: Sequence[float]) -> Any:
        """
        One configuration of this sphere as the kernel walks it
        (:class:`~virtspec_mi.instruments.sphere.walk.SphereLayout`, plain values): the
        ``holders`` (:class:`~virtspec_mi.instruments.sphere.walk.Holder`; holder 0 in the
        beam), each port's cap fate (a :class:`~virtspec_mi.instruments.sphere.walk.SphereFate`
        code, or ``None`` for a plugged port, which is wall), the step cap and ρw at
        ``wavelengths`` (nm).
        """

        from virtspec_mi.instruments.sphere.walk import SphereLayout
        from virtspec_mi.instruments.sphere.real import real_layout

        radius = self.radius
        grid = np.unique(np.asarray(wavelengths, dtype=np.float64))

        def plane(port: Port) -> tuple:
            return (tuple(float(v) for v in port.axis), radius * port.cos_half_angle(radius),
                    tuple(float(v) for v in self.port_plane_centre(port)))

        plain = all(p.depth == 0.0 and p.shape == "circle" and p.aperture is None and p.field_of_view is None
                    and p.proud == 0.0 for p in self.ports) and self.beam_profile is None and self.wall_specular == 0.0 \
            and self.wall_bsdf is None
        if not plain:
            return real_layout(self, holders, caps, max_bounces, grid)
        return SphereLayout(
            radius=radius, ports=len(self.ports),
            caps=tuple((tuple(float(v) for v in p.axis), radius * p.cos_half_angle(radius), int(action))
                       for p, action in zip(self.ports, caps) if action is not None),
            planes=tuple(plane(self.ports[h.port]) for h in holders), holders=tuple(holders),
            baffle=None if self.baffle is None else (self.baffle.centre, self.baffle.normal, self.baffle.radius),
            max_bounces=int(max_bounces),
            wall=(tuple(float(w) for w in grid), tuple(float(r) for r in self.wall_reflectance_at(grid))))

    def describe(self) -> str:
        """A short description: diameter, ρw, ports with their cap fractions, baffle."""

        rho = self.wall_reflectance
        rho_text = f"{rho:g}" if isinstance(rho, float) else f"spectral ({len(rho[0])} values)"
        ports = "; ".join(f"{p.name} ({p.role}, r = {p.radius:g} mm at {p.polar:g}/{p.azimuth:g} deg, "
                          f"f = {self.cap_fraction(p):.5f})" for p in self.ports)
        baffle = "" if self.baffle is None else f"; baffle r = {self.baffle.radius:g} mm"
        from virtspec_mi.instruments.sphere.ports import extras_text

        extras = "".join(f"; port {p.name}:{extras_text(p)}" for p in self.ports if extras_text(p))
        beam = "" if self.beam_profile is None else f"; beam {self.beam_profile.text()}"
        beam += f"; wall specular share {self.wall_specular:g}" if self.wall_specular else ""
        beam += f"; wall BSDF {json.dumps(self.wall_bsdf, sort_keys=True)}" if self.wall_bsdf is not None else ""
        return (f"sphere {self.diameter:g} mm, wall reflectance {rho_text}; ports: {ports or 'none'}{baffle}"
                f"{extras}{beam}")


def _wall_bsdf(value: Any, specular: float) -> dict | None:
    """The wall's BSDF: ``None``, or a Mitsuba plugin dict (or its JSON text) with a ``type``; not with a mirror share."""

    if value is None:
        return None
    if isinstance(value, str):
        try:
            value = json.loads(value)
        except ValueError as error:
            raise ValueError(f"wall_bsdf must be a Mitsuba BSDF plugin dict or its JSON text, e.g. "
                             f"'{{\"type\": \"roughplastic\", \"alpha\": 0.3}}' ({error})") from None
    if not isinstance(value, dict) or not isinstance(value.get("type"), str):
        raise ValueError(f"wall_bsdf must be a Mitsuba BSDF plugin dict with a 'type' (got {value!r})")
    try:
        json.dumps(value)
    except TypeError:
        raise ValueError("wall_bsdf must hold plain values (numbers, text, lists, dicts): it is recorded with the "
                         "reading") from None
    if specular:
        raise ValueError("wall_bsdf replaces the wall's Lambertian + mirror model: give wall_specular = 0 with it")
    return value


def parse_wall_reflectance(value: Any) -> float | tuple[tuple[float, ...], tuple[float, ...]]:
    """
    ρw from a number, a ``(wavelengths, values)`` pair or a string ``"0.98"`` /
    ``"400:0.97, 700:0.99"`` (λ:value pairs); every value in [0, 1].
    """

    if isinstance(value, str):
        text = value.replace(",", " ").split()
        if len(text) == 1 and ":" not in text[0]:
            try:
                value = number("wall_reflectance", text[0])
            except ValueError:
                raise ValueError("wall_reflectance must be a number 0 <= rho_w <= 1 or 'nm:value' pairs such as "
                                 f"'400:0.97, 700:0.99' (got {value!r})") from None
        else:
            try:
                pairs = [tuple(float(v) for v in token.split(":")) for token in text]
            except ValueError:
                raise ValueError(f"wall_reflectance must be a number or 'nm:value' pairs (got {value!r})") from None
            if not pairs or any(len(p) != 2 for p in pairs):
                raise ValueError(f"wall_reflectance must be a number or 'nm:value' pairs (got {value!r})")
            value = ([p[0] for p in pairs], [p[1] for p in pairs])
    if isinstance(value, tuple) and len(value) == 2 and not isinstance(value[0], (int, float)) \
            or isinstance(value, list) and len(value) == 2 and not isinstance(value[0], (int, float)):
        grid = np.asarray(value[0], dtype=np.float64)
        values = np.asarray(value[1], dtype=np.float64)
        if grid.ndim != 1 or grid.shape != values.shape or grid.size == 0:
            raise ValueError("wall_reflectance: wavelengths and values must be two 1-D sequences of one length")
        if not np.all(np.isfinite(grid)) or np.any(np.diff(grid) <= 0):
            raise ValueError("wall_reflectance: wavelengths must be finite and increasing")
        if not np.all((values >= 0.0) & (values <= 1.0)):
            raise ValueError(f"wall_reflectance must satisfy 0 <= rho_w <= 1 (got values from "
                             f"{values.min():g} to {values.max():g})")
        return tuple(float(v) for v in grid), tuple(float(v) for v in values)
    rho = _finite("wall_reflectance", value)
    if not 0.0 <= rho <= 1.0:
        raise ValueError(f"wall_reflectance must satisfy 0 <= rho_w <= 1 (got {rho:g})")
    return rho


def _fields(text: str, name: str, allowed: tuple[str, ...]) -> dict[str, str]:
    out: dict[str, str] = {}
    for token in text.replace(";", " ").split():
        key, sep, value = token.partition("=")
        if not sep or key not in allowed:
            raise ValueError(f"{name}: expected 'key=value' items with keys {', '.join(allowed)} (got {token!r})")
        out[key] = value
    return out


def parse_port(name: str, text: str) -> Port:
    """A port from its XML string, e.g. ``"role=detector polar=90 azimuth=90 radius=6.35"``."""

    from virtspec_mi.instruments.sphere.ports import EXTRA_KEYS

    items = _fields(text, f"port {name!r}", ("role", "polar", "azimuth", "radius", *EXTRA_KEYS))
    shaped = items.get("shape", "circle") != "circle"
    missing = [k for k in ("role", "polar", *(() if shaped else ("radius",))) if k not in items]
    if missing:
        raise ValueError(f"port {name!r}: missing {', '.join(missing)} (e.g. 'role=detector polar=90 radius=6.35')")
    try:
        extras: dict[str, Any] = {k: float(items[k]) for k in ("depth", "edge_reflectance", "width", "height",
                                                               "aperture", "mask_reflectance", "field_of_view",
                                                               "proud")
                                  if k in items}
        if "shape" in items:
            extras["shape"] = items["shape"]
        return Port(name, items["role"], float(items["polar"]), float(items.get("azimuth", 0.0)),
                    float(items["radius"]) if "radius" in items else None, **extras)
    except ValueError as error:
        if str(error).startswith("port"):
            raise
        raise ValueError(f"port {name!r}: polar, azimuth and radius must be numbers ({error})") from None


def parse_baffle(text: str) -> Baffle:
    """A baffle from its XML string, e.g. ``"centre=0,40,-40 normal=0,-1,1 radius=12"``."""

    items = _fields(text, "baffle", ("centre", "normal", "radius"))
    if set(items) != {"centre", "normal", "radius"}:
        raise ValueError("baffle: give centre=x,y,z normal=x,y,z radius=r (mm)")
    try:
        centre = tuple(float(v) for v in items["centre"].split(","))
        normal = tuple(float(v) for v in items["normal"].split(","))
        return Baffle(centre, normal, float(items["radius"]))  # type: ignore[arg-type]
    except ValueError as error:
        raise ValueError(f"baffle: {error}") from None


SPHERE_PARAMETERS: tuple[str, ...] = ("diameter", "wall_reflectance", "baffle", "beam_profile", "wall_specular",
                                      "wall_bsdf")
"""Parameters of a sphere description besides its ``port_<name>`` entries."""


def is_sphere_parameter(name: str) -> bool:
    """True for a flat parameter of a sphere description: :data:`SPHERE_PARAMETERS` or ``port_<name>``."""

    return name in SPHERE_PARAMETERS or name.startswith("port_")


def sphere_from_parameters(values: Any) -> Sphere:
    """
    A :class:`Sphere` from flat parameters (a dict or ``mi.Properties``: the
    ``integrating_sphere`` integrator's XML or dict): ``diameter`` (mm),
    ``wall_reflectance`` (number or ``"nm:value, …"``), one ``port_<name>`` string per port
    (``"role=… polar=… azimuth=… radius=…"``) and an
    optional ``baffle`` string (``"centre=x,y,z normal=x,y,z radius=r"``).
    """

    if "diameter" not in values:
        raise ValueError("sphere: diameter (mm) is required")
    ports = tuple(parse_port(key[len("port_"):], str(values.get(key))) for key in values.keys()
                  if key.startswith("port_"))
    baffle = parse_baffle(str(values.get("baffle"))) if "baffle" in values and values.get("baffle") else None
    wall = {"wall_reflectance": values.get("wall_reflectance")} if "wall_reflectance" in values else {}
    if "beam_profile" in values and values.get("beam_profile"):
        wall["beam_profile"] = str(values.get("beam_profile"))
    if "wall_specular" in values:
        wall["wall_specular"] = values.get("wall_specular")
    if "wall_bsdf" in values and values.get("wall_bsdf"):
        wall["wall_bsdf"] = str(values.get("wall_bsdf"))
    return Sphere(values.get("diameter"), ports=ports, baffle=baffle, **wall)
