"""
Tests of :mod:`virtspec_mi.plugins.bsdfs.prospect_model`: the PROSPECT-D model in NumPy
(its plugin, ``prospect_d``, is tested in ``tests/plugins/bsdfs/test_prospect_d.py``).

The coefficients are the package's own (``virtspec_mi/data/prospect-d``: Féret et al. 2017, MIT). The
reference is the ``prosail`` package (PyPI 2.0.5, in the ``test`` extra): its ``run_prospect``
(J. Gomez-Dans' Python port of Feret et al.'s ``prospect_DB.m``, Feret et al. 2017) on its own
coefficient table ``prospect_d_spectra.txt`` (``dataSpec_PDB.m`` of 16 January 2017, six significant
digits), which the shipped table copies number for number. Both implementations read the same numbers,
so they must agree to float64 rounding. The tests that compare with prosail are skipped only where it
is not installed; the others need nothing beside the package.

References
----------
Jacquemoud & Baret (1990), eqs. 1–7; Féret et al. (2017); Stern (1964); Stokes (1862).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from virtspec_mi.plugins.bsdfs import prospect_model
from virtspec_mi.plugins.bsdfs.prospect_model import (
    ENVIRONMENT_VARIABLE,
    SHIPPED,
    ProspectDataError,
    prospect_coefficients,
    prospect_d,
    tav,
)
from virtspec_mi.references.quadrature import fresnel_reflectance


@pytest.fixture
def prosail():
    return pytest.importorskip("prosail")  # in the test extra; skipped only where it is not installed


LEAVES = [  # (N, Cab, Car, Cbrown, Cw, Cm, Anth): a green leaf, a thick dark one, a thin pale one, a red one
    (1.5, 40.0, 8.0, 0.0, 0.01, 0.009, 0.0),
    (2.5, 80.0, 15.0, 0.5, 0.03, 0.02, 5.0),
    (1.0, 5.0, 1.0, 0.0, 0.002, 0.001, 1.0),
    (1.8, 30.0, 10.0, 0.2, 0.015, 0.006, 20.0),
]


@pytest.mark.parametrize("leaf", LEAVES)
def test_reproduces_prosail_run_prospect(leaf, prosail):
    n, cab, car, cbrown, cw, cm, anth = leaf
    wavelengths, r, t = prosail.run_prospect(n, cab, car, cbrown, cw, cm, ant=anth)
    reflectance, transmittance = prospect_d(N=n, Cab=cab, Car=car, Cbrown=cbrown, Cw=cw, Cm=cm, Anth=anth)
    assert reflectance.shape == (2101,)
    np.testing.assert_allclose(prospect_coefficients().wavelengths, wavelengths)
    np.testing.assert_allclose(reflectance, r, rtol=0, atol=1e-12)
    np.testing.assert_allclose(transmittance, t, rtol=0, atol=1e-12)


def test_vectorised_over_parameter_sets_and_wavelengths():
    cab = np.array([[10.0, 40.0], [60.0, 90.0]])
    reflectance, transmittance = prospect_d([450.0, 550.5, 800.0], Cab=cab, N=1.7)
    assert reflectance.shape == transmittance.shape == (2, 2, 3)
    one, _ = prospect_d([450.0, 550.5, 800.0], Cab=60.0, N=1.7)
    np.testing.assert_allclose(reflectance[1, 0], one, rtol=0, atol=1e-15)
    full, _ = prospect_d(Cab=60.0, N=1.7)  # 550.5 nm: halfway between the 1 nm grid's points
    assert one[1] == pytest.approx((full[150] + full[151]) / 2, abs=1e-3)
    assert np.all((reflectance > 0) & (transmittance >= 0) & (reflectance + transmittance < 1))


@pytest.mark.parametrize("alpha", [40.0, 90.0])
@pytest.mark.parametrize("n", [1.3, 1.5])
def test_tav_is_the_fresnel_transmissivity_averaged_over_the_cone(alpha, n):
    # Stern (1964): tav = (1 / sin^2 a) * integral_0^a (1 - F(theta)) sin(2 theta) d theta, F unpolarised Fresnel
    theta = np.linspace(0.0, alpha, 20001)
    integrand = (1.0 - np.array([fresnel_reflectance(t, n) for t in theta])) * np.sin(2 * np.radians(theta))
    expected = np.trapezoid(integrand, np.radians(theta)) / np.sin(np.radians(alpha)) ** 2
    assert tav(alpha, n) == pytest.approx(expected, abs=1e-6)
    with pytest.raises(ValueError, match="alpha"):
        tav(0.0, n)


def test_bad_parameters_are_refused_by_name():
    with pytest.raises(ValueError, match=r"'Cab'.*0 <= Cab <= 150"):
        prospect_d(Cab=-1.0)
    with pytest.raises(ValueError, match=r"no parameter 'Cx'"):
        prospect_d(Cx=1.0)
    with pytest.raises(ValueError, match="400-2500 nm"):
        prospect_d([350.0], Cab=10.0)


def test_the_shipped_table_loads_without_prosail_or_the_variable(monkeypatch):
    monkeypatch.delenv(ENVIRONMENT_VARIABLE, raising=False)
    monkeypatch.setitem(sys.modules, "prosail", None)  # `import prosail` fails: nothing may need it
    prospect_model._cached.cache_clear()
    data = prospect_coefficients()
    assert "shipped with virtspec-mi" in data.source
    assert SHIPPED.parent == Path(prospect_model.__file__).resolve().parents[2] / "data" / "prospect-d"
    assert {p.name for p in SHIPPED.parent.iterdir()} >= {"LICENSE", "README.md", SHIPPED.name}
    assert data.wavelengths[0] == 400.0 and data.wavelengths[-1] == 2500.0 and len(data.wavelengths) == 2101
    np.testing.assert_array_equal(np.diff(data.wavelengths), 1.0)
    # spot values of dataSpec_PDB.m (first and last rows of the table)
    assert (data.n[0], data.absorption["Cab"][0], data.absorption["Cm"][0]) == (1.5115, 6.48815e-02, 1.09700e+02)
    assert (data.n[-1], data.absorption["Cw"][-1], data.absorption["Cm"][-1]) == (1.2736, 9.53000e+01, 3.87100e+01)
    reflectance, transmittance = prospect_d([550.0, 800.0], Cab=40.0)
    assert 0.05 < reflectance[0] < 0.2 < reflectance[1] and 0.3 < transmittance[1] < 0.6


def test_the_shipped_table_holds_prosails_numbers(prosail):
    theirs = Path(prosail.__file__).parent / "prospect_d_spectra.txt"

    def numbers(path: Path) -> list[list[str]]:
        lines = path.read_text(encoding="utf-8").splitlines()
        return [line.split() for line in lines if line.strip() and not line.lstrip().startswith("#")]

    assert numbers(SHIPPED) == numbers(theirs)  # every number's text, row for row
    np.testing.assert_array_equal(np.loadtxt(SHIPPED), np.loadtxt(theirs))


def test_coefficients_from_a_path_the_variable_and_a_clear_error(tmp_path, monkeypatch):
    table = tmp_path / "coefficients.txt"
    data = prospect_coefficients()
    rows = np.column_stack([data.wavelengths, data.n, *data.absorption.values()])[::100]
    np.savetxt(table, rows)
    mine = prospect_coefficients(table)
    assert len(mine.wavelengths) == len(rows) and mine.source == str(table)
    monkeypatch.setenv(ENVIRONMENT_VARIABLE, str(table))  # the variable overrides the shipped table
    assert len(prospect_coefficients().wavelengths) == len(rows)
    (tmp_path / "bad.txt").write_text("400 1.5 0.1\n")
    with pytest.raises(ProspectDataError, match="eight columns|8 columns"):
        prospect_coefficients(tmp_path / "bad.txt")
    monkeypatch.delenv(ENVIRONMENT_VARIABLE)
    monkeypatch.setattr(prospect_model, "SHIPPED", tmp_path / "absent.txt")  # an incomplete installation
    with pytest.raises(ProspectDataError, match=r"shipped with virtspec-mi are missing.*VIRTSPEC_PROSPECT_DATA"):
        prospect_coefficients()


@pytest.mark.parametrize("n", [1.0, 1.5, 2.7])
def test_nothing_absorbing_is_the_lossless_limit_exactly(n):
    """
    All pigments, Cw and Cm zero (allowed): the pile absorbs nothing, so R + T = 1, and T is the lossless limit
    T = T_top / (1 + (N - 1)(1 - t)) (t: one plate lit isotropically), derived by hand from the model's own
    combination. Left to rounding, Stokes' formula was taken there and lost ~5e-9 (R + T - 1 up to 6.6e-10).
    """

    data = prospect_coefficients()
    reflectance, transmittance = prospect_d(N=n, Cab=0.0, Car=0.0, Anth=0.0, Cbrown=0.0, Cw=0.0, Cm=0.0)
    t21 = tav(90.0, data.n) / data.n ** 2
    plate = tav(90.0, data.n) * t21 / (1 - (1 - t21) ** 2)
    top = tav(40.0, data.n) * t21 / (1 - (1 - t21) ** 2)
    np.testing.assert_allclose(transmittance, top / (1 + (n - 1) * (1 - plate)), rtol=0, atol=1e-15)
    np.testing.assert_allclose(reflectance + transmittance, 1.0, rtol=0, atol=1e-15)


def test_parameters_are_checked_with_their_defaults_filled_in():
    from virtspec_mi.plugins.bsdfs.prospect_model import PROSPECT_DEFAULTS, check_prospect_parameters

    checked = check_prospect_parameters({"Cab": [10.0, 20.0]})
    assert set(checked) == set(PROSPECT_DEFAULTS)
    np.testing.assert_array_equal(checked["Cab"], [10.0, 20.0])
    assert checked["N"] == PROSPECT_DEFAULTS["N"] == 1.5 and checked["N"].dtype == np.float64
    with pytest.raises(ValueError, match=r"PROSPECT-D: 'Cw' \(equivalent water thickness\) must satisfy "
                                         r"0 <= Cw <= 0.1 cm \(got nan\)"):
        check_prospect_parameters({"Cw": [0.01, float("nan")]})


def test_surfaces_conserve_energy_and_interpolation_refuses_outside():
    data = prospect_coefficients()
    r_alpha, t_alpha, r12, t12, r21, t21 = data.surfaces(40.0)
    np.testing.assert_allclose(r_alpha + t_alpha, 1.0)
    np.testing.assert_allclose(t21, t12 / data.n ** 2)  # Stern: the inside-out transmissivity
    assert data.surfaces(40.0)[0] is r_alpha  # computed once per alpha
    part = data.at([400.0, 400.5, 2500.0])
    assert part.n[1] == pytest.approx((data.n[0] + data.n[1]) / 2) and part.source == data.source
    with pytest.raises(ValueError, match=r"PROSPECT-D wavelengths must lie in 400-2500 nm, the coefficients' range "
                                         r"\(got 399-500 nm\)"):
        data.at([399.0, 500.0])
