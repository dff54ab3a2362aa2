"""
Tests of the instrument's ray geometry, through the real ray kernel.

:func:`trace_rays` runs the same Dr.Jit code as a measurement and returns each ray's
emitter point (specimen frame), specimen point and directions. The tests recover the
disk coordinates of both points and check that every sampling strategy is uniform by
area (χ², mean r², inner-disk share), that the rays lie in the cone the geometry
allows (:func:`virtspec_mi.references.quadrature.incidence_angle_range`), the back-lit share
above atan(D/r₁), and the collimated beam.

Statistical checks use fixed seeds (the counter-based random numbers make every run
identical) and thresholds with false-alarm probability ≤ 1e-4 (χ², one-sided) or
beyond 5 standard errors (≈ 6e-7).

References
----------
Baranoski et al. (2001), Sect. 3.2, eqs. (3) and (4), Fig. 1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import virtspec_mi
from virtspec_mi.geometry.disks import InstrumentGeometry, backlit_fraction, incidence_frame
from virtspec_mi.references.quadrature import (
    cone_half_angle_bound,
    conical_average,
    incidence_angle_range,
)

SAMPLINGS = ("jittered", "random", "concentric")
UNIFORMITY_RAYS = 200_000
CONE_RAYS = 1_000_000
SIGNIFICANCE = 1e-4
# float32 storage of an emitter point ~100 mm from the specimen centre: ~2⁻²³·100 per coordinate.
FLOAT32_MM = 1e-5


@pytest.fixture(scope="module")
def instrument():
    return virtspec_mi.find_bench(virtspec_mi.instrument_scene({"type": "simple_dielectric"}))


@pytest.fixture(scope="module")
def trace(instrument):
    """``trace(theta, phi, sampling, rays, seed, beam)`` → the traced rays (cached)."""

    # The plugin module needs Mitsuba's variant, which find_bench has set.
    from virtspec_mi.kernel.tracer import ReadingPlan, trace_rays

    cache: dict = {}

    def run(theta: float, phi: float = 0.0, sampling: str = "jittered", rays: int = UNIFORMITY_RAYS,
            seed: int = 0, beam: str = "conical") -> dict:
        key = (theta, phi, sampling, rays, seed, beam)
        if key not in cache:
            cache[key] = trace_rays(instrument, ReadingPlan(551.0, theta, phi, rays), rays, seed=seed, beam=beam,
                                    sampling=sampling)
        return cache[key]

    return run


def emitter_coordinates(rays: dict, geometry: InstrumentGeometry, theta: float, phi: float) -> np.ndarray:
    """(x, y) of each ray's emitter point on its disk: (origin − D·ω)·e_u and ·e_v."""

    omega, e_u, e_v = incidence_frame(theta, phi)
    offset = rays["origin"].astype(np.float64) - geometry.distance * omega
    return np.stack([offset @ e_u, offset @ e_v], axis=1)


def disk_points(rays: dict, geometry: InstrumentGeometry, disk: str, theta: float, phi: float):
    """Disk points of one disk and its radius."""

    if disk == "emitter":
        return emitter_coordinates(rays, geometry, theta, phi), geometry.emitter_radius
    return rays["target"].astype(np.float64), geometry.specimen_radius


def equal_area_cells(points: np.ndarray, radius: float, rings: int = 8, sectors: int = 8) -> np.ndarray:
    """Cell index of each point: ``rings`` rings of equal area × ``sectors`` equal sectors."""

    area = (points**2).sum(axis=1) / radius**2
    ring = np.minimum((area * rings).astype(int), rings - 1)
    turn = np.mod(np.arctan2(points[:, 1], points[:, 0]) / (2.0 * math.pi), 1.0)
    sector = np.minimum((turn * sectors).astype(int), sectors - 1)
    return ring * sectors + sector


def incidence_angles(rays: dict) -> np.ndarray:
    """Incidence angle γ (degrees) of each ray, from its float32 end points in float64."""

    direction = rays["origin"].astype(np.float64)
    direction[:, :2] -= rays["target"].astype(np.float64)
    return np.degrees(np.arctan2(np.hypot(direction[:, 0], direction[:, 1]), direction[:, 2]))


# --- The incidence frame -----------------------------------------------------------------


