"""
Tests of virtspec_mi.instruments.sphere.double_theory: the exchange model reduces to the single sphere's
closed forms, conserves light, and its cross-talk is the difference between the double and the single readings.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.instruments.sphere import theory as st
from virtspec_mi.instruments.sphere.double_theory import DoubleSphereModel, SphereFractions, fractions_of
from virtspec_mi.instruments.sphere.geometry import Port, Sphere

R_SPHERE = SphereFractions(0.97, specimen=0.03, detector=0.005, open=0.004)
T_SPHERE = SphereFractions(0.96, specimen=0.028, detector=0.006)


@pytest.mark.parametrize("rho", [0.0, 0.3, 0.9])
def test_an_opaque_specimen_is_the_single_spheres_closed_form(rho):
    """tau = 0: the transmittance sphere plays no part; P_R from the specimen is theory.detected_fraction (flat)."""

    model = DoubleSphereModel(R_SPHERE, T_SPHERE)
    p = model.detected(rho, 0.0)
    expected = st.detected_fraction(0.97, rho, sample_fraction=0.03, detector_fraction=0.005, open_fraction=0.004,
                                    start="sample")
    assert p[1, 0] == pytest.approx(expected, rel=1e-12)
    assert p[1, 1] == 0.0 and p[0, 1] == 0.0
    assert model.readings(rho, 0.0)[0] == pytest.approx(model.single(rho, 0.0)[0], rel=1e-12)


def test_a_lossless_pair_detects_every_ray():
    """White walls, no open port, a non-absorbing specimen: every emission ends on one of the two detectors."""

    lossless = DoubleSphereModel(SphereFractions(1.0, 0.03, 0.005), SphereFractions(1.0, 0.028, 0.006))
    p = lossless.detected(0.35, 0.65)
    assert np.allclose(p.sum(axis=1), 1.0, rtol=0, atol=1e-12)


def test_cross_talk_raises_both_readings_over_the_single_spheres():
    """Light passed back through the specimen adds to both detectors: double > single, and equal without it."""

    model = DoubleSphereModel(R_SPHERE, T_SPHERE)
    double, single = model.readings(0.45, 0.45), model.single(0.45, 0.45)
    assert double[0] > single[0] and double[1] > single[1]
    no_transmission = model.readings(0.45, 0.0)[0], model.single(0.45, 0.0)[0]
    assert no_transmission[0] == pytest.approx(no_transmission[1], rel=1e-12)


def test_fractions_of_a_sphere_are_its_exact_caps():
    sphere = Sphere(60, 0.98, (Port("sample", "sample", 180, 0, 10.0), Port("entrance", "entrance", 15.54, 0, 3.0),
                               Port("detector", "detector", 90, 90, 4.0), Port("ref", "reference", 90, 0, 5.0)))
    f = fractions_of(sphere, 0.98, "sample")
    assert f.specimen == pytest.approx(sphere.cap_fraction("sample"))
    assert f.open == pytest.approx(sphere.cap_fraction("entrance"))  # the reference port is plugged: wall
    assert f.wall == pytest.approx(1 - f.specimen - f.open - f.detector)
    t = Sphere(60, 0.98, (Port("entrance", "entrance", 0, 0, 10.0), Port("white", "sample", 180, 0, 5.0),
                          Port("detector", "detector", 90, 90, 4.0)))
    g = fractions_of(t, 0.98, "entrance")
    assert g.standard == pytest.approx(t.cap_fraction("white")) and g.open == 0.0
