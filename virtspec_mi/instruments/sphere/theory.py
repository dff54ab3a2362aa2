"""
Integrating-sphere theory: port fractions, sphere gain, readouts and their correction
=====================================================================================

The analytic side of the integrating sphere: closed forms for what a real instrument
reads (a detector signal ratioed against a reference standard) and their inverse, the
correction that recovers the hemispherical reflectance (transmittance) from a reading.
Pure NumPy on plain floats or arrays (broadcasting: a spectral wall reflectance is an
array); nothing here touches Mitsuba, so it is an independent reference for the
Monte-Carlo sphere walk.

The sphere property
-------------------
For two elements ``dA₁``, ``dA₂`` of the inner surface of a sphere of radius R the
chord between them makes the same angle with both normals, ``cos θ₁ = cos θ₂ = d/2R``,
so the diffuse view factor ``cos θ₁ cos θ₂ dA₂ / (π d²) = dA₂ / 4πR²`` does not depend
on where the two elements are. Lambertian light leaving any point *of the sphere's
surface* therefore lands uniformly over the sphere's area: it reaches a region with
probability equal to the region's share of the area, its **fraction** a (Goebel 1967,
eq. 2; Jacquez & Kuppenheim 1955). A circular port of radius r is a spherical cap of
height ``h = R − √(R² − r²)``, fraction :func:`cap_fraction` ``= h / 2R`` exactly;
:func:`projected_fraction` ``= r² / 4R²`` (the disk's area over the sphere's) is the
small-port approximation of Prahl's IAD program. The two obey
``projected = cap · (1 − cap)`` exactly, so they differ by ``cap/projected − 1 =
2 / (1 + √(1 − r²/R²)) − 1``: 2.944 % for a 20 mm port on a 60 mm sphere
(:func:`port_fractions`).

Flat specimens in ports (the simulation's exact geometry)
---------------------------------------------------------
A specimen (or standard, or detector) sits in its port as a *flat disk* in the port's
plane, not on the cap. Two exact facts follow:

1. Light from the wall aimed at the cap crosses the disk first, so the disk receives
   exactly the cap fraction ``a`` of every wall emission.
2. By reciprocity (``A_disk F_disk→dA = dA F_dA→disk = dA · a``), Lambertian light
   leaving the disk *uniformly over its area* lands uniformly over the rest of the
   sphere, never on itself: a region X receives ``a_X / (1 − a)``. (Check:
   ``A_cap / πr² = 1/(1 − a)`` by the identity above.)

So in the **flat** model a wall emission lands on X with probability ``a_X``, a port
disk's emission on ``X ≠`` itself with ``a_X / (1 − a)``; in the **cap** model (Goebel,
the Labsphere guide, iadpython's ``Sphere.multiplier``) every emission lands on X with
``a_X``. Every function takes ``port_surface="flat"`` (default, the simulation) or
``"cap"``. Where the simulation may still differ: light leaving one *spot* of the disk
(a narrow beam) does not land uniformly; :func:`spot_landing_density` gives the exact
density for the disk's centre (zero at the port's rim, +2.7 % at 90° and +2.9 %
opposite for a 20 mm port in a 60 mm sphere). Only the *first* landing is affected
(every later emission leaves the wall), i.e. the share ``1/G`` of the signal that
reaches the detector before any wall bounce; a baffle removes even that. Light that
comes back to the disk from the wall lights it uniformly as far as the wall is
uniformly bright, which the dark ports spoil only to second order (a NumPy walk of the
whole exact sphere in ``tests/instruments/sphere/test_theory.py`` agrees with the flat forms
within its noise, where the cap forms are 7σ off).

Throughput (geometric series of wall bounces)
---------------------------------------------
Write ``L(u) = 1 − a_s (1 − u)`` for a specimen of fraction ``a_s`` returning diffuse
light with reflectance ``u``. A wall emission reaches the detector directly (``a_d``)
or via one specimen bounce (``a_s u · a_d/(1 − a_s)``): ``a_d k`` with
``k = L(u)/(1 − a_s)``; it reaches the wall again with ``a_w k``. Summing the bounces,

    T_wall   = a_d k Σ (ρw a_w k)ⁿ = a_d L / ((1 − a_s) − ρw a_w L)          (flat)
    T_sample = [a_d + ρw a_w T_wall] / (1 − a_s) = a_d / ((1 − a_s) − ρw a_w L)
    T        = a_d / (1 − ρw a_w − a_s u)                                  (cap, any start)

(probabilities that one unit of Lambertian light leaving the wall / the specimen is
eventually detected; the detector counts every arrival). The cap form is Goebel's
``a_d M / ρ`` with the sphere multiplier ``M = ρ / (1 − ρ̄)``, ``ρ̄ = Σ a_X ρ_X``.
Two reflecting disks A, B (specimen and comparison standard, or a transmittance
specimen at the entrance and the standard opposite) solve in closed form too
(:func:`detected_fraction`): with ``L_X = 1 − a_X(1 − u_X)`` and
``det = (1 − a_A)(1 − a_B) − u_A u_B a_A a_B``,
``T_A = c L_B / det``, ``T_B = c L_A / det``, ``T_wall = c L_A L_B / det``,
``c = a_d / (1 − ρw a_w L_A L_B / det)``.

Readouts
--------
A specimen with diffuse (Lambertian) reflectance x and specular reflectance r
(hemispherical ``ρ = x + r``, returning diffuse light with ``u = x + r``) under an
8° beam: the diffuse part leaves the specimen, the specular beam hits the specular
port — plugged with wall material in SCI (it then leaves the wall: ``r ρw T_wall``),
open to a light trap in SCE (lost) (CIE 15:2004, geometries di:8° and de:8°).

- **Substitution** (single beam; the standard of reflectance ρ_std replaces the
  specimen; a reference port, if any, is plugged with wall material):
  ``M = ρ_std P(specimen) / P(standard)``; the sphere's throughput changes with what
  sits in the port, so for a Lambertian specimen (cap model)
  ``M = ρ (1 − ρw a_w − a_s ρ_std) / (1 − ρw a_w − a_s ρ)``, i.e. the relative
  *substitution error* is ``M/ρ − 1 = −G(ρ) a_s (ρ_std − ρ)``: negative for specimens
  darker than the standard, larger on whiter walls (Jacquez & Kuppenheim 1955;
  Goebel 1967; Prahl's IAD manual, the ``M_R`` formula).
- **Comparison** (specimen and standard in two ports at once; the beam goes to one,
  then the other): the sphere is the same in both readings, the throughput cancels,
  and the cap model reads ``M = x + r ρw`` (SCI), ``x`` (SCE), i.e. exactly ρ for a
  Lambertian specimen (Kessel 1986: no correction with a two-port comparative sphere).
  With flat disks the first
  landing differs (the specimen cannot see itself but sees the standard) and
  ``M = (1 − a_r(1 − ρ_std)) [x / L(u) + r ρw]``: a residual of order
  ``a (ρ_std − ρ)`` instead of ``G a (ρ_std − ρ)``.

Every reading is a linear-fractional function of x, ``M = Q (n₁ x + n₀)/(d₀ − d₁ x)``,
increasing on ``0 ≤ x ≤ 1 − r``, so :func:`correct_reading` inverts it exactly:
``x = (M d₀ − Q n₀) / (Q n₁ + M d₁)`` and returns ``x + r``. Transmittance (specimen
at the entrance port, the 100 % line taken with the port open and the beam on the
standard in the opposite port) is linear in the diffusely transmitted part
(:func:`transmittance_reading`, :func:`correct_transmittance`).

References
----------
- D.G. Goebel (1967), *Generalized integrating-sphere theory*, Appl. Opt. 6(1),
  125–128 (eqs. 2–9: the sphere property, the multiplier, port losses).
- J.A. Jacquez, H.F. Kuppenheim (1955), *Theory of the integrating sphere*, J. Opt.
  Soc. Am. 45(6), 460–470 (the substitution error).
- S.A. Prahl, *Inverse Adding-Doubling* manual and iadpython ``sphere.py``: gain
  ``G = 1/(1 − a_w r_w − a_d r_d − a_s r_s)`` (no baffle) and
  ``1/(1 − r_w (a_w + (1 − a_e)(a_d r_d + a_s r_s)))`` (baffle); ``Sphere.multiplier``.
- J. Kessel (1986), *Transmittance measurements in the integrating sphere*, Appl.
  Opt. 25(16), 2752–2756 (the substitution correction of a one-port sphere; none
  needed with a two-port comparative sphere).
- L. Vidovič, B. Majaron (2013), *Elimination of single-beam substitution error in
  diffuse reflectance measurements using an integrating sphere*, Proc. SPIE 8565,
  85650I (another route: the throughput change measured through an extra reference
  port; not modelled here).
- CIE 15:2004 *Colorimetry*, the illuminating and viewing geometries di:8° and de:8°
  (specular component included or excluded).
- Labsphere, *A guide to integrating sphere theory and applications* (eq. 14).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from virtspec_mi.base.checks import shown_value

__all__ = [
    "PORT_SURFACES",
    "METHODS",
    "MODES",
    "cap_fraction",
    "projected_fraction",
    "port_fractions",
    "cap_fraction_for_projected",
    "port_radius_for_fraction",
    "wall_fraction",
    "spot_landing_density",
    "sphere_gain",
    "detected_fraction",
    "fresnel_reflectance",
    "substitution_reading",
    "comparison_reading",
    "instrument_reading",
    "sci_sce_readings",
    "correct_reading",
    "transmittance_reading",
    "correct_transmittance",
]

PORT_SURFACES: tuple[str, ...] = ("flat", "cap")
"""Where light leaving a port's occupant starts: a flat disk in the port plane (exact
geometry of the simulation) or the spherical cap (Goebel, iadpython)."""

METHODS: tuple[str, ...] = ("substitution", "comparison")
"""Single-beam substitution, or the comparison method (specimen and standard in the sphere)."""

MODES: tuple[str, ...] = ("SCI", "SCE")
"""Specular component included (port plugged with wall material) or excluded (light trap)."""

_READING_SLACK = 1e-12  # relative slack on the invertible range (rounding of the forward model)


# ----------------------------------------------------------------------------- checks
def _array(name: str, value: Any) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number or an array of numbers (got {value!r})") from None
    if np.isnan(array).any():
        raise ValueError(f"{name} must be a number (got NaN)")
    return array


def _shown(array: np.ndarray, bad: np.ndarray) -> str:
    value = array[bad].flat[0] if array.ndim else array
    return shown_value(float(value))


def _within(name: str, value: Any, low: float, high: float, *, low_open: bool = False,
            high_open: bool = False) -> np.ndarray:
    """``value`` as a float array with every element in the interval; else ValueError naming ``name``."""

    array = _array(name, value)
    bad = (array <= low if low_open else array < low) | (array >= high if high_open else array > high)
    if np.any(bad):
        rule = f"{low:g} {'<' if low_open else '<='} {name} {'<' if high_open else '<='} {high:g}"
        raise ValueError(f"{name} must satisfy {rule} (got {_shown(array, bad)})")
    return array


def _choice(name: str, value: Any, allowed: tuple[str, ...]) -> str:
    if value not in allowed:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, allowed))} (got {value!r})")
    return value


def _out(value: np.ndarray) -> Any:
    value = np.asarray(value, dtype=float)
    return float(value) if value.ndim == 0 else value


# ----------------------------------------------------------------------- port fractions
def cap_fraction(port_radius: Any, sphere_radius: Any) -> Any:
    """
    Exact share of the sphere's area taken by a circular port: the cap fraction ``h/2R``.

    Parameters
    ----------
    port_radius
        r, radius of the port's rim circle (any length unit), ``0 <= r <= R``.
    sphere_radius
        R, inner radius of the sphere (same unit), ``R > 0``.

    Returns
    -------
    float or ndarray
        ``h / 2R`` with ``h = R − √(R² − r²)``, written ``(r/R)² / (2 (1 + √(1 − r²/R²)))``
        so small ports lose no digits; 0 for no port, 1/2 for a hemisphere.

    References
    ----------
    Goebel (1967), eq. 2; iadpython ``Sphere.relative_cap_area``.
    """

    ratio = _port_ratio(port_radius, sphere_radius)
    return _out(ratio**2 / (2.0 * (1.0 + np.sqrt(1.0 - ratio**2))))


def projected_fraction(port_radius: Any, sphere_radius: Any) -> Any:
    """
    The projected-disk convention ``r² / 4R²`` (IAD, iadpython ``approx_relative_cap_area``).

    Parameters are those of :func:`cap_fraction`. Equals ``cap · (1 − cap)`` exactly.
    """

    ratio = _port_ratio(port_radius, sphere_radius)
    return _out(ratio**2 / 4.0)


def port_fractions(port_radius: Any, sphere_radius: Any) -> tuple[Any, Any, Any]:
    """
    Both conventions and how far apart they are.

    Parameters are those of :func:`cap_fraction`.

    Returns
    -------
    tuple
        ``(cap, projected, relative_difference)`` with ``relative_difference =
        cap / projected − 1 = 2 / (1 + √(1 − r²/R²)) − 1`` (0 for a vanishing port; 1 for
        a hemisphere). For r = 10 mm, R = 30 mm: ``(0.028595, 0.027778, 0.029437)``.
    """

    ratio = _port_ratio(port_radius, sphere_radius)
    root = np.sqrt(1.0 - ratio**2)
    cap = ratio**2 / (2.0 * (1.0 + root))
    return _out(cap), _out(ratio**2 / 4.0), _out((1.0 - root) / (1.0 + root))


def cap_fraction_for_projected(projected: Any) -> Any:
    """
    The cap fraction of the port whose projected fraction is ``projected`` (``0 <= p <= 1/4``):
    the smaller root of ``cap (1 − cap) = p``, ``2p / (1 + √(1 − 4p))``.
    """

    projected = _within("projected", projected, 0.0, 0.25)
    return _out(2.0 * projected / (1.0 + np.sqrt(1.0 - 4.0 * projected)))


def port_radius_for_fraction(fraction: Any, sphere_radius: Any) -> Any:
    """
    Radius of the port whose cap fraction is ``fraction`` (``0 <= a <= 1/2``):
    ``r = 2R √(a (1 − a))``.
    """

    fraction = _within("fraction", fraction, 0.0, 0.5)
    radius = _within("sphere_radius", sphere_radius, 0.0, math.inf, low_open=True, high_open=True)
    return _out(2.0 * radius * np.sqrt(fraction * (1.0 - fraction)))


def _port_ratio(port_radius: Any, sphere_radius: Any) -> np.ndarray:
    radius = _within("sphere_radius", sphere_radius, 0.0, math.inf, low_open=True, high_open=True)
    port = _within("port_radius", port_radius, 0.0, math.inf, high_open=True)
    port, radius = np.broadcast_arrays(port, radius)
    if np.any(port > radius):
        raise ValueError(f"port_radius must satisfy 0 <= port_radius <= sphere_radius "
                         f"(got port_radius {_shown(port, port > radius)} with sphere_radius "
                         f"{_shown(radius, port > radius)})")
    return port / radius


def wall_fraction(*fractions: Any) -> Any:
    """
    What is left of the sphere for the wall: ``1 − Σ fractions``.

    Parameters
    ----------
    fractions
        Port fractions (each ``0 <= a <= 1``); their sum must not exceed 1.
    """

    total = np.zeros(())
    for index, fraction in enumerate(fractions):
        total = total + _within(f"port fraction #{index + 1}", fraction, 0.0, 1.0)
    if np.any(total > 1.0):
        raise ValueError(f"port fractions must sum to at most 1 (got {_shown(total, total > 1.0)})")
    return _out(1.0 - total)


def spot_landing_density(angle_from_port: Any, port_radius: Any, sphere_radius: Any) -> Any:
    """
    Landing density of Lambertian light leaving the *centre* of a flat disk in a port,
    relative to the uniform density it would have if it left the whole disk.

    The centre sits at ``c = √(R² − r²)`` from the sphere's centre; a wall point at
    angle ψ (at the sphere's centre) from the port's centre has ``cos α = −cos ψ`` and
    receives ``(R cos α + c)(R + c cos α) / (π |d|⁴)`` per unit area,
    ``|d|² = R² + c² + 2Rc cos α``; the uniform density over the rest of the sphere is
    ``1 / (4πR² (1 − a))``. The ratio integrates to 1 over the wall, is 1 everywhere
    for r → 0 and 0 at the port's rim.

    Parameters
    ----------
    angle_from_port
        ψ in degrees, ``ψ₀ <= ψ <= 180`` where ψ₀ = asin(r/R) is the port's rim
        (180: the point opposite the port).
    port_radius, sphere_radius
        As in :func:`cap_fraction`.
    """

    ratio = _port_ratio(port_radius, sphere_radius)
    psi = _within("angle_from_port", angle_from_port, 0.0, 180.0)
    rim = np.degrees(np.arcsin(ratio))
    psi, rim = np.broadcast_arrays(psi, rim)
    if np.any(psi < rim - 1e-9):
        bad = psi < rim - 1e-9
        raise ValueError(f"angle_from_port must satisfy asin(port_radius/sphere_radius) <= angle_from_port "
                         f"<= 180 degrees, i.e. {_shown(rim, bad)} <= angle_from_port here (got {_shown(psi, bad)})")
    c = np.sqrt(1.0 - ratio**2)  # in units of R
    cos_alpha = -np.cos(np.radians(psi))
    d2 = 1.0 + c**2 + 2.0 * c * cos_alpha
    fraction = ratio**2 / (2.0 * (1.0 + c))
    density = np.maximum(cos_alpha + c, 0.0) * (1.0 + c * cos_alpha) / d2**2
    return _out(4.0 * (1.0 - fraction) * density)


# ------------------------------------------------------------------------------- gain
def sphere_gain(wall_reflectance: Any, sample_reflectance: Any = 0.0, *, sample_fraction: Any,
                detector_fraction: Any, open_fraction: Any = 0.0, detector_reflectance: Any = 0.0,
                baffle: bool = False) -> Any:
    """
    The sphere gain G of the cap model: detector irradiance relative to a black sphere.

    Parameters
    ----------
    wall_reflectance
        ρw, diffuse reflectance of the wall, ``0 <= ρw <= 1`` (array: per wavelength).
    sample_reflectance
        ρs (iadpython's ``URU``), the sample's reflectance for diffuse light, ``[0, 1]``.
    sample_fraction, detector_fraction, open_fraction
        a_s, a_d, a_e: port fractions (:func:`cap_fraction` or :func:`projected_fraction`,
        the choice is the convention); ``open_fraction`` is every open port (entrance,
        light trap). The wall is ``a_w = 1 − a_s − a_d − a_e``.
    detector_reflectance
        r_d, reflectance of the detector, ``[0, 1]``.
    baffle
        False: ``G = 1 / (1 − a_w ρw − a_s ρs − a_d r_d)`` (Goebel; the denominator of
        iadpython's ``Sphere.multiplier``). True: the baffled form of Prahl's IAD,
        ``1 / (1 − ρw (a_w + (1 − a_e)(a_d r_d + a_s ρs)))`` (iadpython's
        ``Sphere.gain`` returns its reciprocal), light from the sample and detector
        reaching the wall before anything else.

    Returns
    -------
    float or ndarray
        G >= 1 (inf for a closed white sphere).
    """

    rho_w = _within("wall_reflectance", wall_reflectance, 0.0, 1.0)
    rho_s = _within("sample_reflectance", sample_reflectance, 0.0, 1.0)
    r_d = _within("detector_reflectance", detector_reflectance, 0.0, 1.0)
    a_s, a_d, a_e = (_within(n, v, 0.0, 1.0) for n, v in (("sample_fraction", sample_fraction),
                                                           ("detector_fraction", detector_fraction),
                                                           ("open_fraction", open_fraction)))
    a_w = 1.0 - a_s - a_d - a_e
    if np.any(a_w < 0.0):
        raise ValueError(f"port fractions must satisfy sample_fraction + detector_fraction + open_fraction <= 1 "
                         f"(got {_shown(1.0 - a_w, a_w < 0.0)})")
    if baffle:
        denominator = 1.0 - rho_w * (a_w + (1.0 - a_e) * (a_d * r_d + a_s * rho_s))
    else:
        denominator = 1.0 - a_w * rho_w - a_s * rho_s - a_d * r_d
    with np.errstate(divide="ignore"):
        return _out(np.where(denominator > 0.0, 1.0 / np.where(denominator > 0.0, denominator, 1.0), np.inf))


# ------------------------------------------------------------------------ throughputs
def _throughputs(rho_w, a_w, a_d, a_a, u_a, a_b, u_b, surface):
    """(T_A, T_B, T_wall): detection probabilities of unit Lambertian light leaving disk A, disk B, the wall."""

    if surface == "cap":
        t = a_d / (1.0 - rho_w * a_w - u_a * a_a - u_b * a_b)
        return t, t, t
    l_a = 1.0 - a_a * (1.0 - u_a)
    l_b = 1.0 - a_b * (1.0 - u_b)
    det = (1.0 - a_a) * (1.0 - a_b) - u_a * u_b * a_a * a_b
    c = a_d * det / (det - rho_w * a_w * l_a * l_b)
    return c * l_b / det, c * l_a / det, c * l_a * l_b / det


def _fractions(**named: Any) -> dict[str, np.ndarray]:
    values = {name: _within(name, value, 0.0, 1.0) for name, value in named.items()}
    if "detector_fraction" in values and np.any(values["detector_fraction"] <= 0.0):
        raise ValueError(f"detector_fraction must satisfy 0 < detector_fraction <= 1 "
                         f"(got {_shown(values['detector_fraction'], values['detector_fraction'] <= 0.0)})")
    total = sum(values.values())
    if np.any(total >= 1.0):
        names = " + ".join(values)
        raise ValueError(f"port fractions must leave some wall: {names} < 1 (got {_shown(total, total >= 1.0)})")
    return values


def detected_fraction(wall_reflectance: Any, sample_reflectance: Any = 0.0, *, sample_fraction: Any,
                      detector_fraction: Any, open_fraction: Any = 0.0, start: str = "sample",
                      port_surface: str = "flat", second_fraction: Any = 0.0,
                      second_reflectance: Any = 0.0) -> Any:
    """
    Probability that one unit of Lambertian light leaving the sample (or the wall) is
    eventually detected: the geometric series of wall bounces summed.

    Parameters
    ----------
    wall_reflectance
        ρw in [0, 1] (array: per wavelength).
    sample_reflectance
        u in [0, 1], what the sample returns of diffuse light that reaches it again.
    sample_fraction, detector_fraction, open_fraction
        a_s, a_d (> 0), a_o: exact cap fractions (or projected, as a convention); the
        detector counts every arrival, open ports lose it; the wall is the rest.
    start
        ``"sample"``: the light leaves the sample Lambertian-uniformly over its disk
        (flat) or cap; ``"wall"``: it leaves a point of the wall (e.g. the SCI plug hit
        by the specular beam); ``"second"``: it leaves the second disk.
    port_surface
        ``"flat"`` (exact: occupants are flat disks in their port planes) or ``"cap"``
        (Goebel / iadpython: they lie on the sphere).
    second_fraction, second_reflectance
        An optional second reflecting disk (a comparison standard), fraction a_r and
        reflectance ρ_r.

    Returns
    -------
    float or ndarray
        Flat, one disk: ``a_d / ((1 − a_s) − ρw a_w L)`` from the sample,
        ``a_d L / ((1 − a_s) − ρw a_w L)`` from the wall, ``L = 1 − a_s (1 − u)``; cap:
        ``a_d / (1 − ρw a_w − a_s u − a_r ρ_r)`` from anywhere. ``a_d · ρs ·`` this is
        iadpython's ``a_d · Sphere.multiplier(ρs, ρs)`` in the cap model.
    """

    _choice("start", start, ("sample", "wall", "second"))
    surface = _choice("port_surface", port_surface, PORT_SURFACES)
    rho_w = _within("wall_reflectance", wall_reflectance, 0.0, 1.0)
    u = _within("sample_reflectance", sample_reflectance, 0.0, 1.0)
    u_r = _within("second_reflectance", second_reflectance, 0.0, 1.0)
    f = _fractions(sample_fraction=sample_fraction, detector_fraction=detector_fraction,
                   open_fraction=open_fraction, second_fraction=second_fraction)
    a_w = 1.0 - sum(f.values())
    t_a, t_b, t_w = _throughputs(rho_w, a_w, f["detector_fraction"], f["sample_fraction"], u,
                                 f["second_fraction"], u_r, surface)
    return _out({"sample": t_a, "second": t_b, "wall": t_w}[start])


# ---------------------------------------------------------------------------- Fresnel
def fresnel_reflectance(theta_i: Any, refractive_index: Any) -> Any:
    """
    Unpolarised Fresnel reflectance of a smooth interface from air (n = 1).

    Parameters
    ----------
    theta_i
        Incidence angle in degrees, ``0 <= θ <= 90``.
    refractive_index
        n > 0 of the medium below (n < 1: total internal reflection past the critical angle).

    Returns
    -------
    float or ndarray
        ``(R_s + R_p)/2`` with ``R_s = ((cos θ − n cos θt)/(cos θ + n cos θt))²``,
        ``R_p = ((n cos θ − cos θt)/(n cos θ + cos θt))²``; 0.040 at 8° for n = 1.5.
    """

    theta = np.radians(_within("theta_i", theta_i, 0.0, 90.0))
    n = _within("refractive_index", refractive_index, 0.0, math.inf, low_open=True, high_open=True)
    cos_i = np.cos(theta)
    sin_t2 = np.sin(theta) ** 2 / n**2
    cos_t = np.sqrt(np.maximum(1.0 - sin_t2, 0.0))
    r_s = ((cos_i - n * cos_t) / (cos_i + n * cos_t)) ** 2
    r_p = ((n * cos_i - cos_t) / (n * cos_i + cos_t)) ** 2
    return _out(np.where(sin_t2 >= 1.0, 1.0, 0.5 * (r_s + r_p)))


# --------------------------------------------------------------------------- readouts
def _wall(method, mode, a_s, a_d, a_o, a_t, a_r):
    """The wall's fraction: the specular port is wall in SCI, the reference port is wall in substitution."""

    return 1.0 - a_s - a_d - a_o - (a_r if method == "comparison" else 0.0) - (a_t if mode == "SCE" else 0.0)


def _coefficients(method, mode, surface, rho_w, a_s, a_d, a_o, a_t, a_r, rho_std, r):
    """
    ``(Q, n1, n0, d0, d1)`` of the reading ``M(x) = Q (n1 x + n0) / (d0 − d1 x)`` as a
    function of the specimen's diffuse reflectance x (specular r, re-hit ``u = x + r``).
    """

    sci = 1.0 if mode == "SCI" else 0.0
    a_w = _wall(method, mode, a_s, a_d, a_o, a_t, a_r)
    if surface == "cap":
        if method == "comparison":
            one = np.ones_like(a_w)
            return one, one, sci * r * rho_w, one, 0.0 * one
        d0 = 1.0 - rho_w * a_w - a_s * r
        return 1.0 - rho_w * a_w - a_s * rho_std, np.ones_like(d0), sci * r * rho_w, d0, a_s * np.ones_like(d0)
    l0 = 1.0 - a_s * (1.0 - r)  # L(u) = l0 + a_s x
    n1 = 1.0 + sci * r * rho_w * a_s
    n0 = sci * r * rho_w * l0
    if method == "comparison":
        return 1.0 - a_r * (1.0 - rho_std), n1, n0, l0, -a_s
    return (1.0 - a_s) - rho_w * a_w * (1.0 - a_s * (1.0 - rho_std)), n1, n0, \
        (1.0 - a_s) - rho_w * a_w * l0, rho_w * a_w * a_s


def _sphere(method, mode, port_surface, wall_reflectance, sample_fraction, detector_fraction,
            open_fraction, trap_fraction, reference_fraction, standard_reflectance, specular_reflectance):
    method = _choice("method", method, METHODS)
    mode = _choice("mode", mode, MODES)
    surface = _choice("port_surface", port_surface, PORT_SURFACES)
    rho_w = _within("wall_reflectance", wall_reflectance, 0.0, 1.0)
    rho_std = _within("standard_reflectance", standard_reflectance, 0.0, 1.0, low_open=True)
    r = _within("specular_reflectance", specular_reflectance, 0.0, 1.0)
    f = _fractions(sample_fraction=sample_fraction, detector_fraction=detector_fraction,
                   open_fraction=open_fraction, trap_fraction=trap_fraction,
                   reference_fraction=reference_fraction)
    if method == "comparison" and np.any(f["reference_fraction"] <= 0.0):
        raise ValueError("reference_fraction must satisfy 0 < reference_fraction < 1 for the comparison method "
                         "(the standard sits in the reference port)")
    return (method, mode, surface, rho_w, f["sample_fraction"], f["detector_fraction"], f["open_fraction"],
            f["trap_fraction"], f["reference_fraction"], rho_std, r)


def instrument_reading(diffuse_reflectance: Any, *, wall_reflectance: Any, sample_fraction: Any,
                       detector_fraction: Any, open_fraction: Any = 0.0, trap_fraction: Any = 0.0,
                       reference_fraction: Any = 0.0, standard_reflectance: Any = 0.99,
                       specular_reflectance: Any = 0.0, method: str = "substitution", mode: str = "SCI",
                       port_surface: str = "flat") -> Any:
    """
    The reflectance factor an 8°/d sphere instrument reads for a specimen.

    Computed from the throughputs of :func:`detected_fraction` (sums of the bounce
    series), independently of the closed-form coefficients :func:`correct_reading`
    inverts.

    Parameters
    ----------
    diffuse_reflectance
        x, the specimen's diffuse (Lambertian) reflectance, ``0 <= x <= 1 − r``.
    wall_reflectance
        ρw in [0, 1] (array: per wavelength).
    sample_fraction, detector_fraction, open_fraction
        a_s (specimen port), a_d (> 0, counts every arrival), a_o (entrance and other
        open ports): cap fractions (exact) unless a convention is being compared.
    trap_fraction
        a_t, the specular port: open to a light trap in SCE (lost), plugged with wall
        material in SCI (part of the wall).
    reference_fraction
        a_r, the comparison port: it holds the standard in the comparison method and is
        plugged with wall material in substitution (where the standard replaces the
        specimen in the sample port), so one sphere description serves both methods.
    standard_reflectance
        ρ_std in (0, 1], the Lambertian reference standard's reflectance.
    specular_reflectance
        r in [0, 1], the specimen's specular reflectance at 8° (e.g.
        :func:`fresnel_reflectance`); it also returns diffuse light with ``u = x + r``.
    method
        ``"substitution"`` (single beam) or ``"comparison"`` (standard in the reference
        port at the same time, beam moved between them).
    mode
        ``"SCI"`` or ``"SCE"``.
    port_surface
        ``"flat"`` (exact geometry) or ``"cap"`` (Goebel / iadpython).

    Returns
    -------
    float or ndarray
        M = ρ_std · P(specimen) / P(standard).
    """

    method, mode, surface, rho_w, a_s, a_d, a_o, a_t, a_r, rho_std, r = _sphere(
        method, mode, port_surface, wall_reflectance, sample_fraction, detector_fraction, open_fraction,
        trap_fraction, reference_fraction, standard_reflectance, specular_reflectance)
    x = _within("diffuse_reflectance", diffuse_reflectance, 0.0, 1.0)
    if np.any(x + r > 1.0 + 1e-15):
        raise ValueError(f"diffuse_reflectance must satisfy 0 <= diffuse_reflectance <= 1 - specular_reflectance "
                         f"(got diffuse_reflectance + specular_reflectance = {_shown(x + r, x + r > 1.0 + 1e-15)})")
    sci = 1.0 if mode == "SCI" else 0.0
    a_w = _wall(method, mode, a_s, a_d, a_o, a_t, a_r)
    if method == "substitution":
        t_s, _, t_w = _throughputs(rho_w, a_w, a_d, a_s, x + r, 0.0, 0.0, surface)
        t_std, _, _ = _throughputs(rho_w, a_w, a_d, a_s, rho_std, 0.0, 0.0, surface)
        return _out((x * t_s + sci * r * rho_w * t_w) / t_std)
    t_s, t_std, t_w = _throughputs(rho_w, a_w, a_d, a_s, x + r, a_r, rho_std, surface)
    return _out((x * t_s + sci * r * rho_w * t_w) / t_std)


def substitution_reading(diffuse_reflectance: Any, **sphere: Any) -> Any:
    """:func:`instrument_reading` with ``method="substitution"`` (same keywords)."""

    return instrument_reading(diffuse_reflectance, method="substitution", **sphere)


def comparison_reading(diffuse_reflectance: Any, **sphere: Any) -> Any:
    """:func:`instrument_reading` with ``method="comparison"`` (same keywords; ``reference_fraction > 0``)."""

    return instrument_reading(diffuse_reflectance, method="comparison", **sphere)


def sci_sce_readings(diffuse_reflectance: Any, **sphere: Any) -> tuple[Any, Any]:
    """
    ``(SCI, SCE)`` readings of one specimen on one sphere (keywords of
    :func:`instrument_reading`, ``mode`` excepted). In the cap model with the comparison
    method, ``SCI − SCE = r ρw``: the excluded specular part (times the plug's ρw).
    """

    if "mode" in sphere:
        raise ValueError("mode must not be given to sci_sce_readings (it returns both)")
    return (instrument_reading(diffuse_reflectance, mode="SCI", **sphere),
            instrument_reading(diffuse_reflectance, mode="SCE", **sphere))


def correct_reading(reading: Any, *, wall_reflectance: Any, sample_fraction: Any, detector_fraction: Any,
                    open_fraction: Any = 0.0, trap_fraction: Any = 0.0, reference_fraction: Any = 0.0,
                    standard_reflectance: Any = 0.99, specular_reflectance: Any = 0.0,
                    method: str = "substitution", mode: str = "SCI", port_surface: str = "flat") -> Any:
    """
    The hemispherical reflectance ``ρ = x + r`` behind an instrument reading: the exact
    inverse of :func:`instrument_reading` (same keywords, same meaning).

    The reading is ``M = Q (n₁ x + n₀) / (d₀ − d₁ x)`` (coefficients from the sphere,
    see the module docstring), increasing in x, so ``x = (M d₀ − Q n₀)/(Q n₁ + M d₁)``.
    For SCE the specular part r must be given (e.g. Fresnel) to return the
    hemispherical value; with r = 0 an SCE reading corrects to the diffuse part.

    Parameters
    ----------
    reading
        M, the instrument's reflectance factor (array: per wavelength). It must lie in
        ``[M(0), M(1 − r)]`` for this sphere, else ``ValueError`` naming ``reading``.

    Returns
    -------
    float or ndarray
        ρ in ``[r, 1]``.
    """

    method, mode, surface, rho_w, a_s, a_d, a_o, a_t, a_r, rho_std, r = _sphere(
        method, mode, port_surface, wall_reflectance, sample_fraction, detector_fraction, open_fraction,
        trap_fraction, reference_fraction, standard_reflectance, specular_reflectance)
    m = _array("reading", reading)
    q, n1, n0, d0, d1 = _coefficients(method, mode, surface, rho_w, a_s, a_d, a_o, a_t, a_r, rho_std, r)
    low = q * n0 / d0
    high = q * (n1 * (1.0 - r) + n0) / (d0 - d1 * (1.0 - r))
    _check_reading(m, low, high, "M(0) <= reading <= M(1 - specular_reflectance)",
                   "; it is no reading of a specimen with 0 <= reflectance <= 1")
    x = (m * d0 - q * n0) / (q * n1 + m * d1)
    return _out(np.clip(x, 0.0, 1.0 - r) + r)


# ---------------------------------------------------------------------- transmittance
def _transmission_sphere(wall_reflectance, entrance_fraction, sample_fraction, detector_fraction,
                         open_fraction, standard_reflectance, sample_reflectance, port_surface):
    surface = _choice("port_surface", port_surface, PORT_SURFACES)
    rho_w = _within("wall_reflectance", wall_reflectance, 0.0, 1.0)
    rho_std = _within("standard_reflectance", standard_reflectance, 0.0, 1.0, low_open=True)
    u = _within("sample_reflectance", sample_reflectance, 0.0, 1.0)
    f = _fractions(entrance_fraction=entrance_fraction, sample_fraction=sample_fraction,
                   detector_fraction=detector_fraction, open_fraction=open_fraction)
    a_e, a_q, a_d = f["entrance_fraction"], f["sample_fraction"], f["detector_fraction"]
    a_w = 1.0 - sum(f.values())
    t_spec, t_std, _ = _throughputs(rho_w, a_w, a_d, a_e, u, a_q, rho_std, surface)
    _, t_open, _ = _throughputs(rho_w, a_w, a_d, a_e, 0.0, a_q, rho_std, surface)
    # P(specimen) = x t_spec + t_c ρ_std t_std ; P(open port) = ρ_std t_open
    return t_spec / (rho_std * t_open), t_std / t_open


def transmittance_reading(diffuse_transmittance: Any, *, wall_reflectance: Any, entrance_fraction: Any,
                          sample_fraction: Any, detector_fraction: Any, open_fraction: Any = 0.0,
                          standard_reflectance: Any = 0.99, sample_reflectance: Any = 0.0,
                          collimated_transmittance: Any = 0.0, port_surface: str = "flat") -> Any:
    """
    The transmittance factor a sphere reads with the specimen at the entrance port.

    The 100 % line is taken with the entrance port open: the beam crosses the sphere
    and hits the standard (ρ_std) in the opposite port. With the specimen in place its
    diffusely transmitted part x leaves the entrance disk Lambertian; its unscattered
    part t_c hits the standard as the reference beam did; the specimen returns diffuse
    light that reaches it from inside with ``sample_reflectance``.

    Parameters
    ----------
    diffuse_transmittance
        x in [0, 1 − t_c].
    wall_reflectance
        ρw in [0, 1].
    entrance_fraction
        a_e, the port the specimen covers.
    sample_fraction
        a_q, the opposite port holding the standard (the reflectance port).
    detector_fraction, open_fraction
        a_d (> 0) and every other open port.
    standard_reflectance
        ρ_std in (0, 1].
    sample_reflectance
        u in [0, 1], the specimen's reflectance for diffuse light from inside.
    collimated_transmittance
        t_c in [0, 1], unscattered transmittance.
    port_surface
        ``"flat"`` or ``"cap"``.

    Returns
    -------
    float or ndarray
        ``M_T = x g + t_c h``: ``g = T_A / (ρ_std T_open)``, ``h = T_std / T_open``
        (throughputs of :func:`detected_fraction` with two disks).
    """

    g, h = _transmission_sphere(wall_reflectance, entrance_fraction, sample_fraction, detector_fraction,
                                open_fraction, standard_reflectance, sample_reflectance, port_surface)
    x = _within("diffuse_transmittance", diffuse_transmittance, 0.0, 1.0)
    t_c = _within("collimated_transmittance", collimated_transmittance, 0.0, 1.0)
    if np.any(x + t_c > 1.0 + 1e-15):
        raise ValueError("diffuse_transmittance must satisfy 0 <= diffuse_transmittance <= "
                         "1 - collimated_transmittance")
    return _out(x * g + t_c * h)


def correct_transmittance(reading: Any, *, wall_reflectance: Any, entrance_fraction: Any, sample_fraction: Any,
                          detector_fraction: Any, open_fraction: Any = 0.0, standard_reflectance: Any = 0.99,
                          sample_reflectance: Any = 0.0, collimated_transmittance: Any = 0.0,
                          port_surface: str = "flat") -> Any:
    """
    The hemispherical transmittance ``x + t_c`` behind a reading of
    :func:`transmittance_reading` (same keywords): ``x = (M_T − t_c h) / g``.
    A reading outside ``[M_T(0), M_T(1 − t_c)]`` raises ``ValueError`` naming ``reading``.
    """

    g, h = _transmission_sphere(wall_reflectance, entrance_fraction, sample_fraction, detector_fraction,
                                open_fraction, standard_reflectance, sample_reflectance, port_surface)
    m = _array("reading", reading)
    t_c = _within("collimated_transmittance", collimated_transmittance, 0.0, 1.0)
    low, high = t_c * h, (1.0 - t_c) * g + t_c * h
    _check_reading(m, low, high, "M_T(0) <= reading <= M_T(1 - collimated_transmittance)")
    return _out(np.clip((m - t_c * h) / g, 0.0, 1.0 - t_c) + t_c)


def _check_reading(m: np.ndarray, low: np.ndarray, high: np.ndarray, rule: str, note: str = "") -> None:
    """``ValueError`` naming ``reading`` when a reading lies outside [low, high] (beyond rounding)."""

    slack = _READING_SLACK * np.maximum(np.abs(high), 1.0)
    bad = (m < low - slack) | (m > high + slack)
    if np.any(bad):
        shape = np.broadcast(m, low, high).shape
        bad = np.broadcast_to(bad, shape)
        lo, hi, got = (np.broadcast_to(v, shape)[bad].flat[0] for v in (low, high, m))
        raise ValueError(f"reading must satisfy {rule} for this sphere, i.e. {lo:.6g} <= reading <= {hi:.6g} "
                         f"(got {shown_value(float(got))}){note}")
