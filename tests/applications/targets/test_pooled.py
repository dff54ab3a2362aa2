"""
A linear target by pooled two-stage readings (applications/targets/pooled.py): the draw of
the wavelengths, the rule's exact miss probability, fresh rays of its own for each
functional, what is refused, and an interrupted run resumed to the same result.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.stats import chi2

import virtspec_mi as vm
from dark_specimen import dark_scene, exact, recorded_traces
from killed_runs import Interrupting
from virtspec_mi.applications.targets.pooled import pilot_pays, poolable, pooled_rays
from virtspec_mi.budgets.bounds import exact_rays, hoeffding_rays
from virtspec_mi.budgets.twostage import two_stage_law

@pytest.fixture(scope="module")
def dark(mi):
    return dark_scene()


def test_the_draw_follows_the_weights_and_the_seed_alone():
    weights = np.array([0.5, 0.0, 0.25, 0.25])
    rays = pooled_rays(weights, 100_000, seed=7, stage=1, functional=0)
    assert rays.sum() == 100_000 and rays[1] == 0
    assert np.array_equal(rays, pooled_rays(weights, 100_000, seed=7, stage=1, functional=0))
    assert not np.array_equal(rays, pooled_rays(weights, 100_000, seed=7, stage=0, functional=0))
    assert not np.array_equal(rays, pooled_rays(weights, 100_000, seed=7, stage=1, functional=1))
    used = weights > 0
    expected = 100_000 * weights[used]
    statistic = float(np.sum((rays[used] - expected) ** 2 / expected))
    assert statistic < chi2.ppf(1 - 1e-6, used.sum() - 1)  # a multinomial of these shares (fixed seed)
    assert np.array_equal(pooled_rays(-weights, 1000, 3, 0, 0), pooled_rays(weights, 1000, 3, 0, 0))


def test_a_band_is_certified_with_fewer_rays_than_hoeffdings_route(dark):
    target = vm.band((450, 600), tolerance=0.002)
    pooled = vm.measure(dark, target=target, delta=0.05, seed=1, bound="two-stage")
    hoeffding = vm.measure(dark, target=target, delta=0.05, seed=1, bound="hoeffding")
    value = pooled["band_450-600"]
    assert pooled.met and pooled.bound == "two-stage" and len(pooled.batches) == 1
    assert value.lower <= exact(target.functionals()[0]) <= value.upper
    assert value.half_width <= 0.002 * (1 + 1e-12) and pooled.functional_tolerances == (0.002,)
    assert pooled.rays == sum(pooled.batches) == int(np.sum(pooled.readings.rays))
    assert pooled.pilot_rays == 5000  # ceil(10/mu), mu = 0.002 of weights summing to 1
    assert pooled.total_rays < hoeffding.total_rays / 4, (pooled.total_rays, hoeffding.total_rays)
    again = vm.measure(dark, target=target, delta=0.05, seed=1, bound="two-stage")
    assert again["band_450-600"] == value and np.array_equal(again.readings.rays, pooled.readings.rays)
    assert "pooled two-stage exact rule" in pooled.summary()
    assert "drawn with probability |w_k|/sum|w|" in pooled.summary()


def test_a_loose_tolerance_takes_the_exact_rule_without_a_pilot(dark):
    """A pilot of 10/mu rays would cost about as much as it saves: N is the exact rule's over every p."""

    assert pilot_pays(0.002, 0.01) and pilot_pays(0.04, 0.01) and not pilot_pays(0.05, 0.01)
    target = vm.band((450, 600), tolerance=0.2)
    loose = vm.measure(dark, target=target, delta=0.05, seed=1)
    assert loose.pilot_rays == 0 and loose.rays == exact_rays(0.2, 0.05) < hoeffding_rays(0.2, 0.05)
    assert loose.met and loose.values[0].lower <= exact(target.functionals()[0]) <= loose.values[0].upper


def test_the_rules_exact_miss_probability_is_at_most_delta():
    """The pooled count is one binomial proportion: the two-stage law is then exact for it."""

    for rho in (0.03, 0.2, 0.5, 0.9):
        law = two_stage_law(rho, 0.02, 0.025, other="absorbed")
        assert law.miss_probability <= 0.025, (rho, law.miss_probability)
        assert law.expected_rays < hoeffding_rays(0.02, 0.025)


def test_each_functional_draws_fresh_rays_of_its_own(dark, monkeypatch):
    calls = recorded_traces(monkeypatch)
    # the first band the brightest (most rays) and last on the grid, the second darker and first: their ranges
    # would meet if each functional's stride were its own rays; the third shares the first's wavelengths
    target = vm.band((740, 790), (300, 320), (760, 780), tolerance=0.01)
    result = vm.measure(dark, target=target, delta=0.05, seed=3, bound="two-stage")
    assert len(calls) == 6 and len({seed for seed, *_ in calls}) == 2  # a pilot and a second batch each
    assert result.pilot_rays == sum(int(c[2].sum()) for c in calls[::2]) == 3 * 1000
    assert result.rays == sum(int(c[2].sum()) for c in calls[1::2]) and len(set(result.batches)) == 3
    spans: dict[int, list[tuple[int, int]]] = {}
    for seed, wavelengths, rays, offsets in calls:
        for n, o in zip(rays, offsets):
            spans.setdefault(seed, []).append((int(o), int(o + n)))
    for seed, ranges in spans.items():  # a ray's random numbers are its global index's: no index twice at a seed
        ranges.sort()
        assert all(a[1] <= b[0] for a, b in zip(ranges, ranges[1:])), (seed, ranges)
    for f, v in zip(target.functionals(), result.values):
        assert v.lower <= exact(f) <= v.upper


def test_what_cannot_be_pooled_is_refused_naming_the_others(dark):
    assert poolable(vm.band("B04")) == "" and poolable(vm.fapar()) == ""
    assert "not linear" in poolable(vm.index("NDVI"))
    with pytest.raises(ValueError, match="needs a linear target whose weights have one sign: .* give "
                                         "bound='betting' or 'hoeffding'"):
        vm.measure(dark, target=vm.colour(tolerance_dE00=2.0), bound="two-stage")


def test_an_interrupted_run_resumes_to_the_same_result(dark, tmp_path, monkeypatch):
    import virtspec_mi.instruments.hemispherical.allocated as allocated

    keywords = dict(target=vm.band((500, 520), (600, 620), tolerance=0.004), delta=0.05, seed=3, bound="two-stage")
    whole = vm.measure(dark, **keywords)
    traces = Interrupting(monkeypatch, allocated, "trace_allocated", after=3)  # the second band's pilot done
    path = tmp_path / "pooled.json"
    with pytest.raises(KeyboardInterrupt):
        vm.measure(dark, checkpoint=path, **keywords)
    assert len(json.loads(path.read_text())["traces"]) == 3
    traces.calls, traces.after = 0, -1
    resumed = vm.measure(dark, checkpoint=path, **keywords)
    assert traces.calls == 1 and not path.exists()  # only the last second batch traced again
    assert resumed.values == whole.values and resumed.batches == whole.batches
    assert np.array_equal(resumed.readings.rays, whole.readings.rays)


def test_a_sweep_pools_each_angle_as_a_measurement_does(dark):
    target = vm.band((500, 520), tolerance=0.01)
    sweep = vm.sweep(dark, theta_i=[0, 40], target=target, delta=0.05, seed=2)
    for theta, result in zip(sweep.theta_i, sweep):
        alone = vm.measure(dark, target=target, delta=0.05, seed=2, theta_i=theta)
        assert result.bound == alone.bound == "two-stage" and result.values == alone.values
