"""Tests of the fitting application (virtspec_mi/applications/fitting/): vm.fit and `virtspec fit`.

The specimen is PROSPECT-D (``prospect_d``, cheap rays), whose model gives the exact spectrum a
synthetic measurement is made from: the measured values are the model's plus noise drawn uniformly
within +-u, so the measurement's uncertainty u is a sure bound and the confidence set's level is
1 - delta (the forward readings' risk) exactly as the fit states it.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.stats import binom

import virtspec_mi as vm
from virtspec_mi.applications.fitting import read_fit
from virtspec_mi.applications.fitting.forward import Reading
from virtspec_mi.applications.fitting.inversion import intervals, verdicts
from virtspec_mi.plugins.bsdfs.prospect_model import prospect_d
from measured_csv import write_measured

WAVELENGTHS = np.array([450.0, 530.0, 560.0, 600.0, 650.0, 680.0, 700.0, 720.0, 800.0, 1200.0, 1450.0, 1650.0,
                        1950.0, 2200.0])
FAST = dict(evaluations=(8, 4, 2), profile_points=3, table_points=5, theta_i=8.0, beam="collimated")


def synthetic(truth: dict, u: float, seed: int, bias: float = 0.0, wavelengths=WAVELENGTHS) -> dict:
    """Reflectance and transmittance of PROSPECT-D at ``truth`` + uniform noise within +-u (+ a planted bias)."""

    rng = np.random.default_rng(seed)
    reflectance, transmittance = prospect_d(wavelengths, **truth)
    n = len(wavelengths)
    return {"reflectance": (wavelengths, reflectance + rng.uniform(-u, u, n) + bias, np.full(n, u)),
            "transmittance": (wavelengths, transmittance + rng.uniform(-u, u, n), np.full(n, u))}


def inside(result, truth: dict) -> bool:
    return all(result.intervals[i, 0] <= truth[name] <= result.intervals[i, 1] for i, name in enumerate(result.names))


def test_round_trip_recovers_the_leaf_inside_its_confidence_set():
    truth = {"Cab": 52.0, "Cm": 0.008}
    result = vm.fit(synthetic(truth, 0.02, seed=1), "prospect_d", {"Cab": (10, 90), "Cm": (0.002, 0.02)},
                    delta=0.1, seed=4, **FAST)
    assert result.consistent and result.statistic <= 1.0
    assert inside(result, truth), (result.intervals, truth)
    assert result.estimate[0] == pytest.approx(52.0, abs=10.0)
    # rays raised as the fit converged: the optimum read at mu* = mu_fraction x u, certified
    assert result.forward_mu == pytest.approx(0.01)
    assert result.forward_tolerance <= 0.01 + 1e-9
    assert set(result.candidate_mu) == {0.02, 0.01}  # table and stage 1 at 0.02 (4 mu* capped), then 2 mu*, mu*
    assert not any(result.unconstrained)
    assert "confidence set" in result.summary()


def test_a_planted_bias_makes_an_inconsistent_fit():
    truth = {"Cab": 40.0, "Cm": 0.01}
    # the last stage needs room for a move beyond its simplex (2 + 2 readings) to settle: (8, 4, 2) has none
    result = vm.fit(synthetic(truth, 0.01, seed=2, bias=0.05), "prospect_d", {"Cab": (10, 90), "Cm": (0.002, 0.02)},
                    delta=0.1, **dict(FAST, evaluations=(8, 4, 4)))
    assert not result.consistent and result.converged
    assert np.all(np.isnan(result.intervals))
    assert "INCONSISTENT" in result.summary()


def test_a_search_out_of_budget_says_it_did_not_converge_not_inconsistent(tmp_path):
    """Data the model made, a search with no budget: no consistent candidate found, and no verdict on the model."""

    result = vm.fit(synthetic({"Cab": 75.0, "Cm": 0.017}, 0.005, seed=3), "prospect_d",
                    {"Cab": (10, 90), "Cm": (0.002, 0.02)}, delta=0.1,
                    **dict(FAST, evaluations=(0, 0, 0), table_points=2, profile_points=0, confirm=False))
    assert not result.consistent and not result.converged
    summary = result.summary()
    assert "NOT CONVERGED" in summary and "INCONSISTENT" not in summary and "--evaluations" in summary
    assert read_fit(result.write(tmp_path / "fit.json")).converged is False


def test_data_that_do_not_see_a_parameter_leave_it_unconstrained():
    near_infrared = np.array([800.0, 1000.0, 1300.0, 1600.0, 2000.0, 2300.0])  # anthocyanins absorb below 700 nm
    truth = {"Anth": 10.0, "Cm": 0.01}
    result = vm.fit(synthetic(truth, 0.02, seed=3, wavelengths=near_infrared), "prospect_d",
                    {"Anth": (0, 40), "Cm": (0.002, 0.02)}, delta=0.1, **FAST)
    assert result.consistent and inside(result, truth)
    assert result.unconstrained == (True, False)
    assert "UNCONSTRAINED" in result.summary()


def test_intervals_carry_each_end_to_the_next_tested_value():
    values = np.array([[0.0], [1.0], [2.0], [3.0], [4.0]])
    consistent = np.array([False, True, True, False, False])
    np.testing.assert_array_equal(intervals(values, consistent, np.array([[0.0, 4.0]])), [[0.0, 3.0]])
    np.testing.assert_array_equal(intervals(values, ~consistent, np.array([[-1.0, 5.0]])), [[-1.0, 5.0]])
    assert np.all(np.isnan(intervals(values, consistent & False, np.array([[0.0, 4.0]]))))


def test_a_candidate_is_judged_by_its_finest_reading():
    def reading(value, mu):
        return Reading(values=np.array([value]), mu=mu, predicted={}, tolerance={}, rays=1, stage="")

    readings = [reading(1.0, 0.02), reading(2.0, 0.02), reading(1.0, 0.005), reading(3.0, 0.005)]
    # 1.0 consistent at 0.02 but not at 0.005: judged inconsistent in both rows; 2.0 only coarse: consistent
    np.testing.assert_array_equal(verdicts(readings, np.array([0.8, 0.9, 1.3, 0.5])), [False, True, False, True])


def test_bad_input_is_refused_by_name():
    measured = synthetic({"Cab": 40.0}, 0.02, seed=0)
    with pytest.raises(ValueError, match=r"no parameter 'Chl'.*Cab"):
        vm.fit(measured, "prospect_d", {"Chl": (10, 80)})
    with pytest.raises(ValueError, match=r"'Cab'.*0 <= Cab <= 150"):
        vm.fit(measured, "prospect_d", {"Cab": (10, 500)})
    with pytest.raises(ValueError, match="lowest < highest"):
        vm.fit(measured, "prospect_d", {"Cab": (80, 10)})
    with pytest.raises(ValueError, match="outside the data range of the specimen"):
        vm.fit((np.array([350.0, 500.0]), np.array([0.1, 0.1]), np.array([0.01, 0.01])), "prospect_d",
               {"Cab": (10, 80)})
    with pytest.raises(ValueError, match="has no uncertainty"):
        vm.fit((WAVELENGTHS, np.full(len(WAVELENGTHS), 0.1)), "prospect_d", {"Cab": (10, 80)})
    with pytest.raises(ValueError, match="sets mu of its forward readings itself"):
        vm.fit(measured, "prospect_d", {"Cab": (10, 80)}, mu=0.01)
    with pytest.raises(TypeError, match=r"fit\(\) got unexpected keyword argument\(s\) colour"):
        vm.fit(measured, "prospect_d", {"Cab": (10, 80)}, colour="green")
    with pytest.raises(ValueError, match="theta_i"):
        vm.fit(measured, "prospect_d", {"Cab": (10, 80)}, theta_i=95.0)
    with pytest.raises(ValueError, match="loss must be one of chi2, rmse, max"):
        vm.fit(measured, "prospect_d", {"Cab": (10, 80)}, loss="l1")
    with pytest.raises(ValueError, match="reach outside the measured"):
        vm.fit(measured, "prospect_d", {"Cab": (10, 80)}, wavelengths=[420.0, 2400.0])


def test_a_fit_interrupted_in_its_table_stage_resumes(tmp_path, monkeypatch):
    """Stopped before the table's first reading it said "nothing to resume", then refused its own table forever."""

    import virtspec_mi.base.interrupts as interrupts
    from virtspec_mi.kernel import tracer

    real, calls = tracer.tally_readings, []

    def stopped_once(*args, **kwargs):
        calls.append(1)
        if len(calls) == 1:
            raise interrupts.Interrupted()
        return real(*args, **kwargs)

    monkeypatch.setattr(tracer, "tally_readings", stopped_once)
    measured, options = synthetic({"Cab": 45.0}, 0.02, seed=6), dict(FAST, evaluations=(2, 1, 1), profile_points=0,
                                                                   confirm=False)
    with pytest.raises(KeyboardInterrupt):
        vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, delta=0.1, directory=tmp_path / "work", **options)
    assert (tmp_path / "work" / "table.zarr").exists()
    resumed = vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, delta=0.1, directory=tmp_path / "work", **options)
    assert resumed.candidate_stage.count("table") == FAST["table_points"]


