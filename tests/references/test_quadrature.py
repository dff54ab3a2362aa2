"""
Tests of :mod:`virtspec_mi.references.quadrature`: the NumPy references the instrument is checked against.

Fresnel values are the research notes' anchors (Born & Wolf, Principles of Optics, Sect. 1.5,
computed independently and cross-checked with ``iadpython.fresnel_reflection`` and
Mitsuba's own spot check); the conical quadrature is checked for convergence, for its
normal-incidence anchor and against closed forms of the geometry.

References
----------
Baranoski et al. (2001), Sect. 5.1, Fig. 1; Born & Wolf, Sect. 1.5.2.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.geometry.disks import InstrumentGeometry
from virtspec_mi.references.quadrature import (
    DEFAULT_NODES,
    QuadratureNodes,
    cone_half_angle_bound,
    conical_average,
    conical_mean_incidence_angle,
    conical_reflectance,
    emitter_points,
    fresnel_reflectance,
    fresnel_reflectance_cos,
    incidence_angle_bounds,
    incidence_angle_range,
    specimen_points,
)

PAPER = InstrumentGeometry()
DIAMOND = 2.419

# the project's exact computations (virtspec_mi/budgets/bounds.py): θ (deg) → R air→1.5, R air→2.419, R 2.419→air (η = 1/2.419).
FRESNEL_ANCHORS = [
    (0.0, 0.040000, 0.172253, 0.172253),
    (10.0, 0.040015, 0.172269, 0.172921),
    (20.0, 0.040266, 0.172524, 0.198857),
    (30.0, 0.041523, 0.173742, 1.0),
    (45.0, 0.050240, 0.181386, 1.0),
    (60.0, 0.089187, 0.211486, 1.0),
    (67.54, 0.143160, 0.250699, 1.0),
    (80.0, 0.387704, 0.433323, 1.0),
    (85.0, 0.612800, 0.621651, 1.0),
    (89.0, 0.904185, 0.899711, 1.0),
]


# --- Fresnel -----------------------------------------------------------------------------


@pytest.mark.parametrize("theta, glass, diamond, diamond_inside", FRESNEL_ANCHORS)
def test_fresnel_matches_anchor_table(theta, glass, diamond, diamond_inside):
    # The table is printed to 6 decimals: agreement to rounding (5e-7) plus float noise.
    assert fresnel_reflectance(theta, 1.5) == pytest.approx(glass, abs=6e-7)
    assert fresnel_reflectance(theta, DIAMOND) == pytest.approx(diamond, abs=6e-7)
    assert fresnel_reflectance(theta, 1.0 / DIAMOND) == pytest.approx(diamond_inside, abs=6e-7)


def test_fresnel_mitsuba_spot_check():
    # Mitsuba's test_dielectric.py::test05_spot_check value, to 15 digits.
    assert fresnel_reflectance(80.0, 1.5) == pytest.approx(0.387704354691473, abs=1e-14)


def test_fresnel_is_vectorised_and_float64():
    theta = np.array([[0.0, 60.0], [80.0, 90.0]])
    values = fresnel_reflectance(theta, DIAMOND)
    assert values.shape == (2, 2) and values.dtype == np.float64
    expected = [[fresnel_reflectance(t, DIAMOND) for t in row] for row in theta]
    np.testing.assert_array_equal(values, expected)
    np.testing.assert_allclose(fresnel_reflectance(60.0, [1.5, DIAMOND]), [0.089187, 0.211486], atol=6e-7)


@pytest.mark.parametrize("eta", [1.5, DIAMOND])
def test_fresnel_normal_incidence_closed_form(eta):
    assert fresnel_reflectance(0.0, eta) == pytest.approx(((eta - 1.0) / (eta + 1.0)) ** 2, abs=1e-15)


@pytest.mark.parametrize("eta", [1.5, DIAMOND, 1.0 / 1.5, 1.0 / DIAMOND, 0.2, 5.0])
def test_fresnel_grazing_incidence_is_one(eta):
    assert fresnel_reflectance(90.0, eta) == 1.0


def test_fresnel_no_interface_reflects_nothing():
    theta = np.linspace(0.0, 90.0, 91)
    np.testing.assert_array_equal(fresnel_reflectance(theta, 1.0), 0.0)


@pytest.mark.parametrize("eta, critical", [(1.5, 41.810), (DIAMOND, 24.418)])
def test_fresnel_total_internal_reflection_starts_at_critical_angle(eta, critical):
    # critical angles (arcsin(1/eta)) 41.810° (1.5) and 24.418° (2.419), inside the denser medium.
    exact = math.degrees(math.asin(1.0 / eta))
    assert exact == pytest.approx(critical, abs=5e-4)
    assert fresnel_reflectance(exact - 1e-3, 1.0 / eta) < 1.0
    assert fresnel_reflectance(exact + 1e-3, 1.0 / eta) == 1.0
    np.testing.assert_array_equal(fresnel_reflectance(np.linspace(exact + 1e-6, 90.0, 50), 1.0 / eta), 1.0)


@pytest.mark.parametrize("eta, brewster", [(1.5, 56.310), (DIAMOND, 67.540)])
def test_fresnel_brewster_angle_has_no_p_reflection(eta, brewster):
    # At Brewster's angle r_p = 0, so R = r_s²/2 = ½((cos θ − η cos θt)/(cos θ + η cos θt))².
    exact = math.degrees(math.atan(eta))
    assert exact == pytest.approx(brewster, abs=5e-4)
    cos_i = math.cos(math.radians(exact))
    cos_t = math.sqrt(1.0 - (1.0 - cos_i**2) / eta**2)
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    assert fresnel_reflectance(exact, eta) == pytest.approx(0.5 * r_s**2, rel=1e-13)


def test_fresnel_reciprocity_across_the_interface():
    # Stokes relation: R is the same for the refracted ray travelling back (θt, 1/η).
    theta = np.linspace(0.0, 89.0, 90)
    theta_t = np.degrees(np.arcsin(np.sin(np.radians(theta)) / DIAMOND))
    np.testing.assert_allclose(fresnel_reflectance(theta, DIAMOND),
                               fresnel_reflectance(theta_t, 1.0 / DIAMOND), rtol=1e-12, atol=1e-15)


# --- Quadrature rules --------------------------------------------------------------------


@pytest.mark.parametrize("theta", [0.0, 60.0, 88.0, 90.0])
def test_disk_rules_integrate_area_moments(theta):
    # Uniform by area: weights sum to 1, centroid at the centre, E[r²] = R²/2, E[r⁴] = R⁴/3.
    points, weights = specimen_points(PAPER)
    r2 = (points**2).sum(axis=1)
    assert weights.sum() == pytest.approx(1.0, abs=1e-14)
    assert weights @ points[:, 0] == pytest.approx(0.0, abs=1e-12)
    assert weights @ r2 == pytest.approx(PAPER.specimen_radius**2 / 2, rel=1e-13)
    assert weights @ r2**2 == pytest.approx(PAPER.specimen_radius**4 / 3, rel=1e-13)

    centre = PAPER.distance * np.array([math.sin(math.radians(theta)), 0.0, math.cos(math.radians(theta))])
    points, weights = emitter_points(theta, 0.0, PAPER)
    offset = points - centre
    r2 = (offset**2).sum(axis=1)
    assert weights.sum() == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(weights @ offset, 0.0, atol=1e-12)
    assert weights @ r2 == pytest.approx(PAPER.emitter_radius**2 / 2, rel=1e-13)
    assert weights @ r2**2 == pytest.approx(PAPER.emitter_radius**4 / 3, rel=1e-13)
    # The emitter disk is perpendicular to ω.
    np.testing.assert_allclose(offset @ (centre / PAPER.distance), 0.0, atol=1e-12)


@pytest.mark.parametrize("theta", [86.0, 88.0, 89.5, 90.0])
def test_emitter_rule_splits_at_the_specimen_plane(theta):
    # The back-lit share is a circular segment: (r²acos(a/r) − a√(r² − a²))/(πr²), a = D cot θ.
    r, a = PAPER.emitter_radius, PAPER.distance / math.tan(math.radians(theta))
    segment = (r * r * math.acos(a / r) - a * math.sqrt(r * r - a * a)) / (math.pi * r * r)
    below = conical_average(lambda c: (c < 0.0).astype(float), theta)
    assert below == pytest.approx(segment, abs=1e-13)
    if theta == 90.0:
        assert below == pytest.approx(0.5, abs=1e-13)


# --- Conical reflectance -----------------------------------------------------------------

ANGLES = [0.0, 30.0, 60.0, 70.0, 80.0, 85.0, 86.0, 88.0, 89.0, 89.5, 90.0]


@pytest.mark.parametrize("theta", ANGLES)
def test_conical_reflectance_is_converged(theta):
    coarse = conical_reflectance(theta)
    fine = conical_reflectance(theta, nodes=DEFAULT_NODES.doubled())
    assert abs(fine - coarse) < 1e-7
    # Fewer nodes still agree: the pieces are analytic, so convergence is geometric.
    assert abs(conical_reflectance(theta, nodes=QuadratureNodes(8, 8, 8, 12)) - fine) < 1e-5


def test_conical_reflectance_at_normal_incidence_matches_anchor():
    # the project's exact computations (virtspec_mi/budgets/bounds.py): cone average 0.172256 for η = 2.419 (0.040003 for 1.5), F(0) = 0.172253.
    value = conical_reflectance(0.0)
    assert value == pytest.approx(0.172256, abs=6e-7)
    assert value == pytest.approx(float(fresnel_reflectance(0.0, DIAMOND)), abs=1e-4)
    assert conical_reflectance(0.0, eta=1.5) == pytest.approx(0.040003, abs=6e-7)
    # The anchors' range of R over the cone, [0.172253, 0.172282]: the mean lies inside.
    assert 0.172253 <= value <= 0.172282


@pytest.mark.parametrize("theta", [0.0, 45.0, 85.0, 89.0])
def test_conical_reflectance_does_not_depend_on_phi(theta):
    # The specimen disk and the Fresnel specimen are isotropic.
    assert conical_reflectance(theta, phi_i=123.0) == pytest.approx(conical_reflectance(theta), abs=1e-12)


def test_conical_reflectance_tends_to_fresnel_for_a_small_instrument():
    # A pinhole emitter and specimen far apart: the cone shrinks to the collimated beam.
    tiny = InstrumentGeometry(1e-4, 1e-4, 100.0)
    for theta in (0.0, 30.0, 70.0, 85.0):
        assert conical_reflectance(theta, geometry=tiny) == pytest.approx(
            float(fresnel_reflectance(theta, DIAMOND)), abs=1e-9)


def test_conical_reflectance_without_interface_is_zero_unless_back_lit():
    # η = 1: front-lit rays never reflect; back-lit rays always pass to the upper hemisphere.
    for theta in (0.0, 70.0, 85.0):
        assert conical_reflectance(theta, eta=1.0) == 0.0
    for theta in (88.0, 90.0):
        below = conical_average(lambda c: (c < 0.0).astype(float), theta)
        assert conical_reflectance(theta, eta=1.0) == pytest.approx(below, abs=1e-13)


@pytest.mark.parametrize("theta", [88.0, 89.0, 90.0])
def test_back_lit_rays_of_diamond_count_as_transmitted(theta):
    # Back-face incidence is within ~5° of grazing, beyond the critical angle 24.4°: every
    # back-lit ray is totally internally reflected, stays below the plane and is
    # "transmitted". So ρ is the front-face average over the whole emitter.
    front_only = conical_average(
        lambda c: np.where(c >= 0.0, fresnel_reflectance_cos(np.abs(c), DIAMOND), 0.0), theta)
    assert conical_reflectance(theta) == pytest.approx(front_only, abs=1e-13)


def test_conical_reflectance_exceeds_collimated_at_oblique_incidence():
    # F is convex in θ over the instrument's cone at oblique incidence, so the cone average
    # exceeds F(θi): the property that lets the conical tests tell the two beams apart.
    for theta in (30.0, 60.0, 70.0, 80.0):
        assert conical_reflectance(theta) > float(fresnel_reflectance(theta, DIAMOND))
    assert conical_reflectance(70.0) - float(fresnel_reflectance(70.0, DIAMOND)) > 2.9e-3


def test_mean_incidence_angle_at_normal_incidence():
    # a reference mean 5.466° (a Monte Carlo estimate; the converged quadrature gives
    # 5.46853°, and 10⁸ independent pairs give 5.4687 ± 0.0002).
    value = conical_mean_incidence_angle(0.0)
    assert value == pytest.approx(5.466, abs=5e-3)
    assert value == pytest.approx(5.46853, abs=1e-5)
    finer = conical_mean_incidence_angle(0.0, nodes=QuadratureNodes(48, 48, 48, 96))
    assert abs(finer - value) < 1e-6


# --- Where the rays point ----------------------------------------------------------------


def test_cone_half_angle_bound_of_the_paper():
    assert cone_half_angle_bound(PAPER) == pytest.approx(math.degrees(math.asin(0.205)), abs=1e-12)
    assert cone_half_angle_bound(PAPER) == pytest.approx(11.8295, abs=1e-4)
    assert cone_half_angle_bound(InstrumentGeometry(60.0, 60.0, 100.0)) == 180.0


def test_atan_cone_only_holds_at_normal_incidence():
    # At θi = 70° the pair below makes 11.72° with ω (the maximum is 11.7317°): more than
    # atan((r1 + r2)/D) = 11.585°, less than the proven asin bound 11.83°.
    theta, beta = math.radians(70.0), math.radians(12.5)
    omega = np.array([math.sin(theta), 0.0, math.cos(theta)])
    emitter = PAPER.distance * omega + PAPER.emitter_radius * np.array([0.0, 1.0, 0.0])
    target = PAPER.specimen_radius * np.array([math.sin(beta), -math.cos(beta), 0.0])
    ray = (emitter - target) / np.linalg.norm(emitter - target)
    angle = math.degrees(math.acos(ray @ omega))
    assert angle > math.degrees(math.atan(0.205)) + 0.1
    assert angle < cone_half_angle_bound(PAPER)


@pytest.mark.parametrize("theta", [0.0, 30.0, 70.0, 85.0, 88.0, 90.0])
def test_incidence_angle_range_lies_in_the_proven_bounds(theta):
    exact = incidence_angle_range(theta)
    low, high = incidence_angle_bounds(theta)
    assert low <= exact.low <= exact.high <= high
    assert exact.slack < 0.01
    assert exact.low <= theta <= exact.high


def test_incidence_angle_range_at_normal_incidence():
    # Opposite rim points: atan((r1 + r2)/D) = 11.585° (the project's exact computations (virtspec_mi/budgets/bounds.py) 11.568°, a sample max).
    exact = incidence_angle_range(0.0)
    assert exact.low == 0.0
    assert exact.high == pytest.approx(math.degrees(math.atan(0.205)), abs=1e-9)


def test_incidence_angle_range_contains_the_quadrature_pairs():
    # Every quadrature pair's angle lies in the enclosure, and the pairs come close to both ends.
    nodes = QuadratureNodes(32, 32, 32, 64)
    target, _ = specimen_points(PAPER, nodes)
    for theta in (30.0, 85.0, 89.0):
        emitter, _ = emitter_points(theta, 0.0, PAPER, nodes)
        dx = emitter[:, None, 0] - target[None, :, 0]
        dy = emitter[:, None, 1] - target[None, :, 1]
        gamma = np.degrees(np.arctan2(np.hypot(dx, dy), emitter[:, None, 2]))
        exact = incidence_angle_range(theta)
        low, high = exact.enclosure
        assert low <= gamma.min() and gamma.max() <= high
        assert gamma.min() - exact.low < 0.1 and exact.high - gamma.max() < 0.1
