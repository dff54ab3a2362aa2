"""
A sphere description in the terms of the sphere theory (the one rule that ties them)
====================================================================================

:mod:`virtspec_mi.instruments.sphere.geometry` describes a physical sphere (ports with roles, wall, baffle),
the sphere's options say how it is read (:class:`ReadingMode`: plain values, whatever
options class carries them);
:mod:`virtspec_mi.instruments.sphere.theory` predicts readings from port *fractions*. This module is
the single place where the one becomes the other: :func:`theory_inputs` maps a sphere,
its reading mode and the specimen disk's radius to the keywords of
:func:`~virtspec_mi.instruments.sphere.theory.instrument_reading` /
:func:`~virtspec_mi.instruments.sphere.theory.correct_reading` (reflectance) or
:func:`~virtspec_mi.instruments.sphere.theory.transmittance_reading` /
:func:`~virtspec_mi.instruments.sphere.theory.correct_transmittance` (transmittance), exactly as the
simulation (:func:`virtspec_mi.instruments.sphere.configurations`) treats each port:

=========  ==========================================  ===========================
role       reflectance                                 transmittance
=========  ==========================================  ===========================
sample     ``sample_fraction`` (the specimen disk)     ``sample_fraction`` (the
                                                       standard, in both readings)
entrance   ``open_fraction`` (the beam's way in)       ``entrance_fraction`` (the
                                                       specimen, lit from outside)
reference  ``reference_fraction``: the standard        ``open_fraction``
           (comparison), a wall plug (substitution)
detector   ``detector_fraction`` (every one counts)    ``detector_fraction``
specular   ``trap_fraction``: a trap (SCE), a plug     ``open_fraction`` (SCE),
           (SCI)                                       wall (SCI)
open       ``open_fraction``                           ``open_fraction``
=========  ==========================================  ===========================

**Port convention:** the fractions are the exact cap fractions h/2R
(:meth:`virtspec_mi.instruments.sphere.geometry.Sphere.cap_fraction`) and ``port_surface="flat"``: the
specimen and the standards are flat disks in their port planes, as simulated. A disk
smaller than its port (radius ρ < r) receives on average the share ρ²/(4R²(1 − a)) of
wall emission (a: the port's cap fraction; exact for a uniformly bright wall, equal to
a when ρ = r); the rest of the cap is open (lost). ρw is the sphere's wall
reflectance at the reading's wavelengths (an array).

**Not modelled by the theory:** a baffle (it shades the detector from the first
emission of the specimen, the 1/G share of the signal detected before any wall bounce);
non-Lambertian specimens (their first emission does not land uniformly); a narrow beam
spot (:func:`~virtspec_mi.instruments.sphere.theory.spot_landing_density`). The readings of the
simulation differ from the theory by these, which is what the validation tests measure.

References
----------
Goebel (1967), eq. 2 (port fractions); :mod:`virtspec_mi.instruments.sphere.theory` (the models).
"""

from __future__ import annotations

import math
from typing import Any, Protocol, Sequence

import numpy as np

from virtspec_mi.instruments.sphere.geometry import Sphere
from virtspec_mi.instruments.sphere.theory import (correct_reading, correct_transmittance, detected_fraction,
                                                  instrument_reading, transmittance_reading)

__all__ = ["REFLECTANCE_ROLES", "TRANSMITTANCE_ROLES", "ReadingMode", "disk_share", "theory_inputs",
           "invertible_range", "correct_readings"]


class ReadingMode(Protocol):
    """
    How a sphere is read, as :func:`theory_inputs` takes it: the plain values of the
    sphere's options (any object with these attributes; this module imports no options
    class, which belongs to the instrument above it).
    """

    measurement: str
    """``"reflectance"`` or ``"transmittance"``."""
    specular: str
    """``"SCI"`` or ``"SCE"``."""
    method: str
    """``"substitution"`` or ``"comparison"``."""
    standard: float
    """Reflectance of the white standard."""

REFLECTANCE_ROLES: dict[str, str] = {
    "sample": "sample_fraction", "entrance": "open_fraction", "reference": "reference_fraction",
    "detector": "detector_fraction", "specular": "trap_fraction", "open": "open_fraction",
}
"""Port role → keyword of :func:`~virtspec_mi.instruments.sphere.theory.instrument_reading` (reflectance)."""

TRANSMITTANCE_ROLES: dict[str, str | None] = {
    "sample": "sample_fraction", "entrance": "entrance_fraction", "reference": "open_fraction",
    "detector": "detector_fraction", "specular": "open_fraction", "open": "open_fraction",
}
"""Port role → keyword of :func:`~virtspec_mi.instruments.sphere.theory.transmittance_reading`
(the specular port: open in SCE, wall in SCI)."""