def test_a_fit_resumes_from_its_directory_and_reuses_its_table(tmp_path):
    truth = {"Cab": 30.0}
    measured = synthetic(truth, 0.02, seed=5)
    options = dict(FAST, delta=0.1)
    first = vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, directory=tmp_path / "work", **options)
    assert (tmp_path / "work" / "table.zarr").exists() and first.traced_rays == first.rays
    files = sorted((tmp_path / "work" / "readings").glob("*.nc"))  # the engine's ResultStore
    assert files and (tmp_path / "work" / "readings" / "identity.json").exists()
    files[len(files) // 2].unlink()  # as if interrupted before that reading
    again = vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, directory=tmp_path / "work", **options)
    np.testing.assert_array_equal(again.estimate, first.estimate)  # common random numbers: the same path
    np.testing.assert_array_equal(again.candidate_statistic, first.candidate_statistic)
    assert 0 < again.traced_rays < first.traced_rays / 5
    # the table, reused by a fit with another loss
    other = vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, table=tmp_path / "work" / "table.zarr", loss="rmse",
                   **options)
    assert other.consistent and inside(other, truth)
    with pytest.raises(ValueError, match="no grid over specimen.Cm"):
        vm.fit(measured, "prospect_d", {"Cm": (0.002, 0.02)}, table=tmp_path / "work" / "table.zarr", **options)


