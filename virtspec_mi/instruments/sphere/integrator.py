"""
``integrating_sphere``: a physical integrating sphere around the specimen (Mitsuba integrator)
==============================================================================================

The ``spectrophotometer`` integrator's settings plus a sphere description: the sphere
of :mod:`virtspec_mi.instruments.sphere.geometry` and how it is read: the fields of
:class:`virtspec_mi.instruments.sphere.SphereOptions`, the one definition.
A thin adapter: it reads its parameters with the one reader
(:meth:`virtspec_mi.settings.Options.from_parameters`), :func:`virtspec_mi.sphere_measure`
takes them from a scene as its defaults, and ``mi.render`` takes the sphere readings with
the ``sphere`` instrument of the registry (:data:`virtspec_mi.instruments.INSTRUMENTS`).
It takes every parameter of ``spectrophotometer`` (theta_i, phi_i, wavelengths, mu, delta,
rays, bound, joint, pilot_rays, pilot_delta, beam, sampling, seed, chunk_size) and these:

Parameters
----------
diameter : float, required
    Inner diameter of the sphere, mm (> 0).
wall_reflectance : float or string, default 0.98
    ρw in [0, 1]: a number, or ``"nm:value, nm:value, …"`` (linear interpolation).
port_<name> : string
    One per port: ``"role=ROLE polar=DEG azimuth=DEG radius=MM"``; ROLE one of sample,
    entrance, reference, detector, specular, open; polar/azimuth of the port centre in
    sphere coordinates (centre at the origin, +z up).
    A port string may add (:mod:`virtspec_mi.instruments.sphere.ports`): ``depth=MM``
    (a port wall), ``edge_reflectance=R``, ``shape=ellipse|rectangle width=MM
    height=MM`` (instead of radius), ``aperture=MM mask_reflectance=R`` (a holder mask),
    ``field_of_view=DEG`` (a detector's cone half-angle).
baffle : string, optional
    ``"centre=x,y,z normal=x,y,z radius=r"`` (mm, sphere coordinates).
beam_profile : string, optional
    ``"shape=point|ellipse|rectangle width=MM height=MM divergence=DEG"``: a traced beam
    (:mod:`virtspec_mi.instruments.sphere.beam`).
wall_specular : float, default 0
    The mirror share of the wall's reflection, 0 … 1.
measurement : string, default "reflectance"
    ``reflectance`` (specimen in the sample port) or ``transmittance`` (at the entrance port).
specular : string, default "SCI"
    ``SCI`` (specular port plugged) or ``SCE`` (open to a light trap).
method : string, default "substitution"
    ``substitution`` (single beam) or ``comparison`` (standard in the reference port, swapped).
standard : float, default 0.99
    Reflectance of the Lambertian reference standard, 0 < standard ≤ 1.
max_bounces : integer, default 100000
    Step cap of a sphere walk (capped walks are counted, the reading then not certified).
detector : string, default "counted"
    ``counted`` (every ray reaching the detector port counted; Clopper–Pearson) or
    ``expected`` (each wall bounce scores its exact chance of reaching the detector, a score
    per ray in [0, 1]; empirical Bernstein; a plain sphere only:
    :mod:`virtspec_mi.instruments.sphere.expected`).

Notes
-----
``mi.render(scene)`` returns a ``TensorXf`` of shape ``(len(wavelengths), 4)``: per
wavelength the reading, the hemispherical reading of the same rays, and the detector
fractions with the sample and with the standard; the full
:class:`~virtspec_mi.instruments.sphere.result.SphereResult` is kept in ``integrator.last_reading``.
"""

from __future__ import annotations

from typing import Any

import mitsuba as mi

from virtspec_mi.instruments.sphere import IntegratingSphere

from virtspec_mi.instruments.integrator import Spectrophotometer

__all__ = ["IntegratingSphereIntegrator"]


class IntegratingSphereIntegrator(Spectrophotometer):
    """The sphere instrument as a Mitsuba integrator (see the module docstring)."""

    plugin = "integrating_sphere"

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        if self.instrument_options.sphere is None:
            raise ValueError(f"{self.plugin}: sphere: diameter (mm) is required")
        self.sphere_options = self.instrument_options

    def instrument_name(self, parameters: Any) -> str:
        """Always the integrating sphere."""

        return IntegratingSphere.name

    def to_string(self) -> str:
        return f"IntegratingSphere[{self.sphere_options.sphere.describe()}; {self.sphere_options.as_dict()}]"
