"""
``double_sphere``: a double integrating sphere around the specimen (Mitsuba integrator)
=======================================================================================

The ``spectrophotometer`` integrator's settings plus two sphere descriptions, read by the
one definition (:class:`virtspec_mi.instruments.sphere.double.DoubleSphereOptions`): the
reflectance sphere's parameters are the ``integrating_sphere`` integrator's (``diameter``,
``wall_reflectance``, ``port_<name>``, ``baffle``), the transmittance sphere's the same
with the prefix ``t_`` (``t_diameter``, ``t_wall_reflectance``, ``t_port_<name>``,
``t_baffle``). ``mi.render`` takes the readings with the ``double_sphere`` instrument of
the registry.

Parameters
----------
diameter, wall_reflectance, port_<name>, baffle
    The reflectance sphere (ports with roles entrance, sample, detector; see
    :mod:`virtspec_mi.instruments.sphere.integrator`).
t_diameter, t_wall_reflectance, t_port_<name>, t_baffle
    The transmittance sphere (ports with roles entrance — where the specimen sits — and
    detector; a ``sample`` port holds the white standard).
standard : float, default 0.99
    Reflectance of the Lambertian reference standard, 0 < standard ≤ 1.
specular : string, default "SCI"
    The reflectance sphere's specular port (if any): ``SCI`` plugged, ``SCE`` open.
max_bounces : integer, default 100000
    Step cap of a walk through both spheres.

Notes
-----
``mi.render(scene)`` returns a ``TensorXf`` of shape ``(len(wavelengths), 4)``: per
wavelength M_R, M_T and the hemispherical R and T of the same rays; the full
:class:`~virtspec_mi.instruments.sphere.double_result.DoubleSphereResult` is kept in
``integrator.last_reading``.
"""

from __future__ import annotations

from typing import Any

import mitsuba as mi

from virtspec_mi.instruments.integrator import Spectrophotometer
from virtspec_mi.instruments.sphere.double import DoubleSphere

__all__ = ["DoubleSphereIntegrator"]


class DoubleSphereIntegrator(Spectrophotometer):
    """The double-sphere instrument as a Mitsuba integrator (see the module docstring)."""

    plugin = "double_sphere"

    def __init__(self, props: mi.Properties) -> None:
        super().__init__(props)
        self.instrument_options.spheres()  # both spheres given and ideal, or a ValueError naming what is wrong

    def instrument_name(self, parameters: Any) -> str:
        """Always the double sphere."""

        return DoubleSphere.name

    def to_string(self) -> str:
        return f"DoubleSphere[{self.instrument_options.as_dict()}]"
