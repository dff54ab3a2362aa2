"""Tests of virtspec_mi.instruments.sphere.double_integrator: the double_sphere Mitsuba integrator."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi import scenes


def test_mi_render_returns_both_readings_and_the_hemispherical_values():
    vm.mitsuba()
    import mitsuba as mi

    scene = mi.load_file(str(scenes.path("double_sphere_leaf")), wavelengths="550,850")
    integrator = scene.integrator()
    integrator.settings = integrator.settings.updated(rays=1500)
    table = np.asarray(mi.render(scene))
    reading = integrator.last_reading
    assert table.shape == (2, 4)
    assert table[:, 0] == pytest.approx(reading.reflectance, rel=1e-6)
    assert table[:, 1] == pytest.approx(reading.transmittance, rel=1e-6)
    assert table[:, 3] == pytest.approx(reading.hemispherical_transmittance, rel=1e-6)


def test_a_double_sphere_integrator_without_its_second_sphere_is_refused():
    vm.mitsuba()
    import mitsuba as mi

    with pytest.raises(Exception, match="transmittance_sphere"):
        mi.load_dict({"type": "double_sphere", "diameter": 30, "port_sample": "role=sample polar=180 radius=5",
                      "port_entrance": "role=entrance polar=15.54 radius=2",
                      "port_detector": "role=detector polar=90 azimuth=90 radius=2"})