def disk_share(sphere: Sphere, port: Any, disk_radius: float) -> float:
    """
    Share of wall emission a flat disk of radius ``disk_radius`` centred in ``port``'s
    plane receives: the port's cap fraction a for a disk filling it, else
    ρ²/(4R²(1 − a)) (the average over a uniformly bright wall, by reciprocity).
    """

    port = sphere._named(port)
    if not 0.0 < disk_radius <= port.radius * (1.0 + 1e-9):
        raise ValueError(f"disk_radius must satisfy 0 < disk_radius <= {port.radius:g} mm, the radius of port "
                         f"{port.name!r} (got {disk_radius!r})")
    cap = sphere.cap_fraction(port)
    if disk_radius >= port.radius * (1.0 - 1e-12):
        return cap
    return disk_radius**2 / (4.0 * sphere.radius**2 * (1.0 - cap))


def theory_inputs(sphere: Sphere, options: ReadingMode, wavelengths: Sequence[float],
                  specimen_radius: float | None = None) -> dict[str, Any]:
    """
    The :mod:`~virtspec_mi.instruments.sphere.theory` keywords of a sphere reading (see the module
    docstring for the rule).

    Parameters
    ----------
    sphere
        The sphere.
    options
        How it is read (:class:`ReadingMode`): ``measurement``, ``specular`` (``mode``),
        ``method``, ``standard``.
    wavelengths
        nm; ``wall_reflectance`` is ρw at these (an array).
    specimen_radius
        Radius of the specimen disk, mm (default: filling its port). In the comparison
        method the standard in the reference port has this radius too, as simulated.

    Returns
    -------
    dict
        Reflectance: ``wall_reflectance``, ``sample_fraction``, ``detector_fraction``,
        ``open_fraction``, ``trap_fraction``, ``reference_fraction``,
        ``standard_reflectance``, ``method``, ``mode``, ``port_surface="flat"`` — the
        keywords of ``instrument_reading`` / ``correct_reading``. Transmittance:
        ``wall_reflectance``, ``entrance_fraction``, ``sample_fraction``,
        ``detector_fraction``, ``open_fraction``, ``standard_reflectance``,
        ``port_surface`` — those of ``transmittance_reading`` / ``correct_transmittance``.
    """

    transmittance = options.measurement == "transmittance"
    if sphere.wall_specular or sphere.wall_bsdf is not None:
        raise ValueError("the sphere theory does not model a non-Lambertian wall (a mirror share, wall_specular "
                         f"{sphere.wall_specular:g}, or a wall_bsdf): its light does not land uniformly")
    beam_role = "entrance" if transmittance else "sample"
    beam_port = sphere.port(beam_role)
    if beam_port is None:
        raise ValueError(f"sphere: a {options.measurement} reading needs a port with role {beam_role!r}")
    if sphere.port("detector") is None:
        raise ValueError("sphere: a reading needs a port with role 'detector'")
    radius = beam_port.radius if specimen_radius is None else float(specimen_radius)
    roles = TRANSMITTANCE_ROLES if transmittance else REFLECTANCE_ROLES
    out: dict[str, Any] = {name: 0.0 for name in set(roles.values())}
    comparison = options.method == "comparison" and not transmittance
    for port in sphere.ports:
        cap = sphere.cap_fraction(port)
        key = roles[port.role]
        if transmittance and (port.role == "specular" and options.specular == "SCI"
                              or port.role == "reference" and sphere.port("sample") is None):
            continue  # plugged with wall material: wall (as simulated)
        plugged = not transmittance and (port.role == "specular" and options.specular == "SCI"
                                         or port.role == "reference" and not comparison)
        holds = port is beam_port or port.role == "reference" and comparison or port.role == "sample" and transmittance
        if port.aperture is not None and holds:
            raise ValueError(f"the sphere theory does not model port {port.name!r}'s holder mask (aperture "
                             f"{port.aperture:g} mm): read the mask's effect from the simulation (SphereResult.budget)")
        if port.proud and holds:
            raise ValueError(f"the sphere theory does not model a specimen standing proud of port {port.name!r} "
                             f"(proud {port.proud:g} mm): read its effect from the simulation (SphereResult.budget)")
        if port.depth > 0.0 and not plugged:  # a port wall (virtspec_mi.instruments.sphere.ports): black walls only
            if port.field_of_view is not None:
                raise ValueError(f"the sphere theory does not model port {port.name!r}'s field of view behind a port "
                                 "wall (depth > 0)")
            cap = _deep_port(port, cap, out, holder=holds)
        elif port.field_of_view is not None:  # Lambertian light within gamma of the axis: sin^2 gamma of it
            share = math.sin(math.radians(port.field_of_view)) ** 2
            out["open_fraction"] += cap * (1.0 - share)
            cap *= share
        disk = None
        if port is beam_port:
            disk = radius
        elif port.role == "reference" and comparison:
            disk = radius  # the simulation mounts the standard with the specimen's radius
        if disk is not None:
            share = disk_share(sphere, port, disk)
            out[key] += share
            out["open_fraction"] += cap - share
        else:
            out[key] += cap
    out["wall_reflectance"] = sphere.wall_reflectance_at(np.atleast_1d(np.asarray(wavelengths, dtype=float)))
    out["standard_reflectance"] = float(options.standard)
    out["port_surface"] = "flat"
    if not transmittance:
        out["method"] = options.method
        out["mode"] = options.specular
    return out


