"""Per-ray flags of the kernel: invalid directions are their own category; flags are full width.

Issue 12 ("Nothing wrong, nothing lost, nothing hangs"): a NaN outgoing direction used to
count as transmitted (``wo.z > 0`` is false for NaN), and a BSDF returning a width-1 weight
(a constant) had its weight violations counted once per chunk instead of once per ray.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.kernel.counts import Counts, Fate
from virtspec_mi.kernel.tracer import ReadingPlan, trace_rays
from virtspec_mi.runtime.scene import find_bench
from virtspec_mi.settings import Settings

from mirror_specimen import register_mirror

# sample1 bands of the invalid-direction test specimen and what each gives.
NAN, ZERO, INFINITE, LONG, ABSORBED_NAN = (0.0, 0.2), (0.2, 0.3), (0.3, 0.35), (0.35, 0.4), (0.9, 1.0)


@pytest.fixture(scope="module")
def invalid_bsdf(mi):
    """Mirror reflection, except: NaN, zero-length, infinite and length-2 directions (weight 1) and
    NaN directions with weight 0 (absorbed) in the sample1 bands above."""

    import drjit as dr

    def change(bs, weight, sample1, si, props):
        def band(span):
            return (sample1 >= span[0]) & (sample1 < span[1])

        nan = dr.nan
        wo = bs.wo
        wo = dr.select(band(NAN) | band(ABSORBED_NAN), mi.Vector3f(nan, nan, nan), wo)
        wo = dr.select(band(ZERO), mi.Vector3f(0.0, 0.0, 0.0), wo)
        wo = dr.select(band(INFINITE), mi.Vector3f(dr.inf, 0.0, 1.0), wo)
        wo = dr.select(band(LONG), 2.0 * mi.reflect(si.wi), wo)
        bs.wo = wo
        return bs, dr.select(band(ABSORBED_NAN), mi.Spectrum(0.0), weight)

    return register_mirror(mi, "invalid_directions_test", change)


@pytest.fixture(scope="module")
def constant_weight_bsdf(mi):
    """Mirror reflection with a width-1 weight given by the ``weight`` parameter (e.g. inf)."""

    return register_mirror(mi, "constant_weight_test",
                           lambda bs, weight, sample1, si, props: (bs, mi.Spectrum(props.get("weight", 1.0))))


def _share(span):
    return span[1] - span[0]


def test_invalid_directions_are_counted_apart_in_no_fate(mi, invalid_bsdf):
    scene = vm.instrument_scene({"type": invalid_bsdf})
    with pytest.warns(RuntimeWarning, match="invalid direction"):
        reading = vm.measure(scene, theta_i=30, beam="collimated", rays=40_000, wavelengths=[500, 600])
    n = reading.rays
    invalid = reading.invalid_directions
    # NaN, zero, infinite and length-2 directions with weight 1; NaN with weight 0 is absorbed.
    p = _share(NAN) + _share(ZERO) + _share(INFINITE) + _share(LONG)
    assert np.all(np.abs(invalid / n - p) < 6 * np.sqrt(p * (1 - p) / n))
    assert np.all(reading.transmitted == 0)  # a NaN direction is not transmitted
    q = _share(ABSORBED_NAN)
    assert np.all(np.abs(reading.absorbed / n - q) < 6 * np.sqrt(q * (1 - q) / n))
    assert np.all(reading.reflected + reading.transmitted + reading.absorbed + reading.capped + invalid == n)
    assert not np.any(reading.certified) and np.all(np.isnan(reading.certified_mu))
    assert "invalid direction" in reading.summary() and "NOT CERTIFIED" in reading.summary()
    assert reading.as_dict()["invalid_directions"] == invalid.tolist()
    assert np.array_equal(reading.counts.count(Fate(4)), invalid)  # Fate.INVALID


def test_trace_rays_marks_invalid_directions(mi, invalid_bsdf):
    instrument = find_bench(vm.instrument_scene({"type": invalid_bsdf}))
    lanes = trace_rays(instrument, ReadingPlan(551.0, 30.0, 0.0, 4000), 4000, seed=0, beam="collimated",
                       sampling="jittered")
    wo, fate = lanes["wo"], lanes["fate"]
    length = np.linalg.norm(wo, axis=1)
    bad = ~(np.abs(length - 1) <= 1e-3) & (lanes["weight"] > 0)
    assert bad.any() and np.all(fate[bad] == 4)  # Fate.INVALID
    assert np.all(fate[~bad & (lanes["weight"] > 0)] == Fate.REFLECTED)
    assert np.all(fate[lanes["weight"] == 0] == Fate.ABSORBED)


def test_a_width_one_weight_is_counted_once_per_ray(mi, constant_weight_bsdf):
    violating = vm.instrument_scene({"type": constant_weight_bsdf, "weight": float("inf")})
    with pytest.warns(RuntimeWarning, match="outside \\[0, 1\\]"):
        reading = vm.measure(violating, rays=1000, wavelengths=[450, 650])
    assert reading.weight_violations.tolist() == [1000, 1000]
    assert reading.largest_weight.tolist() == [np.inf, np.inf]
    rounded = vm.measure(vm.instrument_scene({"type": constant_weight_bsdf, "weight": 1.00005}), rays=1000)
    assert rounded.rounded_weights.tolist() == [1000] and rounded.reflected.tolist() == [1000]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        exact = vm.measure(vm.instrument_scene({"type": constant_weight_bsdf, "weight": 1.0}), rays=1000)
    assert exact.reflected.tolist() == [1000] and exact.certified.all()


def test_counts_of_old_results_read_without_invalid_directions(diamond):
    reading = vm.measure(diamond, rays=1000)
    data = reading.as_dict()
    del data["invalid_directions"], data["absorbed"]
    again = vm.Result.from_dict(data)
    assert again.invalid_directions.tolist() == [0] and again.reflected.tolist() == reading.reflected.tolist()
    assert "invalid_directions" in Counts.names()


# --- the chunk cuts: O(readings) NumPy, never a per-ray or per-cut Python list ----------------


def _cuts_by_loop(starts, offsets, rays):
    """The former per-reading loop (one cut per 2**32 block a reading spans)."""

    word = 1 << 32
    cuts = [starts[-1]]
    for k in range(len(rays)):
        first_block, last_block = offsets[k] // word, (offsets[k] + rays[k] - 1) // word
        cuts.extend(starts[k] + (b * word - offsets[k]) for b in range(first_block + 1, last_block + 1))
        if k and first_block != (offsets[k - 1] + rays[k - 1] - 1) // word:
            cuts.append(starts[k])
    return np.unique(np.array(cuts, dtype=np.int64))


def test_chunk_cuts_match_the_per_reading_rule():
    from virtspec_mi.kernel.tracer import _cuts

    rng = np.random.default_rng(3)
    for _ in range(200):
        count = int(rng.integers(1, 12))
        rays = rng.integers(1, 2**32, size=count, dtype=np.int64)
        gaps = rng.integers(0, 2**33, size=count, dtype=np.int64)
        offsets = np.concatenate([[0], np.cumsum(rays + gaps)[:-1]]) + int(rng.integers(0, 2**34))
        order = rng.permutation(count)
        rays, offsets = rays[order], offsets[order]
        starts = np.concatenate([[0], np.cumsum(rays)])
        np.testing.assert_array_equal(_cuts(starts, offsets, rays), _cuts_by_loop(starts, offsets, rays))


def test_a_reading_beyond_two_to_the_32_is_refused_at_the_boundary(diamond):
    """The kernel trusts its readings (at most 2**32 - 1 rays: a reading crosses one 2**32 boundary at most);
    the boundary refuses more, before anything is traced."""

    with pytest.raises(ValueError, match="rays must satisfy 1 <= rays <= 4294967295"):
        Settings(rays=2**32)
    with pytest.raises(ValueError, match="rays must satisfy 1 <= rays <= 4294967295"):
        vm.measure(diamond, rays=2**32)
