"""Shared random-walk conventions: capped walks are counted apart, walk RNG streams."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.kernel.walk import CAPPED_COMPONENT, walk_rng

from mirror_specimen import register_mirror


@pytest.fixture(scope="module")
def capping_bsdf(mi):
    """A test specimen: reports a capped walk when sample1 < 0.25, else reflects."""

    import drjit as dr

    def change(bs, weight, sample1, si, props):
        capped = sample1 < 0.25
        bs.sampled_component = dr.select(capped, mi.UInt32(CAPPED_COMPONENT), mi.UInt32(0))
        return bs, dr.select(capped, mi.Spectrum(0.0), weight)

    return register_mirror(mi, "capping_test", change)


def test_capped_walks_are_counted_in_no_tally(mi, capping_bsdf):
    scene = vm.instrument_scene({"type": capping_bsdf})
    with pytest.warns(RuntimeWarning, match="step cap"):
        reading = vm.measure(scene, theta_i=20, rays=40_000, wavelengths=[500, 600])
    n = reading.rays
    assert np.all(reading.capped > 0)
    assert np.all(reading.reflected + reading.capped == n)
    assert np.all(reading.absorbed == 0) and np.all(reading.transmitted == 0)
    # sample1 is uniform: P(capped) = 1/4, so the count is Binomial(N, 1/4); 6 sigma.
    assert np.all(np.abs(reading.capped / n - 0.25) < 6 * np.sqrt(0.25 * 0.75 / n))
    assert "step cap" in reading.summary()
    assert reading.as_dict()["capped"] == reading.capped.tolist()


def test_ordinary_specimens_have_no_capped_walks(diamond):
    reading = vm.measure(diamond, rays=10_000)
    assert reading.capped.sum() == 0
    assert reading.absorbed.sum() == 0


def test_walk_rng_is_a_function_of_the_samples(mi):
    import drjit as dr

    s1 = mi.Float([0.1, 0.1, 0.7])
    s2 = mi.Point2f([0.2, 0.2, 0.2], [0.3, 0.3, 0.3])
    a = walk_rng(s1, s2).next_float32()
    b = walk_rng(s1, s2).next_float32()
    dr.eval(a, b)
    a, b = np.array(a), np.array(b)
    assert np.array_equal(a, b)
    assert a[0] == a[1] and a[0] != a[2]


def _streams(mi, lanes: int, draws: int, seed: int = 0):
    """``draws`` numbers of ``lanes`` walk streams seeded from uniform samples (rows: lanes), as NumPy."""

    import drjit as dr

    rng = np.random.default_rng(seed)
    s1 = mi.Float(rng.random(lanes, dtype=np.float32))
    s2 = mi.Point2f(mi.Float(rng.random(lanes, dtype=np.float32)), mi.Float(rng.random(lanes, dtype=np.float32)))
    walk = walk_rng(s1, s2)
    columns = []
    for _ in range(draws):
        u = walk.next_float32()
        dr.eval(u, walk)
        columns.append(np.array(u))
    return np.stack(columns, axis=1)


def test_walk_rng_draws_are_uniform_and_uncorrelated(mi):
    """
    2·10⁶ numbers (4,000 streams × 500 draws): 64-bin χ² below its mean + 6 sd (63 + 6·√126),
    the mean within 6 standard errors of 1/2, and the correlation of consecutive draws of a
    stream and of neighbouring streams (adjacent lanes) within 6/√n of 0. Fixed seed.
    """

    u = _streams(mi, 4000, 500)
    n = u.size
    assert np.all((u >= 0.0) & (u < 1.0))
    assert abs(u.mean() - 0.5) < 6 * np.sqrt(1 / 12 / n)
    observed = np.bincount(np.floor(u.ravel() * 64).astype(int), minlength=64)
    chi2 = float(((observed - n / 64) ** 2 / (n / 64)).sum())
    assert chi2 < 63 + 6 * np.sqrt(126)
    centred = u - 0.5
    along = (centred[:, 1:] * centred[:, :-1]).mean() * 12
    across = (centred[1:, :] * centred[:-1, :]).mean() * 12
    assert abs(along) < 6 / np.sqrt(n) and abs(across) < 6 / np.sqrt(n)


def test_walk_rng_masked_draws_leave_other_lanes_where_they_were(mi):
    """A lane outside the mask keeps its place in its stream: its next unmasked draw is its next number."""

    import drjit as dr

    s1 = mi.Float([0.1, 0.2, 0.3, 0.4])
    s2 = mi.Point2f([0.5, 0.6, 0.7, 0.8], [0.9, 0.1, 0.2, 0.3])
    plain, masked = walk_rng(s1, s2), walk_rng(s1, s2)
    first = plain.next_float32()
    second = plain.next_float32()
    mask = mi.Bool([True, False, True, False])
    a = masked.next_float32(mask)
    b = masked.next_float32()
    dr.eval(first, second, a, b)
    first, second, a, b = map(np.array, (first, second, a, b))
    on = np.array([True, False, True, False])
    assert np.array_equal(a[on], first[on]) and np.array_equal(b[on], second[on])
    assert np.array_equal(b[~on], first[~on])  # the masked-out lanes drew their first number only now


def test_walk_rng_streams_do_not_repeat(mi):
    """Within a stream the 32-bit draws are distinct (an odd stride: x_i = x_0 + i·s never repeats before 2³²)."""

    import drjit as dr

    rng = np.random.default_rng(1)
    walk = walk_rng(mi.Float(rng.random(64, dtype=np.float32)),
                    mi.Point2f(mi.Float(rng.random(64, dtype=np.float32)), mi.Float(rng.random(64, dtype=np.float32))))
    bits = []
    for _ in range(4096):
        value = walk.next_uint32()
        dr.eval(value, walk)
        bits.append(np.array(value))
    bits = np.stack(bits, axis=1)
    assert all(len(np.unique(row)) == row.size for row in bits)
    assert np.all(np.array(walk.stride) % 2 == 1)


# --- the walk as resumable steps, run on queued lanes by the kernel --------------------------

_QUEUE_CASES = {
    # specimen, settings, readings (wavelength, theta_i): walks of every kind and beam
    "abm_b_conical": ({"type": "abm_b"}, {}, [(465.0, 8.0), (800.0, 8.0), (1450.0, 40.0)]),
    "abm_u_backlit_random": ({"type": "abm_u", "side": "abaxial"}, {"sampling": "random", "seed": 3},
                             [(551.0, 88.0), (800.0, 0.0)]),
    "slab_diffuse": ({"type": "turbid_slab", "mu_a": 1.0, "mu_s": 9.0, "g": 0.75, "thickness": 0.2, "eta": 1.4},
                     {"beam": "diffuse", "seed": 7}, [(551.0, 0.0), (600.0, 0.0)]),
    "slab_collimated_clear": ({"type": "turbid_slab", "mu_a": 0.5, "eta": 1.5, "eta_below": 1.33},
                              {"beam": "collimated"}, [(551.0, 30.0)]),
}


def _tally(instrument, readings, settings, rays, **queue):
    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.kernel.tracer import ReadingPlan, WalkQueue, tally_readings

    plans = [ReadingPlan(w, t, 0.0, rays) for w, t in readings]
    offsets = [k * 3 * rays + 17 for k in range(len(plans))]  # gaps: readings keyed apart
    counts = tally_readings(instrument, plans, offsets=offsets, walk=WalkQueue(**queue), **kernel_options(settings)).counts
    return np.stack([counts.reflected, counts.transmitted, counts.capped, counts.specular_reflected,
                     counts.regular_transmitted, counts.rounded_weights, counts.weight_violations])


@pytest.mark.parametrize("case", sorted(_QUEUE_CASES))
def test_queued_walks_count_as_one_loop_per_ray(mi, case):
    """Bit-identical counts: sample() per ray (one loop) vs queued lanes of any count, queue and chunk size."""

    from virtspec_mi.kernel.queue import WalkQueue
    from virtspec_mi.runtime.scene import find_bench
    from virtspec_mi.settings import Settings

    specimen, options, readings = _QUEUE_CASES[case]
    instrument = find_bench(vm.instrument_scene(specimen))
    rays = 3000
    one_loop = _tally(instrument, readings, Settings(**options), rays, lanes=0)
    assert one_loop[0].sum() > 0 and one_loop[1].sum() > 0  # both fates occur: the comparison can fail
    default = WalkQueue()
    for lanes, queue, refill, chunk in ((default.lanes, default.queue, default.refill, 1 << 22),
                                        (1000, "stride", 1, 1024), (37, "counter", 4, 4096), (40, "group", 2, 1024),
                                        (8192, "group", 1, 1 << 22), (4096, "counter", 2, 1 << 22),
                                        (1, "stride", 2, 1024)):
        queued = _tally(instrument, readings, Settings(chunk_size=chunk, **options), rays,
                        lanes=lanes, queue=queue, refill=refill)
        assert np.array_equal(queued, one_loop), (lanes, queue, refill, chunk)


_GONIO_CASES = {
    # specimen, settings, readings (wavelength, theta_i, phi_i), bins
    "abm_b": ({"type": "abm_b"}, {}, [(465.0, 8.0, 0.0), (800.0, 40.0, 30.0), (1450.0, 8.0, 200.0)],
              dict(theta_o_bins=9, phi_o_bins=12)),
    "abm_b_folded_projected": ({"type": "abm_b"}, {"seed": 5}, [(551.0, 60.0, 120.0), (800.0, 8.0, 300.0)],
                               dict(theta_o_bins=5, phi_o_bins=7, binning="projected", fold_phi=True)),
    "slab_edges": ({"type": "turbid_slab", "mu_a": 1.0, "mu_s": 9.0, "g": 0.75, "thickness": 0.2, "eta": 1.4},
                   {"seed": 7}, [(551.0, 0.0, 0.0), (600.0, 50.0, 90.0)],
                   dict(theta_o_bins=[0, 10, 30, 90, 120, 180], phi_o_bins=[0, 45, 200, 360])),
}


@pytest.mark.parametrize("case", sorted(_GONIO_CASES))
def test_queued_walks_bin_as_one_loop_per_ray(mi, case):
    """Goniophotometer bins bit-identical: sample() per ray (one loop) vs queued lanes, any chunk size."""

    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.instruments.goniophotometer.bins import make_bins
    from virtspec_mi.kernel.tracer import ReadingPlan, WalkQueue, tally_readings
    from virtspec_mi.runtime.scene import find_bench
    from virtspec_mi.settings import Settings

    specimen, options, readings, spec = _GONIO_CASES[case]
    instrument = find_bench(vm.instrument_scene(specimen))
    bins = make_bins(**spec)
    plans = [ReadingPlan(w, t, p, 3000) for w, t, p in readings]

    def tally(settings, walk):
        result = tally_readings(instrument, plans, hook=bins.layout(), walk=walk, **kernel_options(settings))
        return result.counts, result.bins

    counts, one_loop = tally(Settings(**options), WalkQueue(lanes=0))
    assert np.count_nonzero(one_loop) > 4  # rays spread over bins: the comparison can fail
    assert np.array_equal(one_loop.sum(axis=1), counts.reflected + counts.transmitted)
    for queue, chunk in ((WalkQueue(), 1 << 22), (WalkQueue(lanes=40, queue="group"), 1024),
                         (WalkQueue(lanes=1000, queue="stride", refill=1), 4096)):
        queued_counts, queued = tally(Settings(chunk_size=chunk, **options), queue)
        assert np.array_equal(queued, one_loop), (queue, chunk)
        assert np.array_equal(queued_counts.reflected, counts.reflected)
        assert np.array_equal(queued_counts.transmitted, counts.transmitted)


def test_walk_specimens_declare_their_steps(mi, diamond):
    from virtspec_mi.kernel.walk import is_random_walk
    from virtspec_mi.runtime.scene import find_bench

    for specimen in ({"type": "abm_b"}, {"type": "abm_u"}, {"type": "turbid_slab"}):
        assert is_random_walk(find_bench(vm.instrument_scene(specimen)).bsdf)
    assert not is_random_walk(find_bench(diamond).bsdf)


@pytest.fixture(scope="module")
def coin_walk(mi):
    """A minimal RandomWalk specimen: each step exits up (p = 0.2), down (p = 0.1) or walks on."""

    import drjit as dr

    from virtspec_mi.kernel.walk import walk_to_end
    from virtspec_mi.plugins.bsdfs.sampled_only import SampledOnlyBSDF

    class CoinWalk(SampledOnlyBSDF):
        def __init__(self, props):
            super().__init__(props)
            self.m_flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.DiffuseTransmission | \
                mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide

        def sample(self, ctx, si, sample1, sample2, active=True):
            return self.walk_sample(walk_to_end(self, self.walk_start(si, sample1, sample2, active)))

        def walk_start(self, si, sample1, sample2, active=True):
            status = dr.select(mi.Bool(active), mi.UInt32(0), mi.UInt32(3)) + dr.zeros(mi.UInt32, dr.width(sample1))
            return (walk_rng(sample1, sample2), status)

        def walk_step(self, state):
            rng, status = state
            u = rng.next_float32()
            return (rng, dr.select(u < 0.2, mi.UInt32(1), dr.select(u < 0.3, mi.UInt32(2), status)))

        def walk_done(self, state):
            return state[1] != 0

        def walk_sample(self, state):
            status = state[1]
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.Vector3f(0.0, 0.0, dr.select(status == 2, -1.0, 1.0))
            bs.pdf = 1.0
            bs.sampled_type = dr.select(status == 2, mi.UInt32(+mi.BSDFFlags.DiffuseTransmission),
                                        mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
            return bs, dr.select((status == 1) | (status == 2), mi.Spectrum(1.0), mi.Spectrum(0.0))

    mi.register_bsdf("coin_walk_test", lambda props: CoinWalk(props))
    return "coin_walk_test"


def test_any_specimen_declaring_the_steps_runs_queued(mi, coin_walk):
    """The protocol is generic: a new walk specimen gets the queued lanes, with the one-loop counts."""

    from virtspec_mi.kernel.walk import is_random_walk
    from virtspec_mi.runtime.scene import find_bench
    from virtspec_mi.settings import Settings

    instrument = find_bench(vm.instrument_scene({"type": coin_walk}))
    assert is_random_walk(instrument.bsdf)
    n = 20_000
    one_loop = _tally(instrument, [(551.0, 10.0)], Settings(), n, lanes=0)
    queued = _tally(instrument, [(551.0, 10.0)], Settings(chunk_size=4096), n, lanes=333)
    assert np.array_equal(queued, one_loop)
    # Exits up with probability 2/3, down 1/3 (each step: 0.2 vs 0.1): 6 sigma.
    assert abs(one_loop[0][0] / n - 2 / 3) < 6 * np.sqrt(2 / 9 / n)
    assert one_loop[0][0] + one_loop[1][0] == n


def test_the_walk_queue_refuses_bad_values():
    from virtspec_mi.kernel.queue import WalkQueue

    for bad, match in (({"lanes": -1}, "lanes"), ({"queue": "lifo"}, "queue"), ({"refill": 3}, "refill"),
                       ({"refill": 0}, "refill")):
        with pytest.raises(ValueError, match=match):
            WalkQueue(**bad)


def test_queued_walks_do_not_depend_on_the_thread_count(mi):
    """The shared counter hands rays to lanes in a timing-dependent order: counts must not care."""

    import drjit as dr

    from virtspec_mi.runtime.scene import find_bench
    from virtspec_mi.settings import Settings

    specimen, options, readings = _QUEUE_CASES["abm_b_conical"]
    instrument = find_bench(vm.instrument_scene(specimen))
    threads = dr.thread_count()
    several = _tally(instrument, readings, Settings(chunk_size=4096, **options), 3000, lanes=64)
    try:
        dr.set_thread_count(1)
        one = _tally(instrument, readings, Settings(chunk_size=4096, **options), 3000, lanes=64)
    finally:
        dr.set_thread_count(threads)
    assert np.array_equal(one, several)
    assert np.array_equal(one, _tally(instrument, readings, Settings(**options), 3000, lanes=0))
