"""
Conical-hemispherical readings against the quadrature reference.

A conical reading of the ``simple_dielectric`` specimen (diamond, η = 2.419) must
agree with :func:`virtspec_mi.references.quadrature.conical_reflectance`, the deterministic
average of the Fresnel reflectance over the instrument's emitter/specimen pairs.

Tolerance: each reading counts N = 10⁶ independent Bernoulli rays whose mean success
probability is the reference ρ (jittered rays are non-identical but independent, and
their probabilities average to ρ). Hoeffding's inequality gives
``P(|m/N − ρ| ≥ μ) ≤ 2·exp(−2Nμ²) = δ`` with ``μ = hoeffding_mu(N, δ)``; with
δ = 1e-6 that is μ ≈ 0.00269, so **each assertion below fails by chance with
probability < 1e-6** (the reference's quadrature error, < 1e-12, is negligible).
The seeds are fixed, so a run is reproducible.

The test discriminates: at θi = 70° the cone's reflectance differs from the
collimated F(70°) by more than μ, and at θi ≥ 88° the back-lit convention changes
the reflectance by far more than μ.

References
----------
Baranoski et al. (2001), eqs. (1), (2), (19)–(23), Sect. 5.1.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi
from virtspec_mi.budgets.bounds import hoeffding_mu
from virtspec_mi.references.quadrature import (
    conical_average,
    conical_reflectance,
    fresnel_reflectance,
    fresnel_reflectance_cos,
)

SAMPLINGS = ("jittered", "random", "concentric")
RAYS = 10**6
DELTA_TEST = 1e-6
# Hoeffding: |m/N − ρ| < MU with probability ≥ 1 − 1e-6, per assertion (eq. 19).
MU = hoeffding_mu(RAYS, DELTA_TEST)
DIAMOND = 2.419


@pytest.fixture(scope="module")
def scene():
    return virtspec_mi.load_scene(virtspec_mi.instrument_scene({"type": "simple_dielectric"}))


def conical_reading(scene, theta: float, sampling: str, seed: int):
    return virtspec_mi.measure(scene, theta_i=theta, beam="conical", sampling=sampling, seed=seed, rays=RAYS)


@pytest.mark.parametrize("sampling", SAMPLINGS)
@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 70.0, 80.0, 85.0])
def test_conical_reading_matches_reference(scene, theta, sampling):
    reading = conical_reading(scene, theta, sampling, seed=1000 + int(theta))
    assert reading.rays.tolist() == [RAYS]
    assert reading.backlit_fraction == 0.0
    expected = conical_reflectance(theta)
    assert abs(reading.reflectance[0] - expected) < MU
    assert reading.absorptance[0] == 0.0  # lossless, unit weights


def test_conical_tolerance_discriminates_the_cone_from_the_collimated_beam():
    # If the instrument ignored the cone (every ray at θi), the reading's expectation would
    # be F(θi): at 70° that is more than MU away from the conical value, so the test above
    # would fail (with probability > 1/2 already at the boundary) instead of passing.
    assert MU == pytest.approx(0.0026934, abs=1e-7)
    assert conical_reflectance(70.0) - float(fresnel_reflectance(70.0, DIAMOND)) > MU
    assert conical_reflectance(80.0) - float(fresnel_reflectance(80.0, DIAMOND)) > 3.0 * MU


def test_collimated_reading_matches_fresnel(scene):
    reading = virtspec_mi.measure(scene, theta_i=70.0, beam="collimated", seed=7, rays=RAYS)
    assert abs(reading.reflectance[0] - float(fresnel_reflectance(70.0, DIAMOND))) < MU


# --- Back-lit incidence ------------------------------------------------------------------


def reflectance_judged_by_face(theta: float) -> float:
    """
    The wrong convention: a back-lit ray that the back face reflects counts as reflected.

    ``F(γ, η)`` on the front face, ``F(π − γ, 1/η)`` on the back face (module docstring
    of :mod:`virtspec_mi.references.quadrature`, *Back-lit rays*, for the convention the integrator uses).
    """

    def by_face(c: np.ndarray) -> np.ndarray:
        return np.where(c >= 0.0, fresnel_reflectance_cos(np.abs(c), DIAMOND),
                        fresnel_reflectance_cos(np.abs(c), 1.0 / DIAMOND))

    return conical_average(by_face, theta)


@pytest.mark.parametrize("sampling", SAMPLINGS)
@pytest.mark.parametrize("theta", [89.0, 90.0])
def test_backlit_conical_reading_matches_reference(scene, theta, sampling):
    # Fates by world hemisphere: back-lit rays refracted upward count as reflected, those
    # reflected by the back face (all of them here: total internal reflection) as transmitted.
    reading = conical_reading(scene, theta, sampling, seed=2000 + int(theta))
    assert reading.backlit_fraction > 0.3
    expected = conical_reflectance(theta)
    assert abs(reading.reflectance[0] - expected) < MU
    assert abs(reading.transmittance[0] - (1.0 - expected)) < MU


@pytest.mark.parametrize("theta", [89.0, 90.0])
def test_backlit_tolerance_discriminates_the_conventions(theta):
    # Judging fates by the face struck, or ignoring the back face (taking |cos γ| as a
    # front-face hit), would move the expected reflectance by far more than MU.
    expected = conical_reflectance(theta)
    assert abs(reflectance_judged_by_face(theta) - expected) > 50.0 * MU
    front_everywhere = conical_average(lambda c: fresnel_reflectance_cos(np.abs(c), DIAMOND), theta)
    assert abs(front_everywhere - expected) > 50.0 * MU
