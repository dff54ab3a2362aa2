"""Tests of how the kernel queues a walk specimen's rays from its declared walk length
(:func:`virtspec_mi.kernel.queue.walk_plan`, ``WalkQueue.prestart``): counts never depend on it."""

import numpy as np
import pytest

import virtspec_mi as vm


@pytest.fixture(scope="module")
def mi():
    return vm.mitsuba()


def test_walk_plan_rule(mi):
    """Long declared walks: refill every 4th iteration; short or undeclared: 2; starts computed in the refill."""

    from virtspec_mi.kernel.queue import LONG_WALK_STEPS, WalkQueue, walk_plan

    assert walk_plan(None) == (2, False)
    assert walk_plan(LONG_WALK_STEPS - 0.5) == (2, False)
    assert walk_plan(LONG_WALK_STEPS) == (4, False)
    assert WalkQueue().planned(LONG_WALK_STEPS * 2) == WalkQueue(refill=4, prestart=False)
    assert WalkQueue().planned(None) == WalkQueue(refill=2, prestart=False)
    explicit = WalkQueue(lanes=64, queue="group", refill=8, prestart=False)
    assert explicit.planned(LONG_WALK_STEPS * 2) == explicit  # given values are kept


def test_walk_specimens_declare_their_length(mi):
    """The leaves declare long walks (the measured mean over the soybean spectrum); the slab declares none."""

    from virtspec_mi.kernel.queue import LONG_WALK_STEPS
    from virtspec_mi.kernel.walk import walk_steps
    from virtspec_mi.runtime.scene import find_bench

    for leaf in ("abm_b", "abm_u"):
        assert walk_steps(find_bench(vm.instrument_scene({"type": leaf})).bsdf) >= LONG_WALK_STEPS
    assert walk_steps(find_bench(vm.instrument_scene({"type": "turbid_slab"})).bsdf) is None


def test_prestart_is_checked(mi):
    from virtspec_mi.kernel.queue import WalkQueue

    with pytest.raises(ValueError, match="prestart"):
        WalkQueue(prestart="yes")


_CASES = {
    # specimen, settings, readings (wavelength, theta_i): several θi so every start array differs per ray
    "abm_b": ({"type": "abm_b"}, {}, [(465.0, 8.0), (800.0, 40.0), (1450.0, 70.0)]),
    "slab_diffuse": ({"type": "turbid_slab", "mu_a": 1.0, "mu_s": 9.0, "g": 0.75, "thickness": 0.2},
                     {"beam": "diffuse", "seed": 3}, [(551.0, 0.0), (600.0, 0.0)]),
}


@pytest.mark.parametrize("case", sorted(_CASES))
def test_prestart_counts_as_one_loop_per_ray(mi, case):
    """Bit-identical counts and bins: starts computed in the refill or before the loop, any chunk size."""

    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.instruments.goniophotometer.bins import make_bins
    from virtspec_mi.kernel.tracer import ReadingPlan, WalkQueue, tally_readings
    from virtspec_mi.runtime.scene import find_bench
    from virtspec_mi.settings import Settings

    specimen, options, readings = _CASES[case]
    instrument = find_bench(vm.instrument_scene(specimen))
    plans = [ReadingPlan(w, t, 0.0, 3000) for w, t in readings]
    offsets = [k * 5000 + 11 for k in range(len(plans))]

    def tally(settings, walk, hook=None):
        return tally_readings(instrument, plans, offsets=offsets, walk=walk, hook=hook, **kernel_options(settings))

    def counts(walk, chunk):
        c = tally(Settings(chunk_size=chunk, **options), walk).counts
        return np.stack([c.reflected, c.transmitted, c.capped, c.specular_reflected, c.regular_transmitted])

    one_loop = counts(WalkQueue(lanes=0), 1 << 22)
    assert one_loop[0].sum() > 0 and one_loop[1].sum() > 0  # both fates occur: the comparison can fail
    for walk, chunk in ((WalkQueue(prestart=True), 1 << 22), (WalkQueue(prestart=True, refill=1, lanes=40), 1024),
                        (WalkQueue(prestart=False, refill=4, queue="group", lanes=64), 4096)):
        assert np.array_equal(counts(walk, chunk), one_loop), (walk, chunk)
    bins = make_bins(theta_o_bins=6, phi_o_bins=8)
    binned = tally(Settings(**options), WalkQueue(lanes=0), bins.layout()).bins
    assert np.count_nonzero(binned) > 4
    queued = tally(Settings(chunk_size=1024, **options), WalkQueue(prestart=True, lanes=100), bins.layout()).bins
    assert np.array_equal(queued, binned)
