"""
Tests of :mod:`virtspec_mi.applications.fitting.problem`: a fit's inputs, checked before any ray.

PROSPECT-D's scene is loaded once per test (no ray is traced): the free parameters are named
with or without ``specimen.``, their bounds normalised and back (clipped to the box), the
scene's own values kept as the start and restored, the measured spectra put on the fit's
wavelengths by linear interpolation; every bad input — no parameter, an unknown one (the
answer lists each with units and bounds), bounds that are no pair or out of order or outside
the specimen's, a spectrum without uncertainty, wavelengths outside the data or the
specimen's range, a quantity a fit does not match — is refused naming it.

References
----------
Baranoski et al. (2001), Sect. 5.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.applications.fitting.problem import FIT_QUANTITIES, describe, fit_problem

WAVELENGTHS = np.array([500.0, 550.0, 600.0, 650.0])
REFLECTANCE = (WAVELENGTHS, np.array([0.10, 0.20, 0.14, 0.08]), np.full(4, 0.01))


def test_a_checked_problem(mi):
    problem = fit_problem(REFLECTANCE, "prospect_d", {"Cab": (10, 80), "specimen.N": "1.2:2.5"},
                          wavelengths=[575.0, 525.0])
    assert problem.names == ("Cab", "specimen.N") and problem.keys == ("specimen.Cab", "specimen.N")
    np.testing.assert_array_equal(problem.bounds, [[10.0, 80.0], [1.2, 2.5]])
    np.testing.assert_array_equal(problem.wavelengths, [525.0, 575.0])  # sorted, distinct
    np.testing.assert_allclose(problem.measured["reflectance"], [0.15, 0.17])  # linear between the data
    np.testing.assert_allclose(problem.uncertainty["reflectance"], [0.01, 0.01])
    assert problem.quantities == ("reflectance",) and problem.specimen == "prospect_d"
    assert problem.start == (40.0, 1.5)  # the scene's own values
    assert problem.fingerprint in problem.fingerprints and problem.scene is problem.bench.scene
    assert "prospect_d" in describe(problem)
    assert FIT_QUANTITIES == ("reflectance", "transmittance")


def test_normalised_coordinates_round_trip_and_clip(mi):
    problem = fit_problem(REFLECTANCE, "prospect_d", {"Cab": (10, 80), "N": (1.0, 3.0)})
    np.testing.assert_allclose(problem.normalised([45.0, 2.0]), [0.5, 0.5])
    np.testing.assert_allclose(problem.denormalised(problem.normalised([17.0, 2.9])), [17.0, 2.9])
    np.testing.assert_allclose(problem.denormalised([-0.5, 1.5]), [10.0, 3.0])


def test_measurement_uncertainty_given_for_the_fit(mi):
    without = (WAVELENGTHS, REFLECTANCE[1])
    with pytest.raises(ValueError, match=r"the measured reflectance of .* has no uncertainty: a fit states which "
                                         r"parameters are consistent with the measurement"):
        fit_problem(without, "prospect_d", {"Cab": (10, 80)})
    problem = fit_problem(without, "prospect_d", {"Cab": (10, 80)}, measurement_uncertainty=0.02)
    np.testing.assert_allclose(problem.uncertainty["reflectance"], 0.02)
    with pytest.raises(ValueError, match=r"must be > 0 at every fitted wavelength"):
        fit_problem(without, "prospect_d", {"Cab": (10, 80)}, measurement_uncertainty=0.0)


@pytest.mark.parametrize("parameters, message", [
    ({}, r"a fit needs free parameters: name -> \(lowest, highest\)"),
    ({"Chl": (10, 80)}, r"the specimen prospect_d has no parameter 'Chl' \(its parameters: .*Cab \(ug/cm2, 0-150\)"),
    ({"Cab": 10}, r"the bounds of free parameter 'Cab' must be \(lowest, highest\) \(got 10\)"),
    ({"Cab": (80, 10)}, r"the bounds of free parameter 'Cab' must be finite with lowest < highest \(got 80, 10\)"),
    ({"Cab": (10, 200)},
     r"PROSPECT-D: 'Cab' \(chlorophylls a \+ b\) must satisfy 0 <= Cab <= 150 ug/cm2 \(got 200.0\)"),
])
def test_bad_parameters_are_refused_naming_them(mi, parameters, message):
    with pytest.raises(ValueError, match=message):
        fit_problem(REFLECTANCE, "prospect_d", parameters)


def test_bad_spectra_are_refused_naming_them(mi):
    with pytest.raises(ValueError, match=r"the fit's wavelengths 450-550 nm reach outside the measured reflectance .* "
                                         r"\(500-650 nm\): never extrapolated"):
        fit_problem(REFLECTANCE, "prospect_d", {"Cab": (10, 80)}, wavelengths=[450.0, 550.0])
    early = (np.array([350.0, 450.0]), np.array([0.1, 0.1]), np.array([0.01, 0.01]))
    with pytest.raises(ValueError, match=r"the measured spectrum reaches 350-450 nm, outside the data range of the "
                                         r"specimen prospect_d \(400-2500 nm\)"):
        fit_problem(early, "prospect_d", {"Cab": (10, 80)})
    with pytest.raises(ValueError, match=r"a fit matches reflectance or transmittance spectra \(got 'absorptance'\)"):
        fit_problem({"absorptance": REFLECTANCE}, "prospect_d", {"Cab": (10, 80)})
    with pytest.raises(ValueError, match="a fit needs a measured reflectance or transmittance spectrum"):
        fit_problem({}, "prospect_d", {"Cab": (10, 80)})


def test_one_column_is_not_both_quantities(mi, tmp_path):
    path = tmp_path / "leaf.csv"
    path.write_text("500,0.1,0.01\n600,0.2,0.01\n")  # no header: one unnamed value column
    with pytest.raises(ValueError, match=r"the measured file .*leaf.csv holds one value column: it cannot be both"):
        fit_problem(str(path), "prospect_d", {"Cab": (10, 80)}, quantities=("reflectance", "transmittance"))
    both = fit_problem({"reflectance": REFLECTANCE, "transmittance": REFLECTANCE}, "prospect_d", {"Cab": (10, 80)})
    assert both.quantities == ("reflectance", "transmittance")
