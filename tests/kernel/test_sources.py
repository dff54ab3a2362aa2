"""
Tests of :mod:`virtspec_mi.kernel.sources`: the helpers that map a chunk's lanes to its
readings, and eq. (3)'s rejection loop.

A chunk of packed lanes [first, first + size) holds the tails and heads of consecutive
readings: each reading's first lane and first ray are those of the layout, every lane finds
its reading by binary lifting, and the per-reading sums from a cumulative sum are the sums
of the lanes. The rejection loop draws keyed points of the square until one falls in the disk:
inside, reproducible from (ray, root), and uniform by area within a Hoeffding bound.
:class:`~virtspec_mi.kernel.sources.RaySource` itself needs a kernel: the tracer's and the
pinned-count tests run it.

References
----------
Baranoski et al. (2001), eqs. (3), (4).
"""

from __future__ import annotations

import math

import numpy as np
import pytest


@pytest.fixture(scope="module")
def sources(mi):
    from virtspec_mi.kernel import sources

    return sources


def layout() -> tuple[np.ndarray, np.ndarray]:
    """Four readings of 5, 3, 7 and 4 rays packed one after the other: their first lanes, their sizes."""

    sizes = np.array([5, 3, 7, 4])
    return np.concatenate([[0], np.cumsum(sizes)[:-1]]), sizes


def test_lane_ranges_of_a_chunk_that_cuts_readings(sources):
    starts, _ = layout()  # readings start at lanes 0, 5, 8, 15
    first, size = 6, 10  # lanes 6 … 15: the tail of reading 1, reading 2, the head of reading 3
    slots = np.array([1, 2, 3])
    bounds, first_ray = sources.lane_ranges(first, size, slots, starts)
    np.testing.assert_array_equal(bounds, [0, 2, 9])  # each reading's first lane in the chunk
    np.testing.assert_array_equal(first_ray, [1, 0, 0])  # reading 1 enters at its ray 1
    assert bounds.dtype == first_ray.dtype == np.uint32


def test_find_slot_gives_each_lane_its_reading(sources, mi):
    for bounds in ([0], [0, 2, 9], [0, 1, 2, 3, 4], [0, 4, 4, 6, 11, 12, 20]):
        bounds = np.array(bounds, dtype=np.uint32)
        lanes = np.arange(int(bounds[-1]) + 3, dtype=np.uint32)
        expected = np.searchsorted(bounds, lanes, side="right") - 1
        found = np.array(sources.find_slot(bounds, mi.UInt32(lanes)))
        np.testing.assert_array_equal(found, expected, err_msg=str(bounds))


def test_segment_sums_are_the_lanes_sums(sources, mi):
    import drjit as dr

    rng = np.random.default_rng(3)
    values = rng.integers(0, 1000, size=23).astype(np.uint32)
    bounds = np.array([0, 4, 4, 9, 17], dtype=np.uint32)
    ends = np.append(bounds[1:], values.size)
    sums = sources.segment_sums(dr.cumsum(mi.UInt32(values)), bounds, ends)
    expected = [values[b:e].sum() for b, e in zip(bounds, ends)]
    np.testing.assert_array_equal(sums, expected)
    assert sums[1] == 0  # an empty range


def test_gather_tree_and_full(sources, mi):
    tree = {"a": mi.Float([1.0, 2.0, 3.0]), "b": (mi.UInt32([7, 8, 9]), mi.Float(5.0)), "c": "label"}
    picked = sources.gather_tree(tree, mi.UInt32([2, 0]))
    np.testing.assert_array_equal(np.array(picked["a"]), [3.0, 1.0])
    np.testing.assert_array_equal(np.array(picked["b"][0]), [9, 7])
    assert picked["b"][1] is tree["b"][1] and picked["c"] == "label"  # width 1 and plain values kept
    assert isinstance(picked["b"], tuple)
    np.testing.assert_array_equal(np.array(sources.full(mi.Float(2.5), 4)), [2.5] * 4)
    wide = mi.Float([1.0, 2.0])
    assert sources.full(wide, 2) is wide


def test_rejection_points_are_in_the_disk_reproducible_and_uniform(sources, mi):
    from virtspec_mi.kernel.rng import chunk_root

    n = 20_000
    root = chunk_root(5, 0)
    index = mi.UInt32(np.arange(n, dtype=np.uint32))
    p = sources.rejection(index, root, mi.Float(2.0), 0)
    xy = np.stack([np.array(p.x), np.array(p.y)], axis=1)
    again = sources.rejection(index, root, mi.Float(2.0), 0)
    np.testing.assert_array_equal(np.array(again.x), xy[:, 0])
    other = sources.rejection(index, root, mi.Float(2.0), 1)  # the specimen disk: other dimensions
    assert np.mean(np.array(other.x) == xy[:, 0]) < 0.01
    r2 = np.sum(xy * xy, axis=1) / 4.0
    assert np.all(r2 <= 1.0)
    half_width = math.sqrt(math.log(2e6) / (2 * n))
    for share in (0.25, 0.5, 0.8):
        assert abs(np.mean(r2 <= share) - share) <= half_width
    assert abs(np.mean(xy[:, 0] > 0) - 0.5) <= half_width
