"""
Tests of :mod:`virtspec_mi.applications.fitting.forward`: a fit's certified forward readings.

Each reading is certified at δ/(n_λ·n_q) and holds PROSPECT-D's model spectrum within its
tolerance (fixed seed); a candidate asked again is remembered, and with a work directory a new
fit reads every reading and the table from it without tracing a ray; readings of two candidates
share their rays (common random numbers: the same seed and ray indices, so a candidate read
twice gives the same counts bit for bit); settings the fit owns, a store of another fit and a
table of too little certainty are refused naming them.

References
----------
Glasserman (2004), Sect. 4.2 (common random numbers); Baranoski et al. (2001), eq. (23).
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.applications.fitting.forward import FIT_OWNS, STORE, Forward
from virtspec_mi.applications.fitting.problem import fit_problem
from virtspec_mi.plugins.bsdfs.prospect_model import prospect_d

WAVELENGTHS = np.array([550.0, 800.0])
SETTINGS = {"theta_i": 0.0, "beam": "collimated"}


@pytest.fixture(scope="module")
def problem(mi):
    measured = (WAVELENGTHS, np.array([0.1, 0.45]), np.full(2, 0.03))
    return fit_problem(measured, "prospect_d", {"Cab": (10.0, 80.0)})


def test_settings_the_fit_owns_are_refused(problem):
    assert set(FIT_OWNS) == {"wavelengths", "mu", "delta", "seed", "joint", "rays"}
    with pytest.raises(ValueError, match=r"a fit sets mu, seed of its forward readings itself"):
        Forward(problem, delta=0.1, seed=1, settings={"seed": 2, "mu": 0.1}, directory=None)
    with pytest.raises(TypeError):
        Forward(problem, delta=0.1, seed=1, settings={"colour": 1}, directory=None)


def test_a_reading_is_certified_around_the_model(problem):
    forward = Forward(problem, delta=0.2, seed=3, settings=SETTINGS, directory=None)
    assert forward.reading_delta == pytest.approx(0.2 / 2) and not forward.joint
    reading = forward.reading([40.0], 0.03, "search")
    model, _ = prospect_d(WAVELENGTHS, Cab=40.0)
    assert np.all(np.abs(reading.predicted["reflectance"] - model) <= reading.tolerance["reflectance"])
    assert reading.rays > 0 and reading.stage == "search" and forward.traced_rays == reading.rays
    assert forward.reading([40.0], 0.03, "search") is reading and forward.traced_rays == reading.rays  # remembered


def test_a_work_directory_keeps_every_reading_and_the_table(problem, tmp_path):
    first = Forward(problem, delta=0.2, seed=3, settings=SETTINGS, directory=tmp_path)
    one = first.reading([25.0], 0.05, "search")
    table = first.table([np.array([20.0, 60.0])], 0.05, tmp_path / "table.zarr")
    assert (tmp_path / STORE).is_dir() and len(table) == 2 and first.traced_rays > 0
    again = Forward(problem, delta=0.2, seed=3, settings=SETTINGS, directory=tmp_path)
    same = again.reading([25.0], 0.05, "search")
    table_again = again.table([np.array([20.0, 60.0])], 0.05, tmp_path / "table.zarr")
    assert again.traced_rays == 0  # everything read back
    np.testing.assert_array_equal(same.predicted["reflectance"], one.predicted["reflectance"])
    for a, b in zip(table, table_again):
        np.testing.assert_array_equal(a.values, b.values)
        np.testing.assert_array_equal(a.predicted["reflectance"], b.predicted["reflectance"])


def test_common_random_numbers_give_the_same_counts_again(problem):
    a = Forward(problem, delta=0.2, seed=9, settings=SETTINGS, directory=None).reading([30.0], 0.05, "search")
    b = Forward(problem, delta=0.2, seed=9, settings=SETTINGS, directory=None).reading([30.0], 0.05, "search")
    np.testing.assert_array_equal(a.predicted["reflectance"], b.predicted["reflectance"])
    c = Forward(problem, delta=0.2, seed=10, settings=SETTINGS, directory=None).reading([30.0], 0.05, "search")
    assert not np.array_equal(a.predicted["reflectance"], c.predicted["reflectance"])


def test_a_table_of_less_certainty_is_refused(problem, tmp_path):
    loose = Forward(problem, delta=0.4, seed=3, settings=SETTINGS, directory=None)
    loose.table([np.array([20.0, 60.0])], 0.05, tmp_path / "loose.zarr")
    strict = Forward(problem, delta=0.02, seed=3, settings=SETTINGS, directory=None)
    with pytest.raises(ValueError, match=r"certifies each reading at delta 0.2; this fit needs 0.01 "
                                         r"\(delta / wavelengths\): measure it again"):
        strict.table([np.array([20.0, 60.0])], 0.05, tmp_path / "loose.zarr")


def test_a_store_of_another_fit_is_refused(problem, tmp_path):
    Forward(problem, delta=0.2, seed=3, settings=SETTINGS, directory=tmp_path).reading([25.0], 0.05, "search")
    other = fit_problem((WAVELENGTHS, np.array([0.1, 0.45]), np.full(2, 0.03)), "prospect_d", {"N": (1.2, 2.5)})
    with pytest.raises(ValueError, match=r"readings belongs to a different fit's forward readings "
                                         r"\(differs in: keys\)"):
        Forward(other, delta=0.2, seed=3, settings=SETTINGS, directory=tmp_path).reading([1.5], 0.05, "search")
