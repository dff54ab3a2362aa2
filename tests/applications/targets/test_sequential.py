"""
Targets measured sequentially (bound="betting", applications/targets/sequential.py): fresh
rays in every batch, determinism, no batch after the certificate holds, what the result
records, and fewer rays than Hoeffding's route where the variance is small.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
import virtspec_mi.applications.targets.sequential as sequential
from dark_specimen import DARK, dark_scene, recorded_traces


@pytest.fixture(scope="module")
def dark(mi):
    return dark_scene()


def _exact_band(low: float, high: float) -> float:
    grid = np.arange(low, high + 1)
    values = np.interp(grid, np.linspace(300, 1000, len(DARK)), DARK)
    weights = np.ones(len(grid))
    weights[[0, -1]] = 0.5
    return float(weights @ values / weights.sum())


def test_every_batch_traces_fresh_rays_and_a_seed_gives_one_result(dark, monkeypatch):
    calls = recorded_traces(monkeypatch)  # the seam's process traces through trace_allocated
    target = vm.band((500, 520), tolerance=0.004)
    first = vm.measure(dark, target=target, delta=0.05, seed=3, bound="betting")
    pilot, calls = calls[0], calls[1:]  # a linear target's pilot (sizing only) has a seed of its own
    assert len(first.batches) >= 2 and len(calls) == len(first.batches)
    assert pilot[0] != calls[0][0] and int(pilot[2].sum()) == first.pilot_rays
    ranges: dict[float, list[tuple[int, int]]] = {}
    for seed, wavelengths, rays, offsets in calls:
        assert seed == calls[0][0]
        for w, n, o in zip(wavelengths, rays, offsets):
            ranges.setdefault(w, []).append((int(o), int(o + n)))
    for w, spans in ranges.items():  # each wavelength continues one stream: no ray twice
        spans.sort()
        assert all(a[1] <= b[0] for a, b in zip(spans, spans[1:])), (w, spans)
    spans = sorted(span for spans in ranges.values() for span in spans)
    assert all(a[1] <= b[0] for a, b in zip(spans, spans[1:]))  # no ray twice, across wavelengths either
    again = vm.measure(dark, target=target, delta=0.05, seed=3, bound="betting")
    assert again.batches == first.batches and again["band_500-520"] == first["band_500-520"]
    other = vm.measure(dark, target=target, delta=0.05, seed=4, bound="betting")
    assert other["band_500-520"].value != first["band_500-520"].value


def test_sampling_stops_at_the_first_batch_that_meets_the_target(dark, monkeypatch):
    target = vm.band((500, 520), tolerance=0.004)
    result = vm.measure(dark, target=target, delta=0.05, seed=5, bound="betting")
    assert result.met and result.bound == "betting" and len(result.batches) >= 2
    assert result.rays == sum(result.batches) == int(np.sum(result.readings.rays))
    value = result["band_500-520"]
    assert value.half_width <= 0.004 and value.lower <= _exact_band(500, 520) <= value.upper
    monkeypatch.setattr(sequential, "MOST_BATCHES", len(result.batches) - 1)
    shorter = vm.measure(dark, target=target, delta=0.05, seed=5, bound="betting")
    assert shorter.batches == result.batches[:-1] and not shorter.met  # the last batch was needed
    assert "NOT MET" in shorter.summary()
    data = result.as_dict()
    assert data["bound"] == "betting" and data["batches"] == list(result.batches)
    assert "betting confidence sequence, stopped after batch" in result.summary()


def test_fewer_rays_than_hoeffding_where_the_reflectance_is_small(dark):
    target = vm.band((450, 600), tolerance=0.002)
    betting = vm.measure(dark, target=target, delta=0.05, seed=1, bound="betting")
    hoeffding = vm.measure(dark, target=target, delta=0.05, seed=1, bound="hoeffding")
    assert betting.met and hoeffding.met and hoeffding.bound == "hoeffding" and not hoeffding.batches
    assert betting.total_rays < hoeffding.total_rays / 2, (betting.total_rays, hoeffding.total_rays)  # pilot included
    exact = _exact_band(450, 600)
    assert betting["band_450-600"].lower <= exact <= betting["band_450-600"].upper


def test_a_colour_stops_on_its_own_certificate(dark):
    result = vm.measure(dark, target=vm.colour(tolerance_dE00=2.0), delta=0.2, seed=2)
    assert result.met and result.colour.dE00_radius <= 2.0 and "betting confidence sequence" in result.colour.method
    assert result.pilot_rays > 0 and result.rays == sum(result.batches)


def test_a_bound_a_target_does_not_take_is_refused(dark):
    with pytest.raises(ValueError, match="bound must be one of auto, betting, two-stage, hoeffding for a target"):
        vm.measure(dark, target=vm.band("B04"), bound="chebyshev")


def test_auto_pools_a_linear_target_and_bets_on_any_other(dark):
    """The choice is the target's kind alone: a band is pooled, an index and a colour take the sequence."""

    band = vm.band((500, 520), tolerance=0.004)
    auto = vm.measure(dark, target=band, delta=0.05, seed=3)
    pooled = vm.measure(dark, target=band, delta=0.05, seed=3, bound="two-stage")
    assert auto.bound == "two-stage" and auto.as_dict()["values"] == pooled.as_dict()["values"]
    assert auto.rays == pooled.rays and auto.pilot_rays == pooled.pilot_rays  # the same route, the same rays
    index = vm.measure(dark, target=vm.index("NDVI", tolerance=0.05), delta=0.2, seed=1)
    assert index.bound == "betting" and index.batches


