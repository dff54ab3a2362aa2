"""
Tests of :mod:`virtspec_mi.exchange.klems_basis`: the Klems angle bases.

The sizes are Klems's and Radiance's (145, 77, 41); the projected solid angles add up to π;
the patch rule (Radiance's ``fo_getndx``) puts every patch centre in its own patch and wraps
azimuths around 0; the φ grid of ``phi_bins`` puts every patch boundary on a bin edge, so
the aggregation gives every bin exactly one patch and the bins of a patch add up to its
projected solid angle; edges that straddle a patch are refused with the edges they need.

References
----------
Klems (1994), ASHRAE Transactions 100(1), 1065–1072; Ward, the Radiance BSDF library
(``bsdf_m.c``: ``abase_list``, ``fo_getndx``).
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.exchange.klems_basis import BASES, klems_basis
from virtspec_mi.plugins.bsdfs.bsdf_table import projected_solid_angles


@pytest.mark.parametrize("key, size, name, bins", [("full", 145, "LBNL/Klems Full", 480),
                                                   ("half", 77, "LBNL/Klems Half", 480),
                                                   ("quarter", 41, "LBNL/Klems Quarter", 48)])
def test_sizes_names_and_phi_grids(key, size, name, bins):
    basis = klems_basis(key)
    assert basis.size == size and basis.name == name == BASES[key][0] and basis.key == key
    assert basis.phi_bins() == bins
    assert all(bins % (2 * n) == 0 for n in basis.phis)
    assert basis.ring.size == basis.index_in_ring.size == basis.theta.size == basis.phi.size == size


@pytest.mark.parametrize("key", list(BASES))
def test_projected_solid_angles_add_up_to_pi(key):
    basis = klems_basis(key)
    omega = basis.projected_solid_angle
    assert omega.sum() == pytest.approx(np.pi, rel=1e-12)
    assert omega[0] == pytest.approx(np.pi * np.sin(np.radians(basis.upper[0])) ** 2)  # the cap
    assert np.all(omega > 0)


@pytest.mark.parametrize("key", list(BASES))
def test_every_patch_centre_is_in_its_own_patch(key):
    basis = klems_basis(key)
    np.testing.assert_array_equal(basis.patch_of(basis.theta, basis.phi), np.arange(basis.size))
    assert basis.theta[0] == 0.0 and np.all(basis.theta[1:] > 0)


def test_patch_rule_wraps_around_zero_and_marks_outside():
    basis = klems_basis("full")
    # ring 1 (5-15 deg, 8 patches of 45 deg centred on 0): 350 deg and 10 deg share patch 1
    assert basis.patch_of(10.0, 350.0) == basis.patch_of(10.0, 10.0) == 1
    assert basis.patch_of(10.0, 22.4) == 1 and basis.patch_of(10.0, 22.6) == 2
    assert basis.patch_of(4.99, 123.0) == 0 and basis.patch_of(5.0, 0.0) == 1
    assert basis.patch_of(90.0, 0.0) == 145 - 12
    np.testing.assert_array_equal(basis.patch_of([-1.0, 90.5], [0.0, 0.0]), [-1, -1])


def test_theta_edges_span_both_hemispheres():
    edges = klems_basis("quarter").theta_edges()
    np.testing.assert_array_equal(edges, [0, 9, 27, 45, 63, 90, 117, 135, 153, 171, 180])


@pytest.mark.parametrize("key, transmitted", [("full", False), ("half", True), ("quarter", False)])
def test_aggregation_gives_each_bin_one_patch_and_sums_the_solid_angle(key, transmitted):
    basis = klems_basis(key)
    theta_edges = basis.theta_edges()
    phi_edges = np.linspace(0.0, 360.0, basis.phi_bins() + 1)
    table = basis.aggregation(theta_edges, phi_edges, transmitted)
    hemisphere = (theta_edges[1:] > 90.0) if transmitted else (theta_edges[1:] <= 90.0)
    assert np.all(table[~hemisphere] == -1) and np.all(table[hemisphere] >= 0)
    omega = projected_solid_angles(theta_edges[:-1], theta_edges[1:], phi_edges[:-1], phi_edges[1:])
    per_patch = np.bincount(table[hemisphere].ravel(), weights=omega[hemisphere].ravel(), minlength=basis.size)
    np.testing.assert_allclose(per_patch, basis.projected_solid_angle, rtol=1e-9)


def test_aggregation_refuses_bins_that_straddle_patches():
    basis = klems_basis("quarter")
    with pytest.raises(ValueError, match=r"theta_o_bins must have every LBNL/Klems Quarter ring bound as an edge "
                                         r"\(in both hemispheres: 0, 9, 27, 45, 63, 90, 117"):
        basis.aggregation(np.linspace(0.0, 180.0, 11), np.linspace(0.0, 360.0, 49), False)
    with pytest.raises(ValueError, match=r"phi_o_bins must put every LBNL/Klems Quarter patch boundary on a bin "
                                         r"edge \(e.g. 48 equal bins\)"):
        basis.aggregation(basis.theta_edges(), np.linspace(0.0, 360.0, 37), False)
    with pytest.raises(ValueError, match=r"phi_o_bins must cover \[0, 360\] without folding"):
        basis.aggregation(basis.theta_edges(), np.linspace(0.0, 180.0, 25), False)


def test_unknown_basis_is_refused():
    with pytest.raises(ValueError, match=r"basis must be one of full, half, quarter \(got 'eighth'\)"):
        klems_basis("eighth")
