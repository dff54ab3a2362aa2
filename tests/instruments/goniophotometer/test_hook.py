"""
Tests of :mod:`virtspec_mi.instruments.goniophotometer.hook`: a ray's outgoing direction to its bin, in Dr.Jit.

Every layout — θo uniform or projected (found arithmetically), given edges (searched), one
hemisphere or both, φo over [0, 360) or folded about φi, equal or given — bins random
directions (fixed seed) exactly as NumPy does from the definitions (θo = acos z, φo =
atan2(y, x), bins by ``searchsorted``), keeping away from edges by a margin far above float32
rounding; the hemisphere is the ray's fate; an absorbed ray, or one outside the bins, gets
code K. :func:`search_edges` closes the last bin and sends keys outside the edges beyond the
bins. The pairing puts the two bins beside the mirror azimuth in one word. The RGL cells
(:class:`~virtspec_mi.instruments.goniophotometer.hook.WarpedLayout`) are tested in ``test_warped.py``.

References
----------
Nicodemus et al. (1977), NBS Monograph 160.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.instruments.goniophotometer.bins import make_bins
from virtspec_mi.instruments.goniophotometer.hook import BinLayout, search_edges
from virtspec_mi.kernel.counts import Fate

N = 20_000
MARGIN = 1e-3  # degrees (and units of sin²θ) kept from every edge: far above float32 rounding


def directions(seed: int = 0) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=(N, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def expected_bins(bins, wo: np.ndarray, fate: np.ndarray, phi_i: float) -> tuple[np.ndarray, np.ndarray]:
    """The flat bin by the definitions, and which rays lie at least MARGIN from every edge."""

    theta = np.degrees(np.arccos(np.clip(wo[:, 2], -1, 1)))
    phi = np.degrees(np.arctan2(wo[:, 1], wo[:, 0])) % 360.0
    if bins.fold_phi:
        relative = (phi - phi_i) % 360.0
        phi = np.minimum(relative, 360.0 - relative)
    if bins.binning == "projected":  # edges uniform in sin²θ: compare in that coordinate
        s = np.sin(np.radians(theta)) ** 2
        key = np.where(theta <= 90.0, s, 2.0 - s)
        edges = np.sin(np.radians(bins.theta_edges)) ** 2
        edges = np.where(bins.theta_edges <= 90.0, edges, 2.0 - edges)
    else:
        key, edges = theta, bins.theta_edges
    t = np.searchsorted(edges, key, side="right") - 1
    p = np.searchsorted(bins.phi_edges, phi, side="right") - 1
    n_theta, n_phi = bins.shape
    hemisphere = np.where(fate == int(Fate.REFLECTED), theta <= 90.0, theta >= 90.0)
    inside = (t >= 0) & (t < n_theta) & (p >= 0) & (p < n_phi) & hemisphere & (fate != int(Fate.ABSORBED))
    flat = np.where(inside, t * n_phi + p, n_theta * n_phi)
    clear = (np.min(np.abs(key[:, None] - edges[None, :]), axis=1) > MARGIN) & \
        (np.min(np.abs(phi[:, None] - bins.phi_edges[None, :]), axis=1) > MARGIN)
    return flat, clear


def kernel_bins(mi, layout: BinLayout, wo: np.ndarray, fate: np.ndarray, phi_i: float) -> np.ndarray:
    codes = layout.bin(mi.Vector3f(*(wo[:, k].astype(np.float32) for k in range(3))), mi.UInt32(fate),
                       mi.Float(phi_i))
    return np.array(codes, dtype=np.int64)


@pytest.mark.parametrize("spec", [
    dict(theta_o_bins=9, phi_o_bins=12),
    dict(theta_o_bins=6, phi_o_bins=8, binning="projected"),
    dict(theta_o_bins=[0, 10, 35, 60, 90, 120, 170], phi_o_bins=[0, 30, 90, 200, 360]),
    dict(theta_o_bins=5, phi_o_bins=6, fold_phi=True),
    dict(theta_o_bins=[20, 40, 80], phi_o_bins=[10, 60, 150], fold_phi=True),
    dict(theta_o_bins=4, phi_o_bins=10, hemispheres="reflection"),
    dict(theta_o_bins=4, phi_o_bins=10, hemispheres="transmission", binning="projected"),
])
def test_every_layout_bins_as_the_definitions(mi, spec):
    bins = make_bins(**spec)
    layout = bins.layout()
    wo = directions()
    # the fate is the hemisphere of the direction, with a share absorbed
    fate = np.where(wo[:, 2] > 0, int(Fate.REFLECTED), int(Fate.TRANSMITTED))
    fate[::7] = int(Fate.ABSORBED)
    phi_i = 37.5
    expected, clear = expected_bins(bins, wo, fate, phi_i)
    codes = kernel_bins(mi, layout, wo, fate, phi_i)
    assert clear.mean() > 0.95
    np.testing.assert_array_equal(codes[clear], expected[clear])
    assert np.all(codes[fate == int(Fate.ABSORBED)] == layout.size)
    assert layout.size == bins.shape[0] * bins.shape[1]


def test_the_hemisphere_is_the_fate_even_at_grazing_exits(mi):
    layout = make_bins(theta_o_bins=3, phi_o_bins=4).layout()
    grazing = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 1e-9], [0.0, 1.0, -1e-9]])
    fate = np.array([int(Fate.REFLECTED), int(Fate.TRANSMITTED), int(Fate.REFLECTED), int(Fate.TRANSMITTED)])
    codes = kernel_bins(mi, layout, grazing, fate, 0.0)
    n_phi = 4
    assert codes[0] // n_phi == 2 and codes[1] // n_phi == 3  # the last bin above, the first below the horizon
    assert codes[2] // n_phi == 2 and codes[3] // n_phi == 3


def test_search_edges_closes_the_last_bin(mi):
    edges = np.array([0.0, 1.0, 2.5, 4.0], dtype=np.float32)
    keys = mi.Float([-0.5, 0.0, 0.999, 1.0, 3.0, 4.0, 4.5])
    found = np.array(search_edges(edges, keys), dtype=np.int64)
    assert found[1:6].tolist() == [0, 0, 1, 2, 2]
    assert found[0] >= 3 and found[6] >= 3  # outside: beyond the bins


def test_the_pairing_puts_the_mirror_bins_in_one_word():
    layout = make_bins(theta_o_bins=3, phi_o_bins=12).layout()  # edges every 30 degrees
    for phi_i in (0.0, 30.0, 50.0, 90.0, 200.0):  # no mirror azimuth halfway between two edges
        mirror_edge = int(round(((phi_i + 180.0) % 360.0) / 30.0))
        pairing = layout.pairing(phi_i)
        if mirror_edge in (0, 12):
            assert pairing == 0
        else:  # bins e-1 and e share the word (2m - p, 2m + 1 - p)
            first = mirror_edge - 1
            assert (first + pairing) % 2 == 0
    assert make_bins(theta_o_bins=3, phi_o_bins=6, fold_phi=True).layout().pairing(45.0) == 0
