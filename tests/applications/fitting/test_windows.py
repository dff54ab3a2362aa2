"""Tests of the optimal-windows loss of a fit (virtspec_mi/applications/fitting/windows.py, loss="windows").

The specimen is PROSPECT-D, whose model makes the synthetic measurement (as in test_fitting.py): the
measured values are the model's plus noise drawn uniformly within +-u.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.fitting.windows import OPTIMAL_WINDOWS, fit_windows
from virtspec_mi.plugins.bsdfs.prospect_model import prospect_d
from measured_csv import write_measured

WAVELENGTHS = np.array([450.0, 530.0, 560.0, 600.0, 650.0, 680.0, 700.0, 705.0, 710.0, 715.0, 720.0, 800.0,
                        1200.0, 1450.0, 1650.0, 1800.0, 1950.0, 2200.0])
FAST = dict(evaluations=(8, 4, 2), profile_points=3, table_points=5, theta_i=8.0, beam="collimated", delta=0.1)


def synthetic(truth: dict, u: float, seed: int, bias=None, wavelengths=WAVELENGTHS, both: bool = False) -> dict:
    """PROSPECT-D at ``truth`` + uniform noise within +-u (+ a planted bias on R, and on T when ``both``)."""

    rng = np.random.default_rng(seed)
    reflectance, transmittance = prospect_d(wavelengths, **truth)
    n = len(wavelengths)
    planted = np.zeros(n) if bias is None else bias
    return {"reflectance": (wavelengths, reflectance + rng.uniform(-u, u, n) + planted, np.full(n, u)),
            "transmittance": (wavelengths, transmittance + rng.uniform(-u, u, n) + (planted if both else 0.0),
                              np.full(n, u))}


def test_the_published_windows():
    assert OPTIMAL_WINDOWS == {"Cab": ((700.0, 720.0),), "Car": ((520.0, 560.0),), "Anth": ((400.0, 800.0),),
                               "Cw": ((1700.0, 2400.0),), "Cm": ((1700.0, 2400.0),)}
    chosen = fit_windows(None, ("N", "Cab", "specimen.Cm"), WAVELENGTHS)
    assert set(chosen.masks) == {1, 2}  # N has no window
    np.testing.assert_array_equal(WAVELENGTHS[chosen.masks[1]], [700.0, 705.0, 710.0, 715.0, 720.0])
    np.testing.assert_array_equal(WAVELENGTHS[chosen.masks[2]], [1800.0, 1950.0, 2200.0])
    # the anthocyanins' 400-800 nm, cut to the fitted range; a window given by the user, several intervals
    chosen = fit_windows({"Cab": "700:705,715:720"}, ("Cab", "Anth"), WAVELENGTHS)
    np.testing.assert_array_equal(WAVELENGTHS[chosen.masks[0]], [700.0, 705.0, 715.0, 720.0])
    assert WAVELENGTHS[chosen.masks[1]].max() == 800.0
    assert chosen.describe(("Cab", "Anth")) == "windows (Cab 700-705, 715-720 nm, Anth 450-800 nm)"


def test_a_window_loss_recovers_cab_where_the_full_range_is_biased():
    # a bias of +0.03 in reflectance and transmittance at 530-690 nm (a model error in the visible, where
    # carotenoids and anthocyanins also act): the full-range chi-square pulls Cab down (the model alone, without
    # noise: to 26.4), the 700-720 nm window does not see the bias (34.0)
    wavelengths = np.array([*np.arange(530.0, 691.0, 10.0), 700.0, 710.0, 720.0, 800.0])
    truth = {"Cab": 34.0}  # not on the table's grid (10, 30, 50 ...)
    bias = np.where(wavelengths <= 690.0, 0.03, 0.0)
    measured = synthetic(truth, 0.005, seed=11, bias=bias, wavelengths=wavelengths, both=True)
    windowed = vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, windows={"Cab": (700, 720)}, seed=2, **FAST)
    full = vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, loss="chi2", seed=2, **FAST)
    assert windowed.loss_name == "windows (Cab 700-720 nm)"
    assert abs(windowed.estimate[0] - 34.0) < 3.0, windowed.estimate
    assert full.estimate[0] < 34.0 - 4.0, full.estimate
    assert any(stage.startswith("window Cab") for stage in windowed.candidate_stage)
    assert windowed.forward_tolerance <= windowed.forward_mu + 1e-12  # the estimate read at mu*
    assert not windowed.consistent and not full.consistent  # the bias is 6 u: no candidate is consistent


def test_windows_recover_a_leaf_inside_its_confidence_set():
    truth = {"Cab": 52.0, "Cm": 0.008}
    result = vm.fit(synthetic(truth, 0.02, seed=1), "prospect_d", {"Cab": (10, 90), "Cm": (0.002, 0.02)},
                    loss="windows", seed=4, **FAST)
    assert result.loss_name == "windows (Cab 700-720 nm, Cm 1700-2200 nm)"
    assert result.consistent  # the estimate itself is judged on the whole spectrum, its windows chose it
    for i, name in enumerate(result.names):
        assert result.intervals[i, 0] <= truth[name] <= result.intervals[i, 1], (name, result.intervals)
    assert result.estimate[0] == pytest.approx(52.0, abs=10.0)


def test_bad_windows_are_refused_by_name():
    measured = synthetic({"Cab": 40.0}, 0.02, seed=0)
    free = {"Cab": (10, 80)}
    with pytest.raises(ValueError, match=r"windows: 'Car' is not a free parameter of this fit \(free: Cab\)"):
        vm.fit(measured, "prospect_d", free, windows={"Car": (520, 560)})
    with pytest.raises(ValueError, match=r"window of 'Cab', 300-720 nm, reaches outside the fitted wavelengths "
                                         r"\(450-2200 nm\)"):
        vm.fit(measured, "prospect_d", free, windows={"Cab": (300, 720)})
    with pytest.raises(ValueError, match=r"window of 'Cab' \(701-704 nm\) holds none of the fitted wavelengths"):
        vm.fit(measured, "prospect_d", free, windows={"Cab": (701, 704)})
    with pytest.raises(ValueError, match=r"window of 'Cab' must be finite with lowest < highest"):
        vm.fit(measured, "prospect_d", free, windows={"Cab": (720, 700)})
    with pytest.raises(ValueError, match=r"windows= chooses the windows of loss='windows' \(got loss='rmse'\)"):
        vm.fit(measured, "prospect_d", free, windows={"Cab": (700, 720)}, loss="rmse")
    with pytest.raises(ValueError, match=r"loss='windows' needs a window for at least one free parameter \(N\)"):
        vm.fit(measured, "prospect_d", {"N": (1, 3)}, loss="windows")
    with pytest.raises(ValueError, match=r"published window of 'Cw' \(1700-2400 nm\) lies outside the fitted"):
        vm.fit(measured, "prospect_d", {"Cw": (0.001, 0.05)}, loss="windows", wavelengths=[450.0, 700.0])


def test_cli_window(tmp_path, capsys):
    from virtspec_mi.cli import main

    path = write_measured(tmp_path / "leaf.csv", WAVELENGTHS, *prospect_d(WAVELENGTHS, Cab=35.0))
    status = main(["fit", str(path), "--specimen", "prospect_d", "--free", "Cab=10:90", "--quantity", "both",
                   "--window", "Cab=700:720", "--delta", "0.1", "--profile-points", "3", "--theta-i", "8",
                   "--beam", "collimated", "--json"])
    assert status == 0
    data = json.loads(capsys.readouterr().out)
    assert data["loss_name"] == "windows (Cab 700-720 nm)"
    assert data["consistent"] and data["intervals"][0][0] <= 35.0 <= data["intervals"][0][1]
    assert main(["fit", str(path), "--specimen", "prospect_d", "--free", "Cab=10:90", "--window", "Cab=300:720"]) == 1
    assert "reaches outside the fitted wavelengths" in capsys.readouterr().err
    # the flag's own check (FitFlags), before anything is read: one line naming it, status 1
    assert main(["fit", str(path), "--specimen", "prospect_d", "--free", "Cab=10:90", "--window", "Cab"]) == 1
    assert "--window: --window takes NAME=LOWEST:HIGHEST" in capsys.readouterr().err