def test_fit_files_and_figure(tmp_path):
    result = vm.fit(synthetic({"Cab": 45.0}, 0.02, seed=6), "prospect_d", {"Cab": (10, 90)}, delta=0.1, **FAST)
    for name in ("fit.json", "fit.nc"):
        back = read_fit(result.write(tmp_path / name))
        assert back.names == result.names and back.consistent == result.consistent
        np.testing.assert_allclose(back.intervals, result.intervals)
        np.testing.assert_allclose(back.fitted["transmittance"], result.fitted["transmittance"])
        assert back.candidate_stage == result.candidate_stage
    values, statistic = result.profile("Cab")
    assert len(values) >= 3 and statistic.min() <= 1.0
    result.plot(tmp_path / "fit.png")
    assert (tmp_path / "fit.png").stat().st_size > 10_000
    with pytest.raises(ValueError, match="a fit is written as .nc, .json"):
        result.write(tmp_path / "fit.csv")
    _edited_fit_files_are_refused(tmp_path / "fit.json", tmp_path / "fit.nc")


def _edited_fit_files_are_refused(path, netcdf):
    """A fit file edited against its own candidates (an interval tightened, ``consistent`` flipped) is refused."""

    import xarray as xr

    data = json.loads(path.read_text())
    low, high = data["intervals"][0]
    for edit, what in ((lambda d: d.update(intervals=[[low + 0.25 * (high - low), high]]), "intervals"),
                       (lambda d: d.update(consistent=not d["consistent"]), "consistent"),
                       (lambda d: d.update(candidate_consistent=[1] * len(d["candidate_consistent"])), "verdict")):
        edited = json.loads(path.read_text())
        edit(edited)
        path.with_name("edited.json").write_text(json.dumps(edited))
        with pytest.raises(ValueError, match=f"edited.json: .*{what}.* disagrees with the fit's own candidates"):
            read_fit(path.with_name("edited.json"))
    with xr.open_dataset(netcdf) as dataset:
        tightened = dataset.load()
    tightened["intervals"].values[0, 0] = low + 0.25 * (high - low)
    tightened.to_netcdf(netcdf.with_name("edited.nc"))
    with pytest.raises(ValueError, match="intervals"):  # the variable edited against the result, or its candidates
        read_fit(netcdf.with_name("edited.nc"))