@pytest.mark.parametrize("theta, phi", [(0.0, 0.0), (30.0, 40.0), (70.0, -120.0), (90.0, 200.0)])
def test_incidence_frame_is_a_right_handed_orthonormal_frame(theta, phi):
    omega, e_u, e_v = incidence_frame(theta, phi)
    frame = np.stack([e_u, e_v, omega])
    np.testing.assert_allclose(frame @ frame.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(np.cross(e_u, e_v), omega, atol=1e-15)
    t, p = math.radians(theta), math.radians(phi)
    np.testing.assert_allclose(omega, [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)],
                               atol=1e-15)
    assert e_v[2] == 0.0  # e_v stays in the specimen plane


# --- Uniform by area ---------------------------------------------------------------------


@pytest.mark.parametrize("disk", ["emitter", "specimen"])
@pytest.mark.parametrize("sampling", SAMPLINGS)
def test_disk_points_lie_in_their_disk(trace, instrument, sampling, disk):
    theta, phi = 30.0, 40.0
    rays = trace(theta, phi, sampling)
    points, radius = disk_points(rays, instrument.geometry, disk, theta, phi)
    slack = radius * 1e-6 + (FLOAT32_MM if disk == "emitter" else 0.0)
    assert np.hypot(points[:, 0], points[:, 1]).max() <= radius + slack
    if disk == "emitter":
        # Emitter points lie in the emitter's plane, perpendicular to ω at distance D.
        omega, _, _ = incidence_frame(theta, phi)
        height = rays["origin"].astype(np.float64) @ omega
        np.testing.assert_allclose(height, instrument.geometry.distance, atol=FLOAT32_MM)


@pytest.mark.parametrize("disk", ["emitter", "specimen"])
@pytest.mark.parametrize("sampling", SAMPLINGS)
def test_disk_points_pass_equal_area_chi_square(trace, instrument, sampling, disk):
    # 8 rings of equal area × 8 sectors; expected 3125 rays per cell. One-sided: only a large
    # χ² (p < 1e-4) rejects. The stratified (jittered) emitter gives a tiny χ², as it should.
    theta, phi = 30.0, 40.0
    points, radius = disk_points(trace(theta, phi, sampling), instrument.geometry, disk, theta, phi)
    counts = np.bincount(equal_area_cells(points, radius), minlength=64)
    assert counts.sum() == UNIFORMITY_RAYS
    assert stats.chisquare(counts).pvalue > SIGNIFICANCE


@pytest.mark.parametrize("disk", ["emitter", "specimen"])
@pytest.mark.parametrize("sampling", SAMPLINGS)
def test_disk_points_have_uniform_radial_moments(trace, instrument, sampling, disk):
    # Uniform by area: r²/R² ~ U(0, 1), so E[r²] = R²/2 (sd R²/√12) and P(r < R/2) = 1/4.
    theta, phi = 30.0, 40.0
    points, radius = disk_points(trace(theta, phi, sampling), instrument.geometry, disk, theta, phi)
    r2 = (points**2).sum(axis=1)
    n = len(r2)
    assert abs(r2.mean() - radius**2 / 2) < 5.0 * radius**2 / math.sqrt(12.0 * n)
    inner = np.mean(r2 < radius**2 / 4)
    assert abs(inner - 0.25) < 5.0 * math.sqrt(0.25 * 0.75 / n)


@pytest.mark.parametrize("sampling", SAMPLINGS)
def test_emitter_and_specimen_points_are_independent(trace, instrument, sampling):
    # Joint χ² over 16 emitter cells × 16 specimen cells (expected 781 per cell): a shared
    # or correlated random stream between the two disks would fail here.
    theta, phi = 30.0, 40.0
    rays = trace(theta, phi, sampling)
    emitter, r1 = disk_points(rays, instrument.geometry, "emitter", theta, phi)
    specimen, r2 = disk_points(rays, instrument.geometry, "specimen", theta, phi)
    joint = equal_area_cells(emitter, r1, 4, 4) * 16 + equal_area_cells(specimen, r2, 4, 4)
    assert stats.chisquare(np.bincount(joint, minlength=256)).pvalue > SIGNIFICANCE


# --- The cone of incidence ---------------------------------------------------------------


