"""
Goniophotometer bins (virtspec_mi.instruments.goniophotometer.bins): layouts, projected solid angles,
bad specifications.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.instruments.goniophotometer.bins import MAX_BINS, make_bins, parse_edges


def test_uniform_bins_cover_both_hemispheres_with_90_as_an_edge():
    bins = make_bins(9, 12)
    assert bins.shape == (18, 12) and bins.size == 216
    assert np.allclose(bins.theta_edges, np.arange(0, 181, 10))
    assert np.allclose(bins.phi_edges, np.arange(0, 361, 30))
    assert list(bins.transmitted) == [False] * 9 + [True] * 9


def test_projected_bins_have_equal_projected_solid_angles_summing_to_pi_per_hemisphere():
    bins = make_bins(7, 5, "projected")
    omega = bins.projected_solid_angles()
    assert np.allclose(omega, np.pi / 35)
    assert np.isclose(omega[:7].sum(), np.pi) and np.isclose(omega[7:].sum(), np.pi)
    assert np.allclose(np.sin(np.radians(bins.theta_edges[:8])) ** 2, np.arange(8) / 7)


def test_folded_bins_cover_half_the_azimuth_with_doubled_solid_angle():
    bins = make_bins(9, 6, fold_phi=True)
    assert np.isclose(bins.phi_edges[-1], 180.0)
    assert np.isclose(bins.projected_solid_angles().sum(), 2 * np.pi)


def test_hemispheres_and_given_edges():
    assert np.allclose(make_bins(3, 1, hemispheres="reflection").theta_edges, [0, 30, 60, 90])
    assert np.allclose(make_bins(3, 1, hemispheres="transmission").theta_edges, [90, 120, 150, 180])
    bins = make_bins("0 20 90 180", "0:360:90")
    assert bins.binning == "edges" and bins.shape == (3, 4)
    assert parse_edges("theta_o_bins", "18") == 18
    assert np.allclose(parse_edges("phi_o_bins", "0,90, 180"), [0, 90, 180])


@pytest.mark.parametrize("kwargs, name", [
    ({"theta_o_bins": 0}, "theta_o_bins"),
    ({"theta_o_bins": 40000}, "theta_o_bins"),
    ({"theta_o_bins": [0, 100, 180]}, "theta_o_bins"),  # straddles 90
    ({"theta_o_bins": [0, 50, 40]}, "theta_o_bins"),
    ({"theta_o_bins": [0, 200]}, "theta_o_bins"),
    ({"theta_o_bins": "a b"}, "theta_o_bins"),
    ({"theta_o_bins": True}, "theta_o_bins"),
    ({"phi_o_bins": 0}, "phi_o_bins"),
    ({"phi_o_bins": [0, 400]}, "phi_o_bins"),
    ({"phi_o_bins": [0, 270], "fold_phi": True}, "phi_o_bins"),
    ({"binning": "log"}, "binning"),
    ({"hemispheres": "upper"}, "hemispheres"),
    ({"fold_phi": "maybe"}, "fold_phi"),
    ({"theta_o_bins": 32768, "phi_o_bins": 64}, "theta_o_bins x phi_o_bins"),
])
def test_bad_bin_specifications_name_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=name):
        make_bins(**kwargs)


def test_too_many_bins_is_refused():
    assert 32768 * 2 * 64 > MAX_BINS


def test_round_trip_of_the_bins_as_plain_data():
    from virtspec_mi.instruments.goniophotometer.bins import GonioBins

    bins = make_bins(5, 7, "projected", True, "reflection")
    again = GonioBins.from_dict(bins.as_dict())
    assert np.array_equal(again.theta_edges, bins.theta_edges) and again.regular_theta == bins.regular_theta
    assert again.fold_phi and again.regular_phi
