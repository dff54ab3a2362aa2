"""
Tests of :mod:`virtspec_mi.instruments.goniophotometer.result`: a goniophotometer reading.

A Lambertian reflector (ρ = 0.5) read on bins of equal projected solid angle: every bin's
simultaneous Clopper–Pearson interval of the BRDF holds ρ/π (fixed seed, δ = 0.05 for all
bins together); the bins' counts and the rays outside them add up to the reading's escaped
rays, the fractions are m/N, the BRDF m/(NΩ), the empirical CDFs rise to the binned share;
the certificate and the files say and keep the same.

References
----------
Nicodemus et al. (1977), NBS Monograph 160; Clopper & Pearson (1934).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments.goniophotometer.result import GonioResult

RHO = 0.5


@pytest.fixture(scope="module")
def reading(mi):
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": RHO})
    return vm.gonio(scene, theta_i=[0, 40], wavelengths=[550], theta_o_bins=4, phi_o_bins=6, binning="projected",
                    hemispheres="reflection", beam="collimated", rays=20_000, delta=0.05, seed=2)


def test_every_bins_interval_holds_the_lambertian_brdf(reading):
    assert isinstance(reading, GonioResult) and reading.size == 24
    assert np.all(reading.brdf_lower <= RHO / math.pi) and np.all(RHO / math.pi <= reading.brdf_upper)
    np.testing.assert_allclose(reading.solid_angles, math.pi / 24)  # equal projected bins over the hemisphere


def test_counts_fractions_and_brdf(reading):
    counts = reading.bin_counts
    assert counts.dtype == np.int64 and counts.shape == (1, 2, 4, 6)
    escaped = np.asarray(reading.result.reflected) + np.asarray(reading.result.transmitted)
    np.testing.assert_array_equal(counts.sum(axis=(-2, -1)) + reading.outside, escaped)
    assert np.all(reading.outside == 0)  # nothing transmitted, every reflected ray binned
    np.testing.assert_allclose(reading.fraction, counts / 20_000)
    np.testing.assert_allclose(reading.brdf, counts / 20_000 / (math.pi / 24))
    np.testing.assert_array_equal(reading.rays, 20_000)
    np.testing.assert_array_equal(reading.theta_i, [0.0, 40.0])
    assert reading.theta_o.shape == (4,) and reading.phi_o.shape == (6,)


def test_the_cdfs_rise_to_the_binned_share(reading):
    cdf = reading.cdf_theta_o
    assert cdf.shape == (1, 2, 5) and np.all(cdf[..., 0] == 0) and np.all(np.diff(cdf, axis=-1) >= 0)
    np.testing.assert_allclose(cdf[..., -1], reading.bin_counts.sum(axis=(-2, -1)) / 20_000)
    np.testing.assert_allclose(reading.cdf_phi_o[..., -1], cdf[..., -1])
    assert np.all(reading.cdf_mu > 0) and np.all(reading.bins_mu > 0)


def test_the_certificate_and_the_files(reading, tmp_path):
    certificate = reading.certificate()
    assert certificate.startswith("N = 20,000 rays per reading, K = 24 bins (rays given), each statement with "
                                  "probability >= 0.95 per reading:")
    assert "each at delta/K = 0.00208" in certificate  # 0.05 / 24
    # the union bound's mu at delta/K, sqrt(ln(2K/delta)/(2N)) = 0.01310, printed rounded up (never narrower)
    np.testing.assert_allclose(reading.bins_mu, math.sqrt(math.log(2 * 24 / 0.05) / (2 * 20_000)), rtol=1e-9)
    assert "every bin fraction at once: |m_k/N - p_k| < 0.0132 (union bound over K)" in certificate
    for suffix in (".nc", ".json"):
        back = vm.read_result(reading.write(tmp_path / f"gonio{suffix}"))
        assert isinstance(back, GonioResult)
        np.testing.assert_array_equal(back.bin_counts, reading.bin_counts)
        np.testing.assert_allclose(back.brdf_upper, reading.brdf_upper)


def test_a_bins_spectrum(mi):
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": RHO})
    reading = vm.gonio(scene, theta_i=0, wavelengths=[500, 600], theta_o_bins=2, phi_o_bins=2, rays=4000,
                       beam="collimated", seed=1)
    sd = reading.to_sd(theta_o=30.0, phi_o=90.0)  # theta_o bin 0 (0-45 deg), phi_o bin 0 (0-180 deg)
    np.testing.assert_allclose(sd.values, reading.brdf[:, 0, 0, 0])
    assert list(sd.wavelengths) == [500.0, 600.0]
    with pytest.raises(ValueError, match=r"to_sd of one bin needs theta_o and phi_o"):
        reading.to_sd(theta_o=30.0)
