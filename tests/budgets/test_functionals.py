"""Linear functionals: Hoeffding's tolerance of a weighted sum and the allocation Nₖ ∝ |wₖ| (issue 30)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.applications.targets.bands import SENTINEL_2, band, quadrature_weights
from virtspec_mi.budgets.functionals import (Functional, allocate, certified_tolerance,
                                                          hoeffding_tolerance, union_delta)
from virtspec_mi.budgets.bounds import hoeffding_rays


def test_a_single_wavelength_functional_is_one_reading_of_the_paper():
    """One weight of 1: eq. (1) is the paper's Hoeffding bound N = ln(2/δ)/(2μ²)."""

    rays = allocate(np.array([1.0]), 0.005, 0.01)
    assert rays[0] == hoeffding_rays(0.005, 0.01)
    assert hoeffding_tolerance(np.array([1.0]), rays, 0.01) <= 0.005


def test_the_proportional_allocation_costs_one_reading_at_t_over_the_total_weight():
    rng = np.random.default_rng(0)
    weights = rng.uniform(-1, 3, 50)
    weights[::7] = 0
    rays = allocate(weights, 0.01, 0.05)
    assert np.all(rays[weights == 0] == 0) and np.all(rays[weights != 0] >= 1)
    assert hoeffding_tolerance(weights, rays, 0.05) <= 0.01
    one_reading = math.log(2 / 0.05) / (2 * (0.01 / np.abs(weights).sum()) ** 2)
    assert rays.sum() <= one_reading + np.count_nonzero(weights)  # + one ray each from rounding up
    uniform = np.full(50, rays.sum() // 50)  # the same rays spread evenly certify less
    assert hoeffding_tolerance(weights, uniform, 0.05) > hoeffding_tolerance(weights, rays, 0.05)


def test_shared_rays_and_the_union_and_errors():
    weights = np.array([0.2, 0.3, 0.5])
    assert hoeffding_tolerance(weights, np.full(3, 1000), 0.1, shared=True) == pytest.approx(
        math.sqrt(math.log(20) / 2000))
    assert union_delta(0.01, 4) == 0.0025
    assert hoeffding_tolerance(weights, np.array([0, 10, 10]), 0.1) == math.inf
    f = Functional("f", np.array([500.0, 510.0]), np.array([0.5, 0.5]))
    assert certified_tolerance(f, np.array([100, 100]), 0.1, rounding=np.array([1e-3, 0])) == pytest.approx(
        hoeffding_tolerance(f.weights, np.array([100, 100]), 0.1) + 5e-4)
    with pytest.raises(ValueError, match="tolerance must be a positive number"):
        allocate(weights, 0.0, 0.1)
    with pytest.raises(ValueError, match="quantity must be one of"):
        Functional("f", np.array([500.0]), np.array([1.0]), "radiance")


def test_bands_are_normalised_trapezoid_weights(tmp_path):
    red = band("B04")
    centre, width = SENTINEL_2["B04"]
    assert red.edges == (pytest.approx(centre - width / 2), pytest.approx(centre + width / 2))
    f = red.functional()
    assert f.weights.sum() == pytest.approx(1.0) and f.value(np.full(len(f.weights), 0.3)) == pytest.approx(0.3)
    file = tmp_path / "srf.csv"
    file.write_text("# wavelength, response\n600, 0\n610, 0.5\n620, 1\n630, 0.5\n640, 0\n")
    from_file = band(file).functional()
    assert from_file.name == "band_srf" and list(from_file.wavelengths) == [610, 620, 630]
    assert from_file.value(from_file.wavelengths) == pytest.approx(620.0)  # a symmetric response: its centre
    assert band({600: 0, 610: 0.5, 620: 1, 630: 0.5, 640: 0}).functional().weights == pytest.approx(from_file.weights)
    assert quadrature_weights(np.array([1.0, 2.0, 4.0])) == pytest.approx([0.5, 1.5, 1.0])
    with pytest.raises(ValueError, match="response must be a Sentinel-2 band"):
        band("B99")
    with pytest.raises(ValueError, match="somewhere > 0"):
        band({600: 0.0, 610: 0.0})


def test_the_joint_allocation_meets_every_tolerance_with_fewer_rays_than_the_largest_of_each():
    from virtspec_mi.colorimetry.certified import tristimulus_weights
    from virtspec_mi.budgets.functionals import allocate_jointly

    weights = tristimulus_weights(np.arange(400, 781, 10.0))
    tolerances, delta = np.array([0.014, 0.015, 0.025]), 0.01 / 3
    joint = allocate_jointly(weights, tolerances, delta)
    each = np.max([allocate(w, t, delta) for w, t in zip(weights, tolerances)], axis=0)
    assert all(hoeffding_tolerance(w, joint, delta) <= t for w, t in zip(weights, tolerances))
    assert joint.sum() < 0.9 * each.sum()
    assert np.array_equal(allocate_jointly(weights[:1], tolerances[:1], delta), allocate(weights[0], 0.014, delta))