@pytest.mark.parametrize("bound", ["betting", "two-stage", "hoeffding", "auto"])
def test_the_command_line_takes_a_targets_bound(dark, capsys, bound):
    import json

    from virtspec_mi.cli import main

    argv = ["measure", "diamond_collimated", "--target", "band:B04,tolerance=0.05", "--seed", "1", "--json"]
    assert main([*argv, "--bound", bound]) == 0
    data = json.loads(capsys.readouterr().out)
    api = vm.measure(vm.scenes.path("diamond_collimated"), target=vm.band("B04", tolerance=0.05), seed=1,
                     bound=bound)
    assert data["bound"] == api.bound and data["rays"] == api.rays and data["batches"] == list(api.batches)
    assert data["bound"] == ("two-stage" if bound == "auto" else bound)  # auto: a band is pooled
    assert data["values"]["band_B04"]["value"] == api["band_B04"].value


def test_a_targets_certificate_is_refused_for_a_spectrum(dark, capsys):
    from virtspec_mi.cli import main

    assert main(["measure", "diamond_collimated", "--bound", "betting"]) != 0
    assert "bound betting certifies a target (give target=..., --target on the command line)" in \
        capsys.readouterr().err
    with pytest.raises(ValueError, match="bound auto certifies a target"):
        vm.measure(dark, bound="auto")


def test_a_colour_is_certified_from_one_joint_region(dark):
    """The betting route's colour: its facets' region, every statement at once (joint.py)."""

    result = vm.measure(dark, target=vm.colour(tolerance_dE00=2.0), delta=0.2, seed=2, bound="betting")
    assert result.met and "joint XYZ region" in result.colour.method and result.statements == 3
    assert result.rays == sum(result.batches)
    colour = result.colour
    assert np.all(colour.XYZ_interval[:, 0] <= colour.XYZ) and np.all(colour.XYZ <= colour.XYZ_interval[:, 1])
    assert np.all(colour.Lab_interval[:, 0] <= colour.Lab) and np.all(colour.Lab <= colour.Lab_interval[:, 1])


def test_a_targets_sweep_on_two_dask_workers_is_the_in_process_one(mi, tmp_path):
    scene = {"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 300, "wavelength_max": 1000,
                                                "values": ", ".join(map(str, DARK))}}
    keywords = dict(theta_i=[0, 30, 60], target=vm.band((500, 520), step=10.0, tolerance=0.01), delta=0.05, seed=3,
                    bound="betting")
    here = vm.sweep(vm.instrument_scene(scene), **keywords)
    there = vm.sweep(vm.instrument_scene(scene), workers=2, **keywords)
    assert there.theta_i == here.theta_i == (0.0, 30.0, 60.0)
    for a, b in zip(here, there):
        assert a.bound == b.bound == "betting" and a.batches == b.batches and a["band_500-520"] == b["band_500-520"]
        assert np.array_equal(a.readings.rays, b.readings.rays)
        assert np.array_equal(a.readings.reflectance, b.readings.reflectance)
    with pytest.raises(ValueError, match="checkpoint and workers: a target's sweep keeps its checkpoint"):
        vm.sweep(vm.instrument_scene(scene), workers=2, checkpoint=tmp_path / "c.json", **keywords)
