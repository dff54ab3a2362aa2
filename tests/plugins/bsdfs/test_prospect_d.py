"""
Tests of the PROSPECT-D plugin (plugins/bsdfs/prospect_d.py): the instrument measures the model
(:mod:`virtspec_mi.plugins.bsdfs.prospect_model`, tested in ``tests/plugins/bsdfs/test_prospect_model.py``)
within its certificate, and its parameters go through ``mi.traverse`` with their refusals.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.plugins.bsdfs.prospect_model import prospect_d
from virtspec_mi.runtime.scene import instrument_scene


WAVELENGTHS = [450.0, 550.0, 680.0, 800.0, 1450.0, 1940.0, 2200.0]


@pytest.mark.parametrize("theta_i", [0.0, 45.0])
def test_plugin_measures_the_model_within_its_certificate(mi, theta_i):
    leaf = {"N": 1.8, "Cab": 55.0, "Car": 9.0, "Anth": 2.0, "Cw": 0.02, "Cm": 0.007}
    scene = instrument_scene({"type": "prospect_d", **leaf})
    result = vm.measure(scene, wavelengths=WAVELENGTHS, theta_i=theta_i, mu=0.005, delta=1e-3, seed=3)
    reflectance, transmittance = prospect_d(WAVELENGTHS, **leaf)
    for quantity, model in (("reflectance", reflectance), ("transmittance", transmittance)):
        spectrum = result.spectrum(quantity)
        assert np.all(np.abs(spectrum.values - model) <= spectrum.tolerance), quantity


def test_plugin_parameters_through_traverse_and_refusals(mi):
    scene = mi.load_dict(instrument_scene({"type": "prospect_d"}))
    assert set(vm.engine.parameters.known_parameters(scene)) >= {"specimen.Cab", "specimen.N", "specimen.Cm"}
    result = vm.measure(scene, parameters={"specimen.Cab": 10.0}, wavelengths=[550.0], mu=0.01, delta=1e-3)
    model, _ = prospect_d([550.0], Cab=10.0)
    assert abs(result.spectrum("reflectance").values[0] - model[0]) <= 0.01
    with pytest.raises(ValueError, match="'N'.*1 <= N <= 4"):
        vm.measure(scene, parameters={"specimen.N": 0.5}, wavelengths=[550.0], mu=0.05)
    with pytest.raises(ValueError, match="400"):
        vm.measure(scene, wavelengths=[380.0], mu=0.05)
    with pytest.raises((ValueError, RuntimeError), match="'Cab' must be a number"):  # Mitsuba wraps it
        mi.load_dict({"type": "prospect_d", "Cab": "lots"})
