"""Tests of virtspec_mi.plugins.bsdfs.bsdf_table (reading/validating goniophotometer tables) and
virtspec_mi.references.analytic_tables (tables of analytic models by NumPy quadrature)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.references.analytic_tables import (
    equal_projected_edges,
    lambertian_table,
    phong_model,
    quadrature_table,
    sample_counts,
    uniform_edges,
)
from virtspec_mi.plugins.bsdfs.bsdf_table import BSDFTable, projected_solid_angles, read_table, table_dataset


def test_projected_solid_angles_cover_pi_per_hemisphere():
    edges = np.array([0.0, 10.0, 45.0, 90.0, 120.0, 180.0])
    phi = uniform_edges(0.0, 360.0, 7)
    omega = projected_solid_angles(edges[:-1], edges[1:], phi[:-1], phi[1:])
    assert omega[:3].sum() == pytest.approx(math.pi, rel=1e-12)
    assert omega[3:].sum() == pytest.approx(math.pi, rel=1e-12)
    folded = projected_solid_angles(edges[:-1], edges[1:], np.array([0.0]), np.array([180.0]), folded=True)
    np.testing.assert_allclose(folded[:, 0], omega.sum(axis=1), rtol=1e-12)


def test_equal_projected_edges_give_lambertian_bins_equal_shares():
    table = lambertian_table(0.6, 0.3, theta_o_edges=equal_projected_edges(5), phi_o_edges=uniform_edges(0, 360, 8))
    reflected = table.fraction[0, 0, :5]
    transmitted = table.fraction[0, 0, 5:]
    np.testing.assert_allclose(reflected, 0.6 / 40, rtol=1e-12)
    np.testing.assert_allclose(transmitted, 0.3 / 40, rtol=1e-12)
    np.testing.assert_allclose(table.brdf[0, 0, :5], 0.6 / math.pi, rtol=1e-12)
    np.testing.assert_allclose(table.brdf[0, 0, 5:], 0.3 / math.pi, rtol=1e-12)
    assert table.reflectance[0, 0] == pytest.approx(0.6, rel=1e-12)
    assert table.transmittance[0, 0] == pytest.approx(0.3, rel=1e-12)


def test_quadrature_of_a_lambertian_model_is_the_exact_table():
    edges, phi = uniform_edges(0, 180, 12), uniform_edges(0, 360, 9)
    exact = lambertian_table(0.4, 0.25, theta_i=[0, 40], theta_o_edges=edges, phi_o_edges=phi)
    numeric = quadrature_table(phong_model(specular=0.0, diffuse=0.4, diffuse_transmission=0.25),
                               theta_i=[0, 40], theta_o_edges=edges, phi_o_edges=phi, nodes=3)
    np.testing.assert_allclose(numeric.fraction, exact.fraction, rtol=1e-12)


def test_phong_lobe_total_is_its_albedo_at_normal_incidence_and_less_when_cut_by_the_horizon():
    table = quadrature_table(phong_model(specular=0.3, exponent=20, diffuse=0.0, diffuse_transmission=0.0),
                             theta_i=[0, 80], theta_o_edges=equal_projected_edges(16), nodes=12)
    assert table.reflectance[0, 0] == pytest.approx(0.3, rel=1e-6)
    assert table.reflectance[0, 1] < 0.3
    # the lobe peaks in the mirror bin: φ relative 180°, θo ≈ θi
    k = np.unravel_index(np.argmax(table.brdf[0, 1]), table.brdf.shape[2:])
    assert table.theta_o_lower[k[0]] <= 80 <= table.theta_o_upper[k[0]]
    assert table.phi_o_lower[k[1]] <= 180 <= table.phi_o_upper[k[1]]


def test_folded_table_integrates_both_halves():
    model = phong_model(specular=0.3, exponent=10)
    unfolded = quadrature_table(model, theta_i=[50], phi_o_edges=uniform_edges(0, 360, 12), phi_i=0.0)
    folded = quadrature_table(model, theta_i=[50], phi_o_edges=uniform_edges(0, 180, 6), folded=True)
    # relative azimuth [a, b] folded = real bins [a, b] and [360 - b, 360 - a]
    np.testing.assert_allclose(folded.fraction[..., :], unfolded.fraction[..., :6] + unfolded.fraction[..., ::-1][..., :6],
                               rtol=1e-10)
    np.testing.assert_allclose(folded.reflectance, unfolded.reflectance, rtol=1e-12)


def test_dataset_round_trip_memory_and_netcdf(tmp_path):
    table = quadrature_table(phong_model(), wavelength=[450, 650], theta_i=[0, 30, 60])
    counts = sample_counts(table, 100_000, seed=3)
    dataset = table_dataset(table, 100_000, counts)
    assert dataset["bin_counts"].dtype == np.int64 and dataset["rays"].dtype == np.int64
    assert dataset["brdf"].attrs["units"] == "1/sr"
    read = read_table(dataset)
    np.testing.assert_array_equal(read.fraction, counts / 100_000)
    path = tmp_path / "table.nc"
    dataset.to_netcdf(path)
    again = read_table(path)
    np.testing.assert_array_equal(again.fraction, read.fraction)
    assert again.digest == read.digest and again.phi_folded is False


def test_sample_counts_are_multinomial_within_the_bound():
    table = lambertian_table(0.5, 0.2)
    counts = sample_counts(table, 50_000, seed=1)
    assert counts.sum() <= 50_000
    # each bin fraction within Hoeffding's μ at δ = 1e-6/K (union over the K bins)
    mu = math.sqrt(math.log(2 * counts.size / 1e-6) / (2 * 50_000))
    assert np.all(np.abs(counts / 50_000 - table.fraction) < mu)


def _good() -> "object":
    return table_dataset(lambertian_table(0.5, 0.2, theta_i=[0, 45]), 1000)


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda d: d.drop_vars("bin_counts"), "bin_counts"),
        (lambda d: d.drop_vars("brdf"), "brdf"),
        (lambda d: d.drop_vars("rays"), "rays"),
        (lambda d: d.assign(rays=d["rays"] * 0), "rays must be >= 1"),
        (lambda d: d.assign(bin_counts=d["bin_counts"] * 10), "must not exceed rays"),
        (lambda d: d.assign(bin_counts=d["bin_counts"].astype(float)), "integers"),
        (lambda d: d.assign(brdf=d["brdf"] * 2), "brdf must equal"),
        (lambda d: d.assign_attrs(phi_folded=2), "phi_folded"),
        (lambda d: d.assign_coords(theta_i=[0.0, 95.0]), "theta_i must lie in"),
        (lambda d: d.assign_coords(theta_i=[45.0, 0.0]), "strictly increasing"),
        (lambda d: d.assign_coords(theta_o_upper=("theta_o", d["theta_o_upper"].values + 1)), "contiguous"),
    ],
)
def test_bad_tables_raise_value_error_naming_the_variable(edit, message):
    with pytest.raises(ValueError, match=message):
        read_table(edit(_good()))


def test_bin_straddling_90_and_edges_out_of_range_are_refused():
    base = lambertian_table(0.5)
    values = dict(wavelength=base.wavelength, theta_i=base.theta_i, phi_o_lower=base.phi_o_lower,
                  phi_o_upper=base.phi_o_upper)
    with pytest.raises(ValueError, match="straddle 90"):
        BSDFTable(**values, theta_o_lower=np.array([0.0, 80.0]), theta_o_upper=np.array([80.0, 100.0]),
                  fraction=np.zeros((1, 1, 2, 4)))
    with pytest.raises(ValueError, match=r"theta_o bin edges must lie in \[0, 180\]"):
        BSDFTable(**values, theta_o_lower=np.array([0.0, 90.0]), theta_o_upper=np.array([90.0, 190.0]),
                  fraction=np.zeros((1, 1, 2, 4)))
    with pytest.raises(ValueError, match="sum to at most 1"):
        BSDFTable(**values, theta_o_lower=np.array([0.0]), theta_o_upper=np.array([90.0]),
                  fraction=np.full((1, 1, 1, 4), 0.3))
    with pytest.raises(ValueError, match=r"fraction must have shape"):
        BSDFTable(**values, theta_o_lower=np.array([0.0]), theta_o_upper=np.array([90.0]),
                  fraction=np.zeros((1, 1, 2, 4)))


def test_folded_tables_need_edges_within_180():
    with pytest.raises(ValueError, match=r"phi_o bin edges must lie in \[0, 180\]"):
        lambertian_table(0.5, folded=True, phi_o_edges=uniform_edges(0, 360, 4))


def test_not_a_dataset_and_missing_file():
    with pytest.raises(ValueError, match="xarray.Dataset"):
        read_table(42)
    with pytest.raises(ValueError, match="not a file"):
        read_table("/nonexistent/table.nc")


def test_gonio_variants_scalar_labels_phi_i_coordinate_and_to_dataset():
    """One reading's scalar θi label, φi as a coordinate of one value, an object with to_dataset()."""

    table = lambertian_table(0.5, 0.2, theta_i=[30.0], phi_i=0.0)
    dataset = table_dataset(table, 10**6)
    single = dataset.squeeze("theta_i")  # theta_i a scalar label, as in a single reading
    single.attrs.pop("phi_i")
    single = single.expand_dims(phi_i=[15.0])  # a dim of one value
    read = read_table(single)
    assert read.theta_i.tolist() == [30.0] and read.phi_i == 15.0
    np.testing.assert_array_equal(read.fraction, read_table(dataset).fraction)

    class Reading:
        def to_dataset(self):
            return dataset

    assert read_table(Reading()).digest == read_table(dataset).digest