@pytest.mark.parametrize("sampling", SAMPLINGS)
@pytest.mark.parametrize("theta", [0.0, 30.0, 70.0, 85.0])
def test_incidence_angles_fill_the_cone_the_geometry_allows(trace, sampling, theta):
    rays = trace(theta, 0.0, sampling, CONE_RAYS, seed=2)
    gamma = incidence_angles(rays)
    exact = incidence_angle_range(theta)
    low, high = exact.enclosure
    # float32 end points move γ by < FLOAT32_MM / (D − r1 − r2) rad ≈ 7e-6°.
    assert low - 1e-4 <= gamma.min() and gamma.max() <= high + 1e-4
    # ...and come close to both ends: 10⁶ rays get within 0.1° (max) and 0.2° (min) here.
    assert exact.high - gamma.max() < 0.2
    assert gamma.min() - exact.low < 0.3


@pytest.mark.parametrize("theta", [0.0, 30.0, 70.0, 85.0])
def test_rays_stay_within_the_proven_cone_about_the_emitter_axis(trace, theta):
    rays = trace(theta, 0.0, "jittered", CONE_RAYS, seed=2)
    omega, _, _ = incidence_frame(theta, 0.0)
    direction = rays["origin"].astype(np.float64)
    direction[:, :2] -= rays["target"].astype(np.float64)
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    angle = np.degrees(np.arccos(np.clip(direction @ omega, -1.0, 1.0)))
    assert angle.max() <= cone_half_angle_bound() + 1e-4


@pytest.mark.parametrize("sampling", SAMPLINGS)
def test_incident_direction_points_from_the_specimen_point_to_the_emitter_point(trace, sampling):
    rays = trace(70.0, 0.0, sampling)
    direction = rays["origin"].astype(np.float64)
    direction[:, :2] -= rays["target"].astype(np.float64)
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    np.testing.assert_allclose(rays["wi"], direction, atol=1e-6)


# --- Back-lit emitter --------------------------------------------------------------------


def test_backlit_threshold_of_the_paper():
    geometry = InstrumentGeometry()
    assert geometry.backlit_threshold == pytest.approx(math.degrees(math.atan(100.0 / 8.0)), abs=1e-12)
    assert geometry.backlit_threshold == pytest.approx(85.43, abs=5e-3)


@pytest.mark.parametrize("theta", [0.0, 30.0, 70.0, 85.0, 85.42])
def test_no_emitter_point_is_below_the_plane_before_the_threshold(trace, theta):
    assert backlit_fraction(InstrumentGeometry(), theta) == 0.0
    assert (trace(theta, 0.0, "random")["origin"][:, 2] > 0.0).all()


@pytest.mark.parametrize("theta", [85.5, 86.0, 88.0, 89.5, 90.0])
def test_backlit_fraction_matches_the_segment_quadrature(theta):
    # Independent value: the reference's emitter rule is split exactly at the plane.
    below = conical_average(lambda c: (c < 0.0).astype(float), theta)
    assert backlit_fraction(InstrumentGeometry(), theta) == pytest.approx(below, abs=1e-12)


@pytest.mark.parametrize("sampling", SAMPLINGS)
@pytest.mark.parametrize("theta", [88.0, 89.5, 90.0])
def test_backlit_fraction_matches_traced_rays(trace, sampling, theta):
    expected = backlit_fraction(InstrumentGeometry(), theta)
    below = np.mean(trace(theta, 0.0, sampling)["origin"][:, 2] < 0.0)
    assert abs(below - expected) < 5.0 * math.sqrt(expected * (1.0 - expected) / UNIFORMITY_RAYS)


def test_half_the_emitter_is_below_the_plane_at_grazing_incidence():
    assert backlit_fraction(InstrumentGeometry(), 90.0) == pytest.approx(0.5, abs=1e-12)


# --- Collimated beam ---------------------------------------------------------------------


@pytest.mark.parametrize("theta, phi", [(0.0, 0.0), (45.0, 30.0), (80.0, 200.0)])
def test_collimated_beam_is_one_direction_at_the_centre(trace, theta, phi):
    rays = trace(theta, phi, rays=10_000, beam="collimated")
    omega, _, _ = incidence_frame(theta, phi)
    np.testing.assert_allclose(rays["wi"], np.broadcast_to(omega, rays["wi"].shape), atol=1e-7)
    np.testing.assert_array_equal(rays["target"], 0.0)