def test_the_specimen_is_loaded_once_for_every_forward_reading(monkeypatch):
    """The scene is loaded where it enters the fit (vm.scene.loaded); each forward reading (a sweep) takes it."""

    from virtspec_mi.runtime import scene

    real, loads = scene.find_bench, []
    monkeypatch.setattr(scene, "find_bench", lambda given, defines=None: loads.append(given) or real(given, defines))
    result = vm.fit(synthetic({"Cab": 45.0}, 0.02, seed=7), "prospect_d", {"Cab": (10, 90)}, delta=0.1,
                    **dict(FAST, evaluations=(4, 2, 1), profile_points=0, confirm=False))
    sweeps = 1 + sum(stage != "table" for stage in result.candidate_stage)  # the table is one sweep
    assert sweeps > 3 and len(loads) == 1 and loads[0]["specimen"]["bsdf"] == {"type": "prospect_d"}


def test_cli_fit(tmp_path, capsys):
    from virtspec_mi.cli import main

    path = write_measured(tmp_path / "leaf.csv", WAVELENGTHS, *prospect_d(WAVELENGTHS, Cab=35.0))
    status = main(["fit", str(path), "--specimen", "prospect_d", "--free", "Cab=10:90", "--quantity", "both",
                   "--delta", "0.1", "--profile-points", "3", "--theta-i", "8", "--beam", "collimated",
                   "--out", str(tmp_path / "fit.json"), "--json"])
    assert status == 0
    data = json.loads(capsys.readouterr().out)
    assert data["consistent"] and data["intervals"][0][0] <= 35.0 <= data["intervals"][0][1]
    assert read_fit(tmp_path / "fit.json").names == ("Cab",)
    assert main(["fit", str(path), "--specimen", "prospect_d", "--free", "Chl=10:90"]) == 1
    assert "no parameter 'Chl'" in capsys.readouterr().err


@pytest.mark.slow
def test_confidence_sets_cover_the_truth_and_biases_are_detected():
    """
    Coverage: over T seeded round trips with random true leaves, the number of confidence sets
    missing the truth is Binomial(T, p) with p <= delta; the test fails when it exceeds the
    binomial's 0.999 quantile at p = delta. Power: a planted bias of 2.5 u on the reflectance
    must be flagged inconsistent in most trials.
    """

    trials, delta = 12, 0.1
    rng = np.random.default_rng(2026)
    misses, flagged = 0, 0
    for trial in range(trials):
        truth = {"Cab": float(rng.uniform(15, 85)), "Cm": float(rng.uniform(0.003, 0.018))}
        bounds = {"Cab": (10, 90), "Cm": (0.002, 0.02)}
        result = vm.fit(synthetic(truth, 0.02, seed=100 + trial), "prospect_d", bounds, delta=delta,
                        seed=trial, **FAST)
        misses += not (result.consistent and inside(result, truth))
        biased = vm.fit(synthetic(truth, 0.02, seed=200 + trial, bias=0.05), "prospect_d", bounds, delta=delta,
                        seed=trial, **FAST)
        flagged += not biased.consistent
    assert misses <= binom.ppf(0.999, trials, delta), misses
    assert flagged >= trials - 2, flagged


def test_the_table_on_two_dask_workers_gives_the_same_fit():
    measured = synthetic({"Cab": 40.0}, 0.02, seed=1)
    here = vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, delta=0.1, **FAST)
    there = vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, delta=0.1, workers=2, **FAST)
    np.testing.assert_array_equal(there.candidate_statistic, here.candidate_statistic)
    np.testing.assert_array_equal(there.intervals, here.intervals)


def test_one_value_column_is_not_both_quantities(tmp_path):
    """--quantity both with a file of one value column: refused, never its reflectance used as the transmittance."""

    from virtspec_mi.applications.fitting.problem import fit_problem

    (tmp_path / "one.csv").write_text("400,0.2,0.01\n500,0.3,0.01\n600,0.35,0.01\n")
    with pytest.raises(ValueError, match=r"one.csv holds one value column: it cannot be both the "
                                         "reflectance and the transmittance"):
        fit_problem(tmp_path / "one.csv", "prospect_d", {"Cab": (10, 90)}, quantities=("reflectance", "transmittance"))
    (tmp_path / "R.csv").write_text("wavelength,reflectance,uncertainty\n400,0.2,0.01\n500,0.3,0.01\n")
    with pytest.raises(ValueError, match="R.csv holds reflectance, no transmittance column"):
        fit_problem(tmp_path / "R.csv", "prospect_d", {"Cab": (10, 90)}, quantities=("reflectance", "transmittance"))
