"""
Tests of :mod:`virtspec_mi.kernel.incidence`: the incidence frame is the rotation of the bench.

References
----------
Baranoski et al. (2001), Sect. 3.2, Fig. 1.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from virtspec_mi.kernel.incidence import incidence_frame

ANGLES = [(0.0, 0.0), (10.0, 0.0), (45.0, 90.0), (60.0, 217.5), (89.0, -30.0)]


@pytest.mark.parametrize("theta, phi", ANGLES)
def test_the_frame_is_orthonormal_and_right_handed(theta, phi):
    omega, e_u, e_v = incidence_frame(theta, phi)
    frame = np.stack([e_u, e_v, omega])
    np.testing.assert_allclose(frame @ frame.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(np.cross(e_u, e_v), omega, atol=1e-15)
    assert omega[2] == pytest.approx(np.cos(np.radians(theta)), abs=1e-15)  # cos θi towards the emitter
    assert e_v[2] == 0.0


@pytest.mark.parametrize("theta, phi", ANGLES)
def test_a_disk_point_is_rotated_by_theta_about_y_then_phi_about_z(theta, phi):
    omega, e_u, e_v = incidence_frame(theta, phi)
    rotation = Rotation.from_euler("z", phi, degrees=True) * Rotation.from_euler("y", theta, degrees=True)
    distance = 2.5
    for x, y in [(0.0, 0.0), (0.3, -0.1), (-0.2, 0.4)]:
        np.testing.assert_allclose(distance * omega + x * e_u + y * e_v, rotation.apply([x, y, distance]),
                                   atol=1e-14)


def test_normal_incidence_is_the_identity_and_phi_turns_about_the_normal():
    omega, e_u, e_v = incidence_frame(0.0, 0.0)
    np.testing.assert_array_equal(np.stack([e_u, e_v, omega]), np.eye(3))
    omega90, _, _ = incidence_frame(30.0, 90.0)
    np.testing.assert_allclose(omega90, [0.0, 0.5, np.sqrt(3) / 2], atol=1e-15)
