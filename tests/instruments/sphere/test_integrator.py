"""
Tests of :mod:`virtspec_mi.instruments.sphere.integrator`: the ``integrating_sphere`` Mitsuba integrator.

It is always the sphere instrument, refuses a scene without the sphere's diameter naming it,
reads the ports and the sphere's options from its parameters, and ``mi.render`` returns per
wavelength the reading, the hemispherical reading and the two detector fractions of the
reading it keeps (moved here from ``test_sphere.py``).

References
----------
Mitsuba 3, ``mi.SamplingIntegrator`` (Python integrators).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm

SCENE = str(Path(__file__).resolve().parents[3] / "scenes" / "sphere_150mm_8d.xml")


def test_a_sphere_needs_its_diameter(mi):
    with pytest.raises(Exception, match=r"integrating_sphere: sphere: diameter \(mm\) is required"):
        mi.load_dict({"type": "integrating_sphere"})


def test_the_sphere_is_read_from_the_parameters(mi):
    integrator = mi.load_dict({"type": "integrating_sphere", "diameter": 60.0, "wall_reflectance": 0.97,
                               "specular": "SCE", "port_s": "role=sample polar=180 radius=5",
                               "port_e": "role=entrance polar=10 radius=4",
                               "port_d": "role=detector polar=90 azimuth=90 radius=3"})
    assert integrator.instrument.name == "sphere" and integrator.instrument_name({}) == "sphere"
    options = integrator.sphere_options
    assert options.sphere.diameter == 60.0 and options.specular == "SCE"
    assert sorted(port.role for port in options.sphere.ports) == ["detector", "entrance", "sample"]
    assert integrator.to_string().startswith("IntegratingSphere[")


def test_mi_render_gives_the_sphere_table():
    mi = vm.mitsuba()
    scene = mi.load_file(SCENE)
    table = np.array(mi.render(scene, spp=5000))
    reading = scene.integrator().last_reading
    assert table.shape == (1, 4)
    assert table[0] == pytest.approx([reading.reading[0], reading.hemispherical[0], reading.detector_fraction[0],
                                      reading.standard_fraction[0]], rel=1e-6)
