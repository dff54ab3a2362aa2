"""
Tests of virtspec_mi.instruments.sphere.expected: the expected-value detector — what it refuses, exact and
reproducible score sums, the theory's closed form inside its certificate (coverage at δ = 0.2 over many seeds),
agreement with the counting route within both certificates, the counted route's counts unchanged, files and the
command line.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

import virtspec_mi as vm
from virtspec_mi.budgets.scores import score_interval
from virtspec_mi.instruments.sphere.expected import (ROUNDING_BIAS, SCORE_SCALE, SCORE_SUMS, SMALLEST_WEIGHT,
                                                     expected_layout)
from virtspec_mi.instruments.sphere.geometry import Port, Sphere
from virtspec_mi.instruments.sphere.result import SphereResult
from virtspec_mi.instruments.sphere.walk import SPECIMEN, Holder, holder_frame

from tests.instruments.sphere.test_walk import theory, three_port_sphere

SCENE = "scenes/sphere_150mm_8d.xml"


def _plain():
    return vm.load_scene(SCENE).integrator().sphere_options.sphere


def _layout(sphere, actions=None):
    holder = Holder(0, SPECIMEN, 12.7, holder_frame(sphere.ports[0].axis, False))
    return expected_layout(sphere, [holder], actions or [6 + j for j in range(len(sphere.ports) - 1)] + [0], 100,
                           [551.0])


def _ports(sphere, role, **change):
    return tuple(replace(p, **change) if p.role == role else p for p in sphere.ports)


@pytest.mark.parametrize("change, named", [
    ({"ports": ("detector", {"depth": 3.0})}, "a port wall"),
    ({"ports": ("detector", {"field_of_view": 40.0})}, "a detector field of view"),
    ({"ports": ("detector", {"radius": None, "shape": "ellipse", "width": 14.0, "height": 10.0})},
     "a non-circular port"),
    ({"ports": ("sample", {"aperture": 9.0})}, "a holder mask"),
    ({"wall_specular": 0.1}, "a mirror share of the wall"),
    ({"beam_profile": "shape=rectangle width=20 height=8 divergence=1"}, "a traced beam"),
    ({"wall_bsdf": {"type": "diffuse", "reflectance": 0.9}}, "a wall BSDF"),
])
def test_a_sphere_whose_detection_chance_is_not_exact_is_refused_naming_the_feature(change, named):
    plain = Sphere(150, 0.98, (Port("sample", "sample", 180, 0, 12.7), Port("entrance", "entrance", 0, 0, 12.7),
                               Port("detector", "detector", 90, 90, 6.35)))
    if "ports" in change:
        role, fields = change["ports"]
        sphere = replace(plain, ports=_ports(plain, role, **fields))
    else:
        sphere = replace(plain, **change)
    with pytest.raises(ValueError, match=f"detector='expected'.*{named}.*detector='counted'"):
        _layout(sphere, [6, 7, 0])
    layout = _layout(plain, [6, 7, 0])
    assert type(layout).__name__ == "ExpectedSphereLayout"
    import pickle

    back = pickle.loads(pickle.dumps(layout))  # a Dask worker receives it
    assert back.detector == layout.detector and back.detector_fraction == layout.detector_fraction
    assert layout.detector_fraction == plain.cap_fraction("detector")


def test_two_detectors_an_adaptive_budget_and_a_bad_choice_are_refused():
    two = Sphere(150, 0.98, (Port("sample", "sample", 180, 0, 12.7), Port("d1", "detector", 90, 90, 6.35),
                             Port("d2", "detector", 90, -90, 6.35)))
    with pytest.raises(ValueError, match="exactly one detector port"):
        _layout(two, [6, 0, 0])
    with pytest.raises(ValueError, match="detector='expected' takes a number of rays fixed before the run"):
        vm.sphere_measure(SCENE, detector="expected", bound="two-stage", mu=0.01)
    with pytest.raises(ValueError, match="detector must be one of counted, expected"):
        vm.sphere_measure(SCENE, detector="guessed", rays=100)


def test_score_sums_are_exact_reproducible_and_independent_of_chunking():
    first = vm.sphere_measure(SCENE, rays=6000, detector="expected", seed=4)
    again = vm.sphere_measure(SCENE, rays=6000, detector="expected", seed=4, chunk_size=1024)
    other = vm.sphere_measure(SCENE, rays=6000, detector="expected", seed=5)
    for configuration in ("sample", "standard"):
        a, b = first.counts[configuration], again.counts[configuration]
        assert all(np.array_equal(a[name], b[name]) for name in a)
        total, squares, rays = (int(a[name][0]) for name in (*SCORE_SUMS, "rays"))
        assert 0 < total <= SCORE_SCALE * rays and total * total <= rays * squares <= rays * SCORE_SCALE * total
    assert first.counts["sample"][SCORE_SUMS[0]] != other.counts["sample"][SCORE_SUMS[0]]


def test_the_standard_read_as_a_sample_reads_its_own_value_exactly():
    scene = vm.mitsuba().load_file(SCENE, reflectance="0.99")
    result = vm.sphere_measure(scene, rays=3000, detector="expected")
    assert result.counts["sample"][SCORE_SUMS[0]][0] == result.counts["standard"][SCORE_SUMS[0]][0] > 0
    assert result.reading[0] == 0.99


def _ideal_reading(seed, rays, delta, f=0.01, rho_w=0.98, detector="expected"):
    """The ideal three-port sphere (a 0.5 grey filling the sample port, conical beam): the flat theory is exact."""

    sphere = three_port_sphere(f, rho_w)
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": 0.5}, specimen_radius=sphere.ports[0].radius)
    return vm.sphere_measure(scene, sphere=sphere, theta_i=0, beam="conical", rays=rays, seed=seed, delta=delta,
                             detector=detector, standard=0.99), sphere


def _coverage(seeds, rays):
    delta = 0.2
    misses = {"sample": 0, "standard": 0, "reading": 0}
    pooled = {c: np.zeros(3, dtype=np.int64) for c in ("sample", "standard")}
    for seed in seeds:
        result, sphere = _ideal_reading(seed, rays, delta)
        truth = {"sample": theory(sphere, 0.5, 0.98), "standard": theory(sphere, 0.99, 0.98)}
        truth["reading"] = 0.99 * truth["sample"] / truth["standard"]
        bounds = {c: result.fraction_interval(c)[0] for c in ("sample", "standard")}
        bounds["reading"] = result.reading_interval[0]
        for name, (low, high) in bounds.items():
            misses[name] += not low <= truth[name] <= high
        for c in pooled:
            pooled[c] += [int(result.counts[c][name][0]) for name in (*SCORE_SUMS, "rays")]
    for c in pooled:  # all seeds' rays at once (independent: keyed on the seed): a far narrower interval at δ = 1e-3
        low, high = score_interval(*pooled[c], 1e-3, SCORE_SCALE, ROUNDING_BIAS, SMALLEST_WEIGHT)
        misses[f"pooled_{c}"] = int(not low <= truth[c] <= high)
    return misses


def test_coverage_at_delta_02_over_many_seeds():
    """
    The ideal sphere's flat theory (exact for a conical beam and a specimen filling its port) lies in each
    fraction's interval (at δ/2) and in the reading's (at δ = 0.2) for all but a few of 30 seeds: a miss count
    above the binomial's 1e-6 quantile at the stated δ fails. The 30 seeds' sums pooled (600,000 rays per
    configuration) hold it at δ = 1e-3 too: an interval about 5x narrower, so a bias of a fraction of a per cent
    would show.
    """

    seeds = range(30)
    misses = _coverage(seeds, 20_000)
    assert misses["sample"] <= stats.binom.ppf(1 - 1e-6, len(seeds), 0.1)
    assert misses["standard"] <= stats.binom.ppf(1 - 1e-6, len(seeds), 0.1)
    assert misses["reading"] <= stats.binom.ppf(1 - 1e-6, len(seeds), 0.2)
    assert misses["pooled_sample"] == misses["pooled_standard"] == 0  # no bias the pooled 600,000 rays can see


@pytest.mark.slow
def test_coverage_at_delta_02_over_two_hundred_seeds():
    seeds = range(100, 300)
    misses = _coverage(seeds, 50_000)
    assert misses["reading"] <= stats.binom.ppf(1 - 1e-6, len(seeds), 0.2)
    assert misses["sample"] + misses["standard"] <= stats.binom.ppf(1 - 1e-6, 2 * len(seeds), 0.1)


def test_expected_and_counted_readings_agree_within_both_certificates_over_many_seeds():
    """
    The shipped 150 mm 8°/d sphere (baffle, SCI, grey 0.5): at the same N the two routes' intervals (each at
    δ = 0.01) overlap for every one of 10 seeds, the expected-value interval is the narrower, and both routes
    trace the same first interactions (the hemispherical counts are the same rays').
    """

    for seed in range(10):
        counted = vm.sphere_measure(SCENE, rays=20_000, seed=seed)
        expected = vm.sphere_measure(SCENE, rays=20_000, seed=seed, detector="expected")
        (c_low, c_high), (e_low, e_high) = counted.reading_interval[0], expected.reading_interval[0]
        assert max(c_low, e_low) <= min(c_high, e_high)
        assert abs(float(counted.reading[0] - expected.reading[0])) <= (c_high - c_low) + (e_high - e_low)
        assert (e_high - e_low) < 0.6 * (c_high - c_low)
        hemispherical = [r.counts["sample"]["hemispherical_reflected"] for r in (counted, expected)]
        assert hemispherical[0] == hemispherical[1]


def test_the_counted_route_is_the_default_and_its_options_are_as_before():
    default = vm.sphere_measure(SCENE, rays=2000, seed=2)
    counted = vm.sphere_measure(SCENE, rays=2000, seed=2, detector="counted")
    assert "detector" not in default.options and "detector" not in counted.options
    assert all(np.array_equal(default.counts[c][k], counted.counts[c][k]) for c in ("sample", "standard")
               for k in default.counts[c])
    assert not any(name in default.counts["sample"] for name in SCORE_SUMS)


def test_the_fraction_interval_is_the_score_interval_with_the_walks_bounds(tmp_path):
    result = vm.sphere_measure(SCENE, rays=5000, seed=1, detector="expected")
    counts = result.counts["standard"]
    low, high = score_interval(counts[SCORE_SUMS[0]], counts[SCORE_SUMS[1]], counts["rays"], result.delta / 2,
                               SCORE_SCALE, ROUNDING_BIAS, SMALLEST_WEIGHT)
    assert result.fraction_interval("standard")[0].tolist() == [low[0], high[0]]
    assert result.standard_fraction[0] == counts[SCORE_SUMS[0]][0] / (SCORE_SCALE * 5000)
    assert "expected value of each wall bounce" in result.summary()
    path = tmp_path / "r.json"
    result.write(path)
    back = vm.read_result(path)
    assert isinstance(back, SphereResult) and back.options["detector"] == "expected"
    assert np.array_equal(back.reading_interval, result.reading_interval)
    data = result.as_dict()
    del data["counts"]["sample"][SCORE_SUMS[1]]
    with pytest.raises(ValueError, match="needs the score sums"):
        SphereResult.from_dict(data)


def test_the_error_budget_of_an_expected_value_reading_names_its_certificate():
    result = vm.sphere_measure(SCENE, rays=3000, seed=1, detector="expected")
    budget = result.budget(lambda sphere, **kw: vm.sphere_measure(SCENE, sphere=sphere, rays=3000, seed=1,
                                                                  detector="expected", **kw))
    assert "empirical Bernstein (readings)" in budget.summary()
    assert budget.error == pytest.approx(sum(budget.parts.values()))


def test_cli_sphere_detector_expected(capsys):
    from virtspec_mi.cli import main

    assert main(["sphere", SCENE, "--rays", "2000", "--detector", "expected", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["options"]["detector"] == "expected"
    assert data["counts"]["sample"][SCORE_SUMS[0]][0] > 0
    with pytest.raises(SystemExit):
        main(["sphere", SCENE, "--rays", "100", "--detector", "sometimes"])
    assert "invalid choice: 'sometimes'" in capsys.readouterr().err
