"""The colour-difference bounds of colorimetry.delta_e enclose colour-science's ΔE₀₀ and ΔE*ab."""

from __future__ import annotations

import re

import colour
import numpy as np
import pytest

from virtspec_mi.colorimetry.delta_e import LabBox, delta_e_00_bounds, delta_e_ab_bounds, lab_box

WHITE = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]


def _random_lab(rng, n):
    lab = np.column_stack([rng.uniform(0, 100, n), rng.uniform(-90, 90, n), rng.uniform(-90, 90, n)])
    lab[::5, 1:] *= 0.02  # near the achromatic axis, where hue is unstable
    return lab


def test_the_de00_enclosure_holds_between_points_and_is_close_near_by():
    rng = np.random.default_rng(1)
    p = _random_lab(rng, 3000)
    q = np.where(np.arange(3000)[:, None] % 2 == 0, p + rng.normal(0, 1.5, p.shape), _random_lab(rng, 3000))
    exact = np.asarray(colour.delta_E(p, q, method="CIE 2000"))
    ratios = []
    for a, b, d in zip(p, q, exact):
        low, high = delta_e_00_bounds(LabBox.point(a), LabBox.point(b))
        assert low - 1e-9 <= d <= high + 1e-9, (a, b, low, d, high)
        ratios.append(high / max(d, 1e-12))
    assert np.median(ratios[::2]) < 1.5  # a useful bound, not just a valid one


@pytest.mark.parametrize("seed", range(4))
def test_every_colour_of_two_boxes_lies_within_the_bounds(seed):
    rng = np.random.default_rng(seed)
    centre_a, centre_b = _random_lab(rng, 2)
    centre_b = centre_a + rng.normal(0, 3, 3) if seed % 2 else centre_b
    half_a, half_b = rng.uniform(0, 2, 3), rng.uniform(0, 2, 3)
    a, b = LabBox(centre_a - half_a, centre_a + half_a), LabBox(centre_b - half_b, centre_b + half_b)
    inside_a = centre_a + rng.uniform(-1, 1, (4000, 3)) * half_a
    inside_b = centre_b + rng.uniform(-1, 1, (4000, 3)) * half_b
    d00 = np.asarray(colour.delta_E(inside_a, inside_b, method="CIE 2000"))
    dab = np.linalg.norm(inside_a - inside_b, axis=1)
    low, high = delta_e_00_bounds(a, b)
    assert low <= d00.min() and d00.max() <= high
    low, high = delta_e_ab_bounds(a, b)
    assert low <= dab.min() and dab.max() <= high
    corners = np.array([[x, y, z] for x in (a.lower[0], a.upper[0]) for y in (a.lower[1], a.upper[1])
                        for z in (a.lower[2], a.upper[2])])
    assert max(np.linalg.norm(corners - centre_a, axis=1)) == pytest.approx(delta_e_ab_bounds(LabBox.point(centre_a),
                                                                                               a)[1])


def test_the_lab_box_is_the_exact_image_of_an_xyz_box():
    rng = np.random.default_rng(3)
    lower, upper = np.array([20.0, 25.0, 10.0]), np.array([22.0, 26.0, 13.0])
    box = lab_box(lower, upper, WHITE)
    inside = lower + rng.uniform(0, 1, (5000, 3)) * (upper - lower)
    lab = np.asarray(colour.XYZ_to_Lab(inside / 100, WHITE))
    assert np.all(lab >= box.lower - 1e-9) and np.all(lab <= box.upper + 1e-9)
    corners = np.array([[x, y, z] for x in (lower[0], upper[0]) for y in (lower[1], upper[1])
                        for z in (lower[2], upper[2])])
    at_corners = np.asarray(colour.XYZ_to_Lab(corners / 100, WHITE))  # the extremes are reached there: exact
    assert np.allclose(at_corners.min(axis=0), box.lower) and np.allclose(at_corners.max(axis=0), box.upper)


def test_what_is_not_a_colour_is_named_not_a_numpy_error():
    from types import SimpleNamespace

    from virtspec_mi.applications.targets.difference import colour_difference

    band_result = SimpleNamespace(target=SimpleNamespace(kind="band"), colour=None)  # a band target's result
    for other, shown in (("red", "'red': not a colour"), (band_result, "the result of a band target: not a colour"),
                         ([[1, 2], 3], "list [[1, 2], 3]")):
        with pytest.raises(ValueError, match=r"^b must be a certified colour .* \(got " + re.escape(shown)):
            colour_difference([50.0, 0.0, 0.0], other)
