"""
Tests of :mod:`virtspec_mi.kernel.rng`: counter-based random numbers keyed on (seed, ray index).

``hash32`` maps 0 to 0 (every step of triple32 does) and is a bijection (no two of 2²⁰
consecutive inputs collide); one flipped input bit flips half the output bits on average;
NumPy and Dr.Jit compute the same hash and keys; the keys depend on the seed, the block and
the dimension; uniforms lie in [0, 1) on a 2⁻²⁴ grid and are uniform within a Hoeffding
bound. Fixed inputs throughout.

References
----------
C. Wellons, *Prospecting for hash functions* (2018) (the triple32 hash).
"""

from __future__ import annotations

import math

import numpy as np

from virtspec_mi.kernel.rng import (
    FIXED_DIMENSIONS,
    GOLDEN,
    chunk_root,
    dimension_key,
    dimension_keys,
    hash32,
    to_unit,
)


def np_hash(values) -> np.ndarray:
    with np.errstate(over="ignore"):
        return hash32(np.asarray(values, dtype=np.uint32))


def test_zero_is_fixed_and_the_hash_is_a_bijection_on_a_range():
    assert int(np_hash([0])[0]) == 0
    inputs = np.arange(1 << 20, dtype=np.uint32) * np.uint32(7919) + np.uint32(12345)
    outputs = np_hash(inputs)
    assert outputs.dtype == np.uint32 and np.unique(outputs).size == inputs.size


def test_one_flipped_bit_flips_half_the_output_bits():
    rng = np.random.default_rng(0)
    x = rng.integers(0, 2**32, size=20_000, dtype=np.uint64).astype(np.uint32)
    flipped = np.zeros(32)
    for bit in range(32):
        diff = np_hash(x) ^ np_hash(x ^ np.uint32(1 << bit))
        flipped[bit] = np.mean(np.unpackbits(diff.view(np.uint8)).reshape(-1, 32).sum(axis=1))
    # the mean of 20,000 counts in [0, 32]: Hoeffding at δ = 1e-6 per bit, 32·√(ln(2e6)/40000) ≈ 0.62
    assert np.all(np.abs(flipped - 16.0) <= 32 * math.sqrt(math.log(2e6) / 40_000))


def test_keys_depend_on_seed_block_and_dimension():
    root = chunk_root(7, 0)
    assert root == chunk_root(7, 0) and 0 <= root < 2**32
    assert len({chunk_root(seed, block) for seed in range(4) for block in range(4)}) == 16
    keys = dimension_keys(root)
    assert len(keys) == FIXED_DIMENSIONS and len(set(keys)) == FIXED_DIMENSIONS
    assert keys[3] == int(np_hash([(root + 3 * GOLDEN) & 0xFFFFFFFF])[0])
    assert dimension_keys(root, 12)[:FIXED_DIMENSIONS] == keys
    assert chunk_root(2**32 + 7, 0) == root  # the seed is taken modulo 2³²


def test_numpy_and_drjit_compute_the_same_hash_and_keys(mi):
    import drjit as dr

    inputs = np.array([0, 1, 2, 12345, 2**31, 2**32 - 1], dtype=np.uint32)
    np.testing.assert_array_equal(np.array(hash32(mi.UInt32(inputs)), dtype=np.uint32), np_hash(inputs))
    root = chunk_root(3, 1)
    keys = dimension_key(mi.UInt32(root), dr.arange(mi.UInt32, FIXED_DIMENSIONS))
    assert [int(k) for k in np.array(keys)] == dimension_keys(root)


def test_uniforms_lie_on_a_24_bit_grid_in_the_unit_interval():
    bits = np.array([0, 255, 256, 2**31, 2**32 - 1], dtype=np.uint32)
    u = to_unit(bits, np.float64)
    np.testing.assert_array_equal(u, [0.0, 0.0, 2.0**-24, 0.5, 1.0 - 2.0**-24])


def test_uniforms_of_consecutive_rays_are_uniform():
    key = dimension_keys(chunk_root(11, 0))[0]
    n = 100_000
    u = to_unit(np_hash(np.arange(n, dtype=np.uint32) ^ np.uint32(key)), np.float64)
    half_width = math.sqrt(math.log(2e6) / (2 * n))  # Hoeffding, δ = 1e-6 per check
    for p in (0.1, 0.25, 0.5, 0.9):
        assert abs(np.mean(u < p) - p) <= half_width
    assert abs(np.mean(u) - 0.5) <= half_width
