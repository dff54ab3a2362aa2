"""
Tests of :mod:`virtspec_mi.applications.klems.measure`: Klems matrices measured by the goniophotometer.

Sized by epsilon and delta, every incidence traces ⌈ln(2S/δ)/(2ε²)⌉ rays for the S statements
of the file (Hoeffding and the union bound); without a back side the file has one side; with
``isotropic`` the patches of a ring hold the ring's one reading rotated by whole bins, so a
rotation-invariant specimen's rings read the same totals; the counts of every incidence add up
to its rays; bad inputs are refused by name before any ray.
The file, its orientation and certificate are tested in ``test_matrices.py``.

References
----------
Klems (1994); Hoeffding (1963), eq. (2.3).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.applications.klems.measure import flipped, klems_measure
from virtspec_mi.exchange.klems_basis import klems_basis


def test_flipped_wraps_the_bsdf():
    assert flipped({"type": "diffuse"}) == {"type": "virtspec_flipped", "nested": {"type": "diffuse"}}


@pytest.fixture(scope="module")
def front(mi):
    return klems_measure("diamond_collimated", basis="quarter", back=False, epsilon=0.2, delta=0.2, isotropic=True,
                         seed=5, progress=False)


def test_rays_are_sized_by_hoeffding_and_the_union_bound(front):
    basis = klems_basis("quarter")
    statements = 1 * 1 * basis.size * (2 * basis.size + 2)  # one side, one wavelength
    expected = math.ceil(math.log(2 * statements / 0.2) / (2 * 0.2 ** 2))
    assert np.all(np.asarray(front.rays) == expected)
    assert tuple(front.sides) == ("front",)  # back=False: the front matrices only


def test_every_incidences_counts_add_up_to_what_left_it(front):
    counts = np.asarray(front.counts)  # (sides, wavelengths, incident patches, R/T, outgoing patches)
    np.testing.assert_array_equal(counts[:, :, :, 0].sum(axis=-1), np.asarray(front.reflected))
    np.testing.assert_array_equal(counts[:, :, :, 1].sum(axis=-1), np.asarray(front.transmitted))
    assert np.all(np.asarray(front.reflected) + np.asarray(front.transmitted) == np.asarray(front.rays))  # lossless


def test_isotropic_rings_repeat_their_reading(front):
    basis = klems_basis("quarter")
    reflected = np.asarray(front.reflected)[0, 0]
    for ring in range(len(basis.phis)):
        members = np.flatnonzero(basis.ring == ring)
        assert np.all(reflected[members] == reflected[members[0]]), ring


@pytest.mark.parametrize("keywords, message", [
    (dict(epsilon=0.5), r"epsilon must satisfy 0 < epsilon < 0.5 \(got 0.5\)"),
    (dict(epsilon="0.1"), r"epsilon"),
    (dict(delta=1.5), r"delta must satisfy 0 < delta < 1"),
    (dict(basis="eighth"), r"basis must be one of full, half, quarter \(got 'eighth'\)"),
    (dict(seed=-1), r"seed"),
    (dict(isotropic="yes"), r"isotropic"),
])
def test_bad_inputs_are_refused_by_name(mi, keywords, message):
    with pytest.raises(ValueError, match=message):
        klems_measure("diamond_collimated", back=False, progress=False, **keywords)