def _deep_port(port: Any, cap: float, out: dict[str, Any], holder: bool) -> float:
    """
    A port of depth d > 0 in the theory: with black walls (``edge_reflectance=0``) and
    nothing held in it, Lambertian light uniform over its rim disk (a uniformly bright
    wall) reaches its outer end with the disk-to-disk view factor F(d, r) and is absorbed
    otherwise, so the port counts as ``cap · F`` of its role and ``cap · (1 − F)`` open
    (returned: the fraction of its role).
    Anything else (a reflecting port wall, a recessed specimen or standard) the theory
    does not model: ``ValueError``.
    """

    from virtspec_mi.instruments.sphere.ports import disk_view_factor

    if holder or port.edge_reflectance != 0.0:
        raise ValueError(f"the sphere theory does not model port {port.name!r}'s wall (depth {port.depth:g} mm"
                         + (", a specimen or standard recessed in it" if holder else
                            f", edge_reflectance {port.edge_reflectance if port.edge_reflectance is not None else 'rho_w'}")
                         + "): only a black port wall (edge_reflectance=0) of a port holding nothing is modelled")
    share = disk_view_factor(port.depth, port.radius)
    out["open_fraction"] += cap * (1.0 - share)
    return cap * share


def _transmittance(inputs: dict[str, Any]) -> bool:
    return "entrance_fraction" in inputs


def _assumptions(inputs: dict[str, Any], specular_reflectance: Any, sample_reflectance: Any,
                 collimated_transmittance: Any) -> dict[str, Any]:
    if _transmittance(inputs):
        if sample_reflectance is None:
            raise ValueError("sample_reflectance is required to correct a transmittance reading: the specimen's "
                             "reflectance for diffuse light reaching it from inside the sphere, 0 <= "
                             "sample_reflectance <= 1 (e.g. its corrected reflectance reading, or a diffuse-beam "
                             "reading of that face)")
        if np.any(np.asarray(specular_reflectance) != 0.0):
            raise ValueError("specular_reflectance is for reflectance readings (give collimated_transmittance "
                             "for a transmittance reading)")
        return dict(inputs, sample_reflectance=sample_reflectance, collimated_transmittance=collimated_transmittance)
    if np.any(np.asarray(collimated_transmittance) != 0.0):
        raise ValueError("collimated_transmittance is for transmittance readings")
    return dict(inputs, specular_reflectance=specular_reflectance)


def _linear_reflectance(inputs: dict[str, Any], specular_reflectance: Any,
                        sample_reflectance: Any) -> tuple[np.ndarray, np.ndarray]:
    """
    ``(slope, offset)`` of a reflectance reading ``M = slope · x + offset`` when the
    specimen returns the sphere's diffuse light with a *given* reflectance u (not x + r):
    the throughputs of :func:`~virtspec_mi.instruments.sphere.theory.detected_fraction` (flat model)
    with u fixed, ``M = (x T_A(u) + [SCI] r ρw T_wall(u)) / T_std``, T_std the standard's
    (in the sample port for substitution, in the reference port for comparison).
    """

    r = np.asarray(specular_reflectance, dtype=float)
    u = np.asarray(sample_reflectance, dtype=float)
    if np.any((u < 0.0) | (u > 1.0)) or np.isnan(u).any():
        raise ValueError(f"sample_reflectance must satisfy 0 <= sample_reflectance <= 1 (got {sample_reflectance!r})")
    rho_w, rho_std = inputs["wall_reflectance"], inputs["standard_reflectance"]
    open_fraction = inputs["open_fraction"] + (inputs["trap_fraction"] if inputs["mode"] == "SCE" else 0.0)
    kw = dict(sample_fraction=inputs["sample_fraction"], detector_fraction=inputs["detector_fraction"],
              open_fraction=open_fraction, port_surface=inputs["port_surface"])
    if inputs["method"] == "comparison":
        kw.update(second_fraction=inputs["reference_fraction"], second_reflectance=rho_std)
        t_std = detected_fraction(rho_w, u, start="second", **kw)
    else:  # the reference port (a plug) and, in SCI, the specular plug are wall: not in kw
        t_std = detected_fraction(rho_w, rho_std, start="sample", **kw)
    t_a = detected_fraction(rho_w, u, start="sample", **kw)
    t_wall = detected_fraction(rho_w, u, start="wall", **kw)
    sci = 1.0 if inputs["mode"] == "SCI" else 0.0
    return np.asarray(t_a / t_std), np.asarray(sci * r * rho_w * t_wall / t_std)


