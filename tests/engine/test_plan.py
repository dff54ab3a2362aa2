"""
Tests of virtspec_mi.engine.plan and the one keyed run (virtspec_mi.engine.readings.run) for
every instrument: plans pickle, groups share rays, tallies do not depend on batching or
chunking, checkpoints keep bins and sums and resume to the uninterrupted tallies, old
checkpoint files, and two-stage sizing from each instrument's certified columns.
"""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.budgets import rules
from virtspec_mi.engine.checkpoint import CheckpointError
from virtspec_mi.engine.plan import Columns, Plan
from virtspec_mi.engine.readings import run, take_keyed_readings
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments.goniophotometer.bins import make_bins
from virtspec_mi.instruments.sphere.walk import SphereFate
from virtspec_mi.runtime.scene import find_bench
from virtspec_mi.settings import Settings

ROUGH = {"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5}
SPHERE = "scenes/sphere_150mm_8d.xml"


@pytest.fixture(scope="module")
def rough(mi):
    return find_bench(vm.instrument_scene(ROUGH))


@pytest.fixture(scope="module")
def bins():
    return make_bins(4, 6)


def gonio_plan(settings, bins, theta_i=(10.0, 50.0), **kwargs):
    return Plan(settings, theta_i, hooks=(bins.layout(),), instrument="goniophotometer",
                options={"bins": bins.as_dict()}, **kwargs)


@pytest.fixture(scope="module")
def sphere(mi):
    """The shipped 8/d sphere: its bench, the two configurations' layouts and settings."""

    from virtspec_mi.instruments.sphere import configurations
    from virtspec_mi.instruments.sphere.result import CONFIGURATIONS

    scene = mi.load_file(SPHERE)
    integrator = scene.integrator()
    bench = find_bench(scene)
    settings = integrator.settings.updated(wavelengths=(450.0, 550.0, 650.0))
    options = integrator.sphere_options
    setups = configurations(options.sphere, options, bench.geometry.specimen_radius)
    layouts = tuple(options.sphere.layout(*setups[name], options.max_bounces, settings.wavelengths)
                    for name in CONFIGURATIONS)
    return bench, layouts, settings


def sphere_plan(sphere, **changes):
    bench, layouts, settings = sphere
    return Plan(settings.updated(**changes), (settings.theta_i,), groups=("sample", "standard"), hooks=layouts,
                columns=Columns(rules.DETECTOR_COLUMNS, bins=(layouts[0].codes_of(SphereFate.DETECTED),)),
                instrument="sphere")


def same(a: Tally, b: Tally) -> None:
    for name in ("rays", "reflected", "transmitted", "capped", "specular_reflected", "regular_transmitted"):
        np.testing.assert_array_equal(getattr(a.counts, name), getattr(b.counts, name), err_msg=name)
    np.testing.assert_array_equal(a.bins, b.bins)
    assert a.sums.keys() == b.sums.keys()
    for name in a.sums:
        np.testing.assert_array_equal(a.sums[name], b.sums[name], err_msg=name)


# --- the plan ------------------------------------------------------------------------------


def test_the_flat_index_puts_the_wavelength_fastest_and_groups_share_keys(bins):
    plan = Plan(Settings(rays=100, wavelengths=(500, 600)), (0.0, 30.0, 60.0), groups=("a", "b"),
                hooks=(bins.layout(), bins.layout()))
    assert plan.shape == (2, 1, 3, 2) and plan.size == 12 and plan.keys == 6
    group, point, theta, lam = plan.split(np.arange(12))
    assert list(group) == [0] * 6 + [1] * 6 and list(theta[:6]) == [0, 0, 1, 1, 2, 2] and list(lam[:4]) == [0, 1, 0, 1]
    assert plan.stride == 100 and plan.bins == bins.size and plan.sums == ()


def test_a_plan_pickles_and_traces_the_same_on_the_other_side(rough, bins, sphere):
    for bench, plan, batch in ((rough, gonio_plan(Settings(rays=3000, wavelengths=(500, 600)), bins), [3, 0, 2]),
                               (sphere[0], sphere_plan(sphere, rays=2000), [4, 0, 5])):
        again = pickle.loads(pickle.dumps(plan))
        same(take_keyed_readings(bench, plan, np.array(batch)), take_keyed_readings(bench, again, np.array(batch)))


def test_groups_share_rays(rough, bins):
    plan = Plan(Settings(rays=4000), (20.0, 40.0), groups=("first", "second"), hooks=(bins.layout(),) * 2)
    tally = run(rough, plan)
    same(tally.take(np.arange(2)), tally.take(np.arange(2, 4)))
    assert tally.bins.sum() > 0


def test_tallies_depend_on_the_key_only(rough, bins, sphere):
    """Any batch, any chunk size, any reading order: the same tallies for every reading."""

    plan = gonio_plan(Settings(rays=3000, wavelengths=(500, 600)), bins)
    whole = run(rough, plan)
    small = run(rough, gonio_plan(Settings(rays=3000, wavelengths=(500, 600), chunk_size=1024), bins))
    same(whole, small)
    order = np.array([3, 1, 0, 2])
    same(take_keyed_readings(rough, plan, order), whole.take(order))
    np.testing.assert_array_equal(whole.bins.sum(axis=1), whole.counts.reflected + whole.counts.transmitted)
    spheres = run(sphere[0], sphere_plan(sphere, rays=3000))
    same(spheres, run(sphere[0], sphere_plan(sphere, rays=3000, chunk_size=1024)))
    np.testing.assert_array_equal(spheres.bins.sum(axis=1), spheres.counts.rays)  # every ray one sphere fate
    assert set(spheres.sums) == {"wall_reflections", "weight_violations", "rounded_weights"}


def test_a_keyed_sphere_run_is_the_sphere_measurement(sphere):
    """The sphere instrument's reading is this keyed run: its counts come from the same tallies."""

    bench, layouts, settings = sphere
    tally = run(bench, sphere_plan(sphere, rays=3000))
    reading = vm.sphere_measure(SPHERE, rays=3000, wavelengths="450, 550, 650")
    detected = tally.bins[:, list(layouts[0].codes_of(SphereFate.DETECTED))].sum(axis=1)
    np.testing.assert_array_equal(detected[:3], reading.counts["sample"]["detected"])
    np.testing.assert_array_equal(detected[3:], reading.counts["standard"]["detected"])
    np.testing.assert_array_equal(tally.sums["wall_reflections"][3:], reading.counts["standard"]["wall_reflections"])


# --- checkpoints: bins and sums kept, resumed --------------------------------------------------


def _interrupted(bench, plan, path, after, monkeypatch):
    import virtspec_mi.engine.readings as engine

    real, calls = engine.take_keyed_readings, []

    def flaky(*args, **kwargs):
        if len(calls) == after:
            raise KeyboardInterrupt
        calls.append(1)
        return real(*args, **kwargs)

    with monkeypatch.context() as patch:
        patch.setattr(engine, "take_keyed_readings", flaky)
        with pytest.raises(KeyboardInterrupt):
            run(bench, plan, checkpoint=path)
    return json.loads(path.read_text())


@pytest.mark.parametrize("instrument", ["gonio", "sphere"])
def test_an_interrupted_run_resumes_to_the_uninterrupted_tallies(rough, bins, sphere, instrument, tmp_path,
                                                                  monkeypatch):
    if instrument == "gonio":
        bench, plan = rough, gonio_plan(Settings(rays=2000, wavelengths=(500, 600), chunk_size=2048), bins)
    else:
        bench, plan = sphere[0], sphere_plan(sphere, rays=2000, chunk_size=2048)
    whole = run(bench, plan)
    path = tmp_path / "run.partial.json"
    saved = _interrupted(bench, plan, path, 2, monkeypatch)
    assert len(saved["done"]) == 2 and len(saved["bins"]) == 2
    assert all(len(row) == plan.bins for row in saved["bins"])
    assert set(saved.get("sums", {})) == set(plan.sums) and saved["identity"]["instrument"] == plan.instrument
    resumed = run(bench, plan, checkpoint=path)
    same(resumed, whole)


def test_a_checkpoint_of_other_bins_is_refused(rough, bins, tmp_path, monkeypatch):
    plan = gonio_plan(Settings(rays=2000, chunk_size=2048), bins)
    path = tmp_path / "run.partial.json"
    _interrupted(rough, plan, path, 1, monkeypatch)
    with pytest.raises(CheckpointError, match="differs in: hooks, options"):
        run(rough, gonio_plan(Settings(rays=2000, chunk_size=2048), make_bins(5, 6)), checkpoint=path)


def test_tampered_bins_are_refused_with_the_reason(rough, bins, tmp_path, monkeypatch):
    plan = gonio_plan(Settings(rays=2000, chunk_size=2048), bins)
    path = tmp_path / "run.partial.json"
    saved = _interrupted(rough, plan, path, 1, monkeypatch)
    saved["bins"][0][0] += 5000  # more binned rays than the reading traced
    path.write_text(json.dumps(saved))
    with pytest.raises(CheckpointError, match="bins must add up to at most the reading's rays"):
        run(rough, plan, checkpoint=path)
    assert json.loads(path.read_text())["bins"][0][0] == saved["bins"][0][0]  # left as it is


def test_a_checkpoint_of_format_3_resumes_a_hemispherical_run_and_is_refused_for_bins(rough, bins, tmp_path,
                                                                                       monkeypatch):
    from virtspec_mi.engine.plan import Columns as PlanColumns

    settings = Settings(rays=2000, chunk_size=2048, wavelengths=(500, 600))
    plain = Plan(settings, (10.0, 50.0), columns=PlanColumns.fates(False))
    whole = run(rough, plain)
    path = tmp_path / "old.partial.json"
    saved = _interrupted(rough, plain, path, 2, monkeypatch)
    assert "bins" not in saved and "sums" not in saved
    path.write_text(json.dumps({**saved, "format": "virtspec-mi sweep checkpoint 3"}))
    same(run(rough, plain, checkpoint=path), whole)

    binned = gonio_plan(settings, bins)
    other = tmp_path / "old_gonio.partial.json"
    saved = _interrupted(rough, binned, other, 1, monkeypatch)
    other.write_text(json.dumps({**saved, "format": "virtspec-mi sweep checkpoint 3"}))
    with pytest.raises(CheckpointError, match="written before bins and sums were kept"):
        run(rough, binned, checkpoint=other)


# --- two-stage from each instrument's columns ----------------------------------------------------


def _pilot_and_second(bench, plan):
    """The two-stage run, and its pilot traced again through the kernel: n1 rays per reading, the seed's own
    rays from key * stride, the reading's group's hook."""

    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.kernel.counts import Counts
    from virtspec_mi.kernel.tracer import ReadingPlan, tally_readings

    tally = run(bench, plan)
    settings = plan.settings
    group, _, theta, lam = plan.split(np.arange(plan.size))
    pilot = [tally_readings(bench, [ReadingPlan(float(plan.wavelengths[lam[k]]), plan.theta_i[theta[k]], settings.phi_i,
                                                settings.pilot_rays_per_reading)],
                            offsets=[(k % plan.keys) * plan.stride], hook=plan.hook(group[k]), **kernel_options(settings))
             for k in range(plan.size)]
    return tally, Tally(Counts.concatenate([p.counts for p in pilot]), bins=np.concatenate([p.bins for p in pilot]))


def test_two_stage_sizes_goniophotometer_readings_from_every_bin_fraction(rough, bins):
    settings = Settings(bound="two-stage", mu=0.05, delta=0.2, wavelengths=(500, 600))
    union = rules.GUARANTEES["union"].stage_two(bins.size)
    plan = gonio_plan(settings, bins, columns=Columns(union, bins="each"))
    tally, pilot = _pilot_and_second(rough, plan)
    np.testing.assert_array_equal(tally.pilot.reflected, pilot.counts.reflected)  # the pilot: the seed's own rays
    expected = plan.columns.stage_two_rays(pilot.bins, settings)  # every bin at delta/K
    np.testing.assert_array_equal(tally.counts.rays, expected)
    # within the key range, and fewer rays than the fixed union bound would trace (the pilot's gain)
    assert np.all(expected <= plan.stride)
    assert np.all(expected + settings.pilot_rays_per_reading < rules.GUARANTEES["union"].rays(0.05, 0.2, bins.size))
    np.testing.assert_array_equal(tally.bins.sum(axis=1), tally.counts.reflected + tally.counts.transmitted)


def test_two_stage_sizes_each_sphere_configuration_from_its_detector_fraction(sphere):
    plan = sphere_plan(sphere, bound="two-stage", mu=0.05, delta=0.2)
    bench = sphere[0]
    tally, pilot = _pilot_and_second(bench, plan)
    detected = pilot.bins[:, list(plan.columns.bins[0])].sum(axis=1)
    expected = plan.columns.stage_two_rays(detected[:, None], plan.settings)  # each at delta/2
    np.testing.assert_array_equal(tally.counts.rays, expected)
    np.testing.assert_array_equal(tally.bins.sum(axis=1), tally.counts.rays)
    # delta/2: the same as sizing at half the delta, one column on its own
    halved = plan.settings.updated(delta=0.1, pilot_delta=plan.settings.pilot_delta_value / 2)
    np.testing.assert_array_equal(expected, Columns(rules.Columns("one", 1)).stage_two_rays(detected[:, None], halved))


def test_two_stage_is_refused_with_the_reason_where_it_cannot_size_the_readings(rough, bins):
    settings = Settings(bound="two-stage", mu=0.05, delta=0.2)
    with pytest.raises(ValueError, match="cannot size guarantee 'dkw'"):
        rules.GUARANTEES["dkw"].stage_two(bins.size)
    plan = gonio_plan(settings, bins, refusal="it certifies the CDFs, which no pilot bounds")
    with pytest.raises(ValueError, match="cannot size these readings: it certifies the CDFs"):
        run(rough, plan)
