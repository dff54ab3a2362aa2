"""
The RGL grid as bins (instruments/goniophotometer/warped.py) and its kernel hook (hook.WarpedLayout): the cells
partition the reflected hemisphere (their solid angles add up to 2π, their projected solid angles to π, at any θi),
agree with closed forms at normal incidence, every node lies in its own cell, and the kernel's float32 cell of a
direction is the float64 rule's except within rounding of a cell's edge.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.instruments.goniophotometer.warped import WarpedGrid, check_resolution


@pytest.mark.parametrize("resolution", [3, 8, 32])
@pytest.mark.parametrize("theta_i", [0.0, 30.0, 75.0, 89.0])
def test_the_cells_partition_the_reflected_hemisphere(resolution, theta_i):
    grid = WarpedGrid(resolution)
    omega = grid.solid_angles(theta_i)
    assert omega.shape == (grid.size,) and np.nanmin(omega) >= 0.0
    assert abs(np.nansum(omega) - 2 * np.pi) < 1e-12
    projected = grid.cell_integral(theta_i, 10.0, lambda wo: wo[..., 2])
    assert abs(np.nansum(projected) - np.pi) < 1e-12
    if theta_i > 0.0:  # unused indices (NaN) only at normal incidence, where each column is one ring
        assert not np.any(np.isnan(omega))


def test_normal_incidence_rings_are_cones_about_the_normal():
    grid = WarpedGrid(8)
    h = 1 / 7
    omega = grid.solid_angles(0.0)
    theta_disc = np.pi / 2 * (h / 2) ** 2  # theta_o = 2 theta_m at normal incidence
    assert omega[0] == pytest.approx(2 * np.pi * (1 - np.cos(2 * theta_disc)), rel=1e-13)
    a, b = np.pi / 2 * (1.5 * h) ** 2, min(np.pi / 4, np.pi / 2 * (2.5 * h) ** 2)
    assert omega[1 + 1 * 7] == pytest.approx(2 * np.pi * (np.cos(2 * a) - np.cos(2 * b)), rel=1e-13)


@pytest.mark.parametrize("theta_i", [0.0, 40.0, 70.0])
def test_every_visible_node_is_in_its_own_cell(theta_i):
    grid = WarpedGrid(9)
    wo = grid.node_directions(theta_i, 25.0)
    np.testing.assert_allclose(np.linalg.norm(wo, axis=-1), 1.0)
    visible = wo[..., 2] > 0
    np.testing.assert_array_equal(grid.cell_of(theta_i, 25.0, wo)[visible], grid.node_cells(theta_i)[visible])
    mirror = [-np.sin(np.radians(theta_i)) * np.cos(np.radians(25.0)),
              -np.sin(np.radians(theta_i)) * np.sin(np.radians(25.0)), np.cos(np.radians(theta_i))]
    np.testing.assert_allclose(wo[:, 0], np.broadcast_to(mirror, (9, 3)), atol=1e-12)  # column 0: the mirror


@pytest.mark.parametrize("theta_i, phi_i", [(0.0, 0.0), (0.0, 180.0), (35.0, 0.0), (70.0, 123.0)])
def test_the_kernel_hook_bins_as_the_float64_rule(mi, theta_i, phi_i):
    from virtspec_mi.kernel.counts import Fate

    grid = WarpedGrid(16)
    rng = np.random.default_rng(7)
    wo = rng.normal(size=(20_000, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1)[:, None]
    t, p = np.radians(theta_i), np.radians(phi_i)
    wi = np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], dtype=np.float32)
    fate = np.full(len(wo), int(Fate.REFLECTED), dtype=np.uint32)
    fate[:100] = int(Fate.TRANSMITTED)
    codes = grid.layout().bin(mi.Vector3f(*(wo[:, c].astype(np.float32) for c in range(3))), mi.UInt32(fate),
                              mi.Float(phi_i), mi.Vector3f(*(mi.Float(float(c)) for c in wi)))
    codes = np.array(codes, dtype=np.int64)
    assert np.all(codes[:100] == grid.size)
    expected = grid.cell_of(theta_i, phi_i, wo[100:])
    differ = codes[100:] != expected
    # a direction binned otherwise lies within float32 rounding of an edge: u (n - 1) is within 1e-3 of a half
    h = wo[100:] + np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    u1 = np.sqrt(np.arctan2(np.hypot(h[:, 0], h[:, 1]), h[:, 2]) * 2 / np.pi) * 15
    reference = 0.0 if theta_i == 0.0 else np.arctan2(wi[1], wi[0])
    u2 = ((np.arctan2(h[:, 1], h[:, 0]) - reference) / (2 * np.pi) + 0.5) % 1.0 * 15
    near = (np.abs(u1 - np.floor(u1) - 0.5) < 1e-3) | (np.abs(u2 - np.floor(u2) - 0.5) < 1e-3)
    assert np.all(near[differ]) and differ.sum() <= 10


def test_bad_resolutions_are_refused():
    assert check_resolution("16") == 16 and check_resolution(16.0) == 16
    for bad in (2, 1026, 3.5, True, "many", None):
        with pytest.raises(ValueError, match="rgl_resolution must be a whole number of nodes per axis, 3 <= "):
            check_resolution(bad)
