"""
A colour's joint region (applications/targets/joint.py): the CIELAB Jacobian, the cover of
the region by pieces (every point of the region in some piece's XYZ hull and its Lab in
that piece's Lab box, checked by sampling the region densely), and the radius over it
never below the largest ΔE₀₀ of a sampled point.
"""

from __future__ import annotations

import colour
import numpy as np
import pytest

from virtspec_mi.applications.targets.joint import lab_jacobian, region_boxes, region_colour
from virtspec_mi.colorimetry.cie import Colour

WHITE = np.asarray(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])


def _lab(XYZ: np.ndarray) -> np.ndarray:
    return np.asarray(colour.XYZ_to_Lab(np.asarray(XYZ) / 100.0, WHITE))


@pytest.mark.parametrize("XYZ", [[7.86, 10.80, 4.76], [17.1, 18.0, 19.6], [0.5, 0.4, 0.9]])
def test_the_jacobian_is_cielabs(XYZ):
    XYZ = np.asarray(XYZ)
    G = lab_jacobian(XYZ, WHITE)
    step = 1e-6 * XYZ
    numeric = np.stack([(_lab(XYZ + np.eye(3)[j] * step[j]) - _lab(XYZ - np.eye(3)[j] * step[j])) / (2 * step[j])
                        for j in range(3)], axis=1)
    assert np.allclose(G, numeric, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("parts", [1, 2, 3])
@pytest.mark.parametrize("XYZ, widths", [([7.86, 10.80, 4.76], [0.3, 0.8, 0.9]), ([17.1, 18.0, 19.6], [2, 3, 3]),
                                        ([0.6, 0.5, 1.2], [0.4, 2.0, 2.0])])
def test_the_pieces_cover_the_region_and_the_radius_bounds_every_point(XYZ, widths, parts):
    rng = np.random.default_rng(1)
    XYZ = np.asarray(XYZ)
    G = lab_jacobian(XYZ * 1.02, WHITE)  # a pilot's point a little off
    centre = G @ XYZ
    low, high = centre - np.asarray(widths) * 0.8, centre + np.asarray(widths) * 1.1
    floor, ceiling = np.zeros(3), np.array([95.0, 100.0, 108.0])
    lower, upper, Lab_low, Lab_high = region_boxes(G, low, high, floor, ceiling, WHITE, parts)
    y = low + (high - low) * np.concatenate([rng.random((4000, 3)), rng.integers(0, 2, (400, 3))])  # corners too
    x = np.linalg.solve(G, y.T).T
    x = x[np.all((x >= 0) & (x <= ceiling), axis=1)]
    Lab = _lab(x)
    inside = ((lower[None] <= x[:, None] + 1e-9) & (x[:, None] <= upper[None] + 1e-9)).all(axis=2) & \
             ((Lab_low[None] <= Lab[:, None] + 1e-9) & (Lab[:, None] <= Lab_high[None] + 1e-9)).all(axis=2)
    assert inside.any(axis=1).all()
    estimate = Colour(XYZ, _lab(XYZ), np.zeros(3), "D65", "CIE 1931 2 Degree Standard Observer", np.arange(3.0))
    certified = region_colour(estimate, G, low, high, floor, ceiling, WHITE, 0.1, 1, "test", parts)
    de00 = np.asarray(colour.delta_E(Lab, _lab(XYZ), method="CIE 2000"))
    assert de00.max() <= certified.dE00_radius
    assert np.all(certified.XYZ_interval[:, 0] <= x.min(axis=0) + 1e-9)
    assert np.all(x.max(axis=0) <= certified.XYZ_interval[:, 1] + 1e-9)
    assert np.all(certified.Lab_interval[:, 0] <= Lab.min(axis=0) + 1e-9)
    assert np.all(Lab.max(axis=0) <= certified.Lab_interval[:, 1] + 1e-9)
    assert certified.dE00_radius < 2.5 * de00.max()  # and not far above it
