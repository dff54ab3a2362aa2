"""
Tests of :mod:`virtspec_mi.kernel.disk`: the kernel's disk sampling, eqs. (3) and (4) and Shirley–Chiu.

Every method puts its points inside the disk and uniformly by area: the share of points
within radius r·√a is a, within a Hoeffding bound (δ = 1e-6) at fixed uniforms; the
jittered grid puts ray j in cell j and leaves rays past n² unstratified; an unknown method
is refused with the allowed ones named.

References
----------
Baranoski et al. (2001), Sect. 3.2, eqs. (3) and (4); P. Shirley, K. Chiu (1997), A low
distortion map between disk and square, J. Graphics Tools 2(3).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.kernel.disk import jittered_cell, polar_warp, sample_disk

N = 40_000
RADIUS = 0.75
HALF_WIDTH = math.sqrt(math.log(2e6) / (2 * N))


def uniforms(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.random(N).astype(np.float32), rng.random(N).astype(np.float32)


def points(mi, sampling: str, rejection=None) -> np.ndarray:
    u1, u2 = uniforms()
    p = sample_disk(mi, sampling, mi.Float(u1), mi.Float(u2), mi.Float(RADIUS), rejection)
    return np.stack([np.array(p.x), np.array(p.y)], axis=1)


def assert_uniform_in_the_disk(xy: np.ndarray) -> None:
    r2 = np.sum(xy * xy, axis=1) / RADIUS ** 2
    assert np.all(r2 <= 1.0 + 1e-5)
    for share in (0.1, 0.25, 0.5, 0.75):
        assert abs(np.mean(r2 <= share) - share) <= HALF_WIDTH, share
    angle = np.arctan2(xy[:, 1], xy[:, 0])
    for quarter in range(4):  # each quadrant a quarter of the area
        low = -math.pi + quarter * math.pi / 2
        assert abs(np.mean((angle >= low) & (angle < low + math.pi / 2)) - 0.25) <= HALF_WIDTH


@pytest.mark.parametrize("sampling", ["jittered", "concentric"])
def test_points_are_uniform_by_area(mi, sampling):
    assert_uniform_in_the_disk(points(mi, sampling))


def test_concentric_is_mitsubas_disk_warp(mi):
    u1, u2 = uniforms(1)
    p = sample_disk(mi, "concentric", mi.Float(u1), mi.Float(u2), mi.Float(2.0))
    q = mi.warp.square_to_uniform_disk_concentric(mi.Point2f(u1, u2))
    np.testing.assert_allclose(np.array(p.x), 2.0 * np.array(q.x), rtol=1e-6, atol=1e-7)


def test_polar_warp_is_eq_4(mi):
    p = polar_warp(mi, mi.Float([0.0, 0.25, 0.5]), mi.Float([1.0, 0.25, 0.04]), mi.Float(2.0))
    np.testing.assert_allclose(np.array(p.x), [2.0, 0.0, -0.4], atol=1e-6)
    np.testing.assert_allclose(np.array(p.y), [0.0, 1.0, 0.0], atol=1e-6)


def test_random_sampling_runs_the_rejection_given(mi):
    rng = np.random.default_rng(2)

    def rejection(radius):  # eq. (3): uniform in the square, kept inside the disk (host side, for the test)
        xy = rng.uniform(-1.0, 1.0, size=(4 * N, 2))
        xy = xy[np.sum(xy * xy, axis=1) <= 1.0][:N] * float(radius[0])
        return mi.Point2f(xy[:, 0], xy[:, 1])

    assert_uniform_in_the_disk(points(mi, "random", rejection))


def test_jittered_cells_put_ray_j_in_cell_j(mi):
    strata = 5
    rays = np.arange(strata * strata + 3, dtype=np.uint32)
    u1 = np.full(rays.size, 0.5, dtype=np.float32)
    u2 = np.full(rays.size, 0.25, dtype=np.float32)
    a, b = jittered_cell(mi, mi.Float(u1), mi.Float(u2), mi.UInt32(rays), mi.UInt32(strata))
    a, b = np.array(a), np.array(b)
    inside = rays < strata * strata
    np.testing.assert_allclose(a[inside], (rays[inside] % strata + 0.5) / strata, rtol=1e-6)
    np.testing.assert_allclose(b[inside], (rays[inside] // strata + 0.25) / strata, rtol=1e-6)
    np.testing.assert_array_equal(a[~inside], 0.5)  # past n²: unstratified
    np.testing.assert_array_equal(b[~inside], 0.25)


def test_unknown_sampling_is_refused(mi):
    with pytest.raises(ValueError, match=r"sampling must be one of jittered, random, concentric \(got 'sobol'\)"):
        sample_disk(mi, "sobol", mi.Float(0.5), mi.Float(0.5), mi.Float(1.0))