def invertible_range(inputs: dict[str, Any], *, specular_reflectance: Any = 0.0, sample_reflectance: Any = None,
                     collimated_transmittance: Any = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """
    The readings ``[M(lowest), M(highest)]`` a physical specimen can give on this sphere
    (``inputs`` from :func:`theory_inputs`): M(0) and M(1 − r) in reflectance,
    M_T(0) and M_T(1 − t_c) in transmittance (the theory's forward model).
    """

    kw = _assumptions(inputs, specular_reflectance, sample_reflectance, collimated_transmittance)
    if _transmittance(inputs):
        t_c = np.asarray(collimated_transmittance, dtype=float)
        return (np.asarray(transmittance_reading(0.0, **kw), dtype=float),
                np.asarray(transmittance_reading(1.0 - t_c, **kw), dtype=float))
    r = np.asarray(specular_reflectance, dtype=float)
    if sample_reflectance is not None:
        slope, offset = _linear_reflectance(inputs, specular_reflectance, sample_reflectance)
        return offset, slope * (1.0 - r) + offset
    return (np.asarray(instrument_reading(0.0, **kw), dtype=float),
            np.asarray(instrument_reading(1.0 - r, **kw), dtype=float))


def correct_readings(readings: Any, inputs: dict[str, Any], *, specular_reflectance: Any = 0.0,
                     sample_reflectance: Any = None, collimated_transmittance: Any = 0.0) -> np.ndarray:
    """
    The hemispherical values behind instrument readings: the theory's exact inverse
    (:func:`~virtspec_mi.instruments.sphere.theory.correct_reading`, or
    :func:`~virtspec_mi.instruments.sphere.theory.correct_transmittance`) with the sphere's
    ``inputs`` (:func:`theory_inputs`).

    Parameters
    ----------
    readings
        Readings per wavelength (shape (n,) or (n, 2) for an interval; NaN stays NaN).
        A reading outside :func:`invertible_range` (by noise, e.g. a white specimen read
        above M(1)) is first clipped to it, so it corrects to the range's end; the
        correction is increasing, so the ends of a reading interval map to the ends of
        the corrected interval.
    inputs
        :func:`theory_inputs` of the sphere and the reading.
    specular_reflectance
        Reflectance: r, the specimen's specular (mirror) reflectance at the beam's angle
        (e.g. :func:`~virtspec_mi.instruments.sphere.theory.fresnel_reflectance`); 0 for a matte one.
    sample_reflectance
        The specimen's reflectance for diffuse light reaching it from inside the sphere
        (0 … 1, per wavelength). Transmittance: required. Reflectance: optional — by
        default the theory takes it to be the corrected value x + r itself (a Lambertian
        specimen); given (e.g. a diffuse-beam reading, ``beam="diffuse"``), the reading
        is linear in x, ``M = (x T_A(u) + [SCI] r ρw T_wall(u)) / T_std``, and is
        inverted as such.
    collimated_transmittance
        Transmittance: the unscattered part t_c.

    Returns
    -------
    ndarray
        The corrected (hemispherical) values, the shape of ``readings``.
    """

    kw = _assumptions(inputs, specular_reflectance, sample_reflectance, collimated_transmittance)
    values = np.asarray(readings, dtype=float)
    low, high = invertible_range(inputs, specular_reflectance=specular_reflectance,
                                 sample_reflectance=sample_reflectance,
                                 collimated_transmittance=collimated_transmittance)
    if values.ndim == 2:
        low, high = low[..., None], high[..., None]
        kw = {k: (np.asarray(v)[..., None] if isinstance(v, np.ndarray) and np.ndim(v) else v) for k, v in kw.items()}
    bad = np.isnan(values)
    clipped = np.where(bad, low, np.clip(values, low, high))
    if _transmittance(inputs):
        out = correct_transmittance(clipped, **kw)
    elif sample_reflectance is not None:
        slope, offset = _linear_reflectance(inputs, specular_reflectance, sample_reflectance)
        r = np.asarray(specular_reflectance, dtype=float)
        if values.ndim == 2:
            slope, offset = slope[..., None], offset[..., None]
            r = r[..., None] if r.ndim else r
        out = (clipped - offset) / slope + r
    else:
        out = correct_reading(clipped, **kw)
    return np.where(bad, np.nan, np.asarray(out, dtype=float))
