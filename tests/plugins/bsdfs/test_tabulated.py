"""Tests of the ``tabulated`` BSDF plugin (plugins/bsdfs/tabulated.py): eval, pdf and sample
consistent with each other and with the table, chi-square tests of sample against pdf,
the spectrophotometer's R and T of a table, and a small ``mi.render``."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import virtspec_mi as vm
from virtspec_mi.references.analytic_tables import equal_projected_edges, lambertian_table, phong_model, quadrature_table, uniform_edges
from virtspec_mi.plugins.bsdfs.bsdf_table import table_dataset

WAVELENGTHS = [450.0, 650.0]
THETA_I = [0.0, 30.0, 60.0]


def _specular(wavelength: float) -> float:
    return 0.2 + 0.2 * (wavelength - 450.0) / 200.0  # 0.2 at 450 nm, 0.4 at 650 nm


@pytest.fixture(scope="module")
def phong():
    """A rough lobe + diffuse reflector/transmitter, wavelength dependent, 3 θi, 16 × 12 bins."""

    return quadrature_table(phong_model(specular=_specular, exponent=8, diffuse=0.2, diffuse_transmission=0.15),
                            wavelength=WAVELENGTHS, theta_i=THETA_I, phi_i=30.0)


@pytest.fixture(scope="module")
def folded():
    return quadrature_table(phong_model(specular=0.3, exponent=8), theta_i=THETA_I,
                            phi_o_edges=uniform_edges(0, 180, 6), folded=True)


def _interaction(mi, n, theta_deg, phi_deg=0.0, wavelengths=(450.0,), below=False):
    import drjit as dr

    si = dr.zeros(mi.SurfaceInteraction3f, n)
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    z = -math.cos(t) if below else math.cos(t)
    si.wi = mi.Vector3f(math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), z)
    lanes = list(wavelengths) + [wavelengths[-1]] * (4 - len(wavelengths))
    si.wavelengths = mi.Spectrum(*lanes)
    return si


def _sample(mi, bsdf, si, n, seed=1, ctx=None):
    u = np.random.default_rng(seed).random((3, n)).astype(np.float32)
    ctx = ctx or mi.BSDFContext()
    return bsdf.sample(ctx, si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))


def _bin_of(table, wo, wi_phi_deg):
    """Flattened bin index of local directions wo (NumPy, unfolded tables), -1 outside."""

    theta = np.degrees(np.arccos(np.clip(wo[2], -1, 1)))
    phi = (np.degrees(np.arctan2(wo[1], wo[0])) - wi_phi_deg + table.phi_i) % 360.0
    a = np.searchsorted(table.theta_o_upper, theta)
    b = np.searchsorted(table.phi_o_upper, phi)
    return a * table.shape[3] + b


def _row_mixture(table, wavelength, theta_i):
    """The bilinear mixture of the table's rows at (λ, θi): fractions over the flattened bins."""

    def weights(grid, x):
        if len(grid) == 1:
            return [(0, 1.0)]
        x = min(max(x, grid[0]), grid[-1])
        i = min(np.searchsorted(grid, x, side="right") - 1, len(grid) - 2)
        t = (x - grid[i]) / (grid[i + 1] - grid[i])
        return [(i, 1 - t), (i + 1, t)]

    flat = table.fraction.reshape(*table.shape[:2], -1)
    return sum(wl * wi * flat[l, i] for l, wl in weights(table.wavelength, wavelength)
               for i, wi in weights(table.theta_i, theta_i))


def test_loads_from_dict_and_from_netcdf_with_a_table_digest(mi, phong, tmp_path):
    bsdf = mi.load_dict(vm.tabulated_bsdf(phong))
    assert f"sha256={phong.digest}" in str(bsdf)
    assert bsdf.wavelength_independent is False
    path = tmp_path / "phong.nc"
    table_dataset(phong, 10**12).to_netcdf(path)
    from_file = mi.load_dict({"type": "tabulated", "filename": str(path)})
    assert "bins=16x12" in str(from_file)
    single = mi.load_dict(vm.tabulated_bsdf(lambertian_table(0.5)))
    assert single.wavelength_independent is True


def test_exactly_one_source_is_required(mi, phong):
    with pytest.raises(Exception, match="exactly one of 'filename'"):
        mi.load_dict({"type": "tabulated"})
    entry = vm.tabulated_bsdf(phong)
    del entry["theta_i"]
    with pytest.raises(Exception, match="'theta_i' is missing"):
        mi.load_dict(entry)
    with pytest.raises(Exception, match="not a file"):
        mi.load_dict({"type": "tabulated", "filename": "/nonexistent.nc"})


@pytest.mark.parametrize("theta_i, phi_wi, below", [(0.0, 0.0, False), (30.0, 75.0, False), (45.0, -20.0, False),
                                                     (60.0, 10.0, True), (85.0, 200.0, False)])
def test_sample_weight_is_eval_over_pdf_and_the_row_total(mi, phong, theta_i, phi_wi, below):
    bsdf = mi.load_dict(vm.tabulated_bsdf(phong))
    n = 20_000
    si = _interaction(mi, n, theta_i, phi_wi, (450.0,), below)
    bs, weight = _sample(mi, bsdf, si, n)
    value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, bs.wo)
    weight, value, pdf, bs_pdf = np.array(weight)[0], np.array(value)[0], np.array(pdf), np.array(bs.pdf)
    total = _row_mixture(phong, 450.0, theta_i).sum()
    assert np.all(pdf > 0)
    np.testing.assert_allclose(bs_pdf, pdf, rtol=1e-5)
    np.testing.assert_allclose(weight, total, rtol=1e-6)          # weight P for every direction
    np.testing.assert_allclose(value / pdf, total, rtol=1e-4)     # = eval / pdf
    wo = np.array(bs.wo)
    np.testing.assert_allclose((wo ** 2).sum(axis=0), 1.0, atol=1e-6)
    if below:  # the table mirrored: reflected rays stay below, transmitted go up
        assert np.mean(wo[2] < 0) == pytest.approx(_row_mixture(phong, 450.0, theta_i)[:8 * 12].sum() / total, abs=0.02)


def test_eval_is_the_table_brdf_times_cos_in_each_bin(mi, phong):
    """Directions at bin centres, incidence at azimuth 75°: f = table brdf (rotated by φ − φi)."""

    table = phong
    centres_t = np.radians((table.theta_o_lower + table.theta_o_upper) / 2)
    centres_p = np.radians((table.phi_o_lower + table.phi_o_upper) / 2 - table.phi_i + 75.0)
    T, P = np.meshgrid(centres_t, centres_p, indexing="ij")
    wo = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)]).reshape(3, -1)
    n = wo.shape[1]
    bsdf = mi.load_dict(vm.tabulated_bsdf(table))
    si = _interaction(mi, n, 30.0, 75.0, (450.0, 650.0, 550.0, 500.0))
    value = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*[c.astype(np.float32) for c in wo])))
    cos = np.abs(wo[2])
    for lane, wavelength in enumerate((450.0, 650.0, 550.0, 500.0)):
        expected = _row_mixture(table, wavelength, 30.0) / table.solid_angles.ravel()
        np.testing.assert_allclose(value[lane] / cos, expected, rtol=2e-4)


def test_lanes_other_than_the_hero_weigh_their_own_table(mi, phong):
    bsdf = mi.load_dict(vm.tabulated_bsdf(phong))
    n = 5000
    si = _interaction(mi, n, 30.0, 0.0, (450.0, 650.0))
    bs, weight = _sample(mi, bsdf, si, n)
    value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, bs.wo)
    np.testing.assert_allclose(np.array(weight)[1], np.array(value)[1] / np.array(pdf), rtol=1e-4)
    assert np.mean(np.array(weight)[1]) == pytest.approx(_row_mixture(phong, 650.0, 30.0).sum(), rel=0.03)


def test_pdf_integrates_to_one_and_eval_to_the_row_total(mi, phong):
    """Midpoint quadrature over the sphere in (cos θ, φ): fine enough that bin edges cost < 1 %."""

    import drjit as dr

    bsdf = mi.load_dict(vm.tabulated_bsdf(phong))
    nz, nphi = 800, 720
    z = -1 + (np.arange(nz) + 0.5) * 2 / nz
    phi = (np.arange(nphi) + 0.5) * 2 * np.pi / nphi
    Z, P = np.meshgrid(z, phi, indexing="ij")
    s = np.sqrt(1 - Z ** 2)
    wo = mi.Vector3f(*(c.ravel().astype(np.float32) for c in (s * np.cos(P), s * np.sin(P), Z)))
    si = _interaction(mi, dr.width(wo), 40.0, 0.0, (500.0,))
    value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, wo)
    cell = (2 / nz) * (2 * np.pi / nphi)
    assert np.sum(np.array(pdf)) * cell == pytest.approx(1.0, abs=0.01)
    assert np.sum(np.array(value)[0]) * cell == pytest.approx(_row_mixture(phong, 500.0, 40.0).sum(), abs=0.01)


@pytest.mark.parametrize("theta_i, fixture", [(30.0, "phong"), (45.0, "phong"), (0.0, "folded"), (52.0, "folded")])
def test_chi_square_of_sampled_bins_against_the_table(mi, request, theta_i, fixture):
    """Pearson's test over the table's own bins: counts of sampled bins against p_k / P (exact)."""

    table = request.getfixturevalue(fixture)
    bsdf = mi.load_dict(vm.tabulated_bsdf(table))
    n = 200_000
    si = _interaction(mi, n, theta_i, 0.0, (450.0,))
    bs, _ = _sample(mi, bsdf, si, n, seed=11)
    wo = np.array(bs.wo)
    if table.phi_folded:
        theta = np.degrees(np.arccos(np.clip(wo[2], -1, 1)))
        rel = np.abs(np.degrees(np.arctan2(wo[1], wo[0])))
        k = np.searchsorted(table.theta_o_upper, theta) * table.shape[3] + np.searchsorted(table.phi_o_upper, rel)
    else:
        k = _bin_of(table, wo, 0.0)
    observed = np.bincount(k, minlength=table.shape[2] * table.shape[3])
    expected_p = _row_mixture(table, 450.0, theta_i)
    expected = expected_p / expected_p.sum() * n
    assert observed[expected == 0].sum() == 0
    keep = expected > 0
    statistic, p_value = stats.chisquare(observed[keep], expected[keep])
    assert p_value > 1e-3, (statistic, p_value)


def test_mitsuba_chi2_test_of_sample_against_pdf(mi, phong):
    """mitsuba.chi2.ChiSquareTest (Mitsuba's own BSDF check) on a 2-D histogram of the sphere."""

    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    for theta_i in (30.0, 50.0):
        t = math.radians(theta_i)
        sample_func, pdf_func = BSDFAdapter("tabulated", vm.tabulated_bsdf(phong),
                                            wi=[math.sin(t), 0.0, math.cos(t)])
        test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
                             sample_dim=3, sample_count=200_000, res=31, ires=16, seed=2)
        assert test.run(significance_level=0.01, test_count=2, quiet=True), test.messages


def test_one_lobe_enabled_samples_only_that_lobe(mi, phong):
    bsdf = mi.load_dict(vm.tabulated_bsdf(phong))
    n = 10_000
    si = _interaction(mi, n, 30.0, 0.0, (450.0,))
    rows = _row_mixture(phong, 450.0, 30.0)
    reflected = rows[: 8 * 12].sum()
    for flags, upper, total in ((mi.BSDFFlags.GlossyTransmission, False, rows.sum() - reflected),
                                (mi.BSDFFlags.GlossyReflection, True, reflected)):
        ctx = mi.BSDFContext(mi.TransportMode.Radiance, flags)
        bs, weight = _sample(mi, bsdf, si, n, ctx=ctx)
        wo = np.array(bs.wo)
        assert np.all((wo[2] > 0) == upper)
        np.testing.assert_allclose(np.array(weight)[0], total, rtol=1e-5)
        value, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
        np.testing.assert_allclose(np.array(value)[0] / np.array(pdf), total, rtol=1e-4)


def test_lambertian_table_reproduces_diffuse(mi):
    """A Lambertian table's eval and pdf are those of Mitsuba's ``diffuse`` (constant within bins)."""

    table = lambertian_table(0.6, theta_o_edges=equal_projected_edges(6, transmission=False),
                             phi_o_edges=uniform_edges(0, 360, 8))
    tabulated = mi.load_dict(vm.tabulated_bsdf(table))
    diffuse = mi.load_dict({"type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.6}})
    n = 20_000
    si = _interaction(mi, n, 35.0, 40.0, (551.0,))
    bs, weight = _sample(mi, tabulated, si, n)
    for bsdf in (tabulated, diffuse):
        value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, bs.wo)
        np.testing.assert_allclose(np.array(value)[0], 0.6 / math.pi * np.array(bs.wo.z), rtol=1e-4)
        np.testing.assert_allclose(np.array(pdf), np.array(bs.wo.z) / math.pi, rtol=1e-4)
    np.testing.assert_allclose(np.array(weight)[0], 0.6, rtol=1e-6)


def _union_mu(reading, count: int) -> float:
    """Hoeffding's μ for every one of ``count`` checks at once (union bound, δ = 0.01)."""

    return vm.hoeffding_mu(int(reading.rays[0]), 0.01 / count)


def test_spectrophotometer_reads_the_tables_sums(mi, phong):
    """R and T of the tabulated BSDF = Σ reflected / transmitted fractions, within the bound."""

    scene = vm.instrument_scene(vm.tabulated_bsdf(phong))
    checks = []
    for theta_i in (30.0, 45.0):  # tabulated, and halfway between rows
        reading = vm.measure(scene, theta_i=theta_i, beam="collimated", wavelengths=WAVELENGTHS + [550.0], seed=5)
        assert np.all(np.isfinite(reading.certified_mu))
        for j, wavelength in enumerate(WAVELENGTHS + [550.0]):
            rows = _row_mixture(phong, wavelength, theta_i)
            checks.append((reading.reflectance[j], rows[: 8 * 12].sum(), reading))
            checks.append((reading.transmittance[j], rows[8 * 12:].sum(), reading))
    for measured, expected, reading in checks:
        assert abs(measured - expected) < _union_mu(reading, len(checks))


def test_spectrophotometer_reads_a_lambertian_table_as_diffuse(mi):
    table = lambertian_table([0.3, 0.7], [0.5, 0.2], wavelength=[500.0, 600.0], theta_i=[0.0, 70.0])
    reading = vm.measure(vm.instrument_scene(vm.tabulated_bsdf(table)), theta_i=70, beam="conical",
                         wavelengths=[500.0, 600.0], seed=2)
    mu = _union_mu(reading, 4)
    np.testing.assert_array_less(np.abs(reading.reflectance - [0.3, 0.7]), mu)
    np.testing.assert_array_less(np.abs(reading.transmittance - [0.5, 0.2]), mu)
    assert reading.weight_violations.sum() == 0 and reading.rounded_weights.sum() == 0


def _camera_scene(mi, bsdf: dict) -> dict:
    """A plain Mitsuba scene: perspective camera, a quad with ``bsdf``, uniform sky of radiance 1."""

    T = mi.ScalarTransform4f
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {"type": "perspective", "fov": 40,
                   "to_world": T().look_at(origin=[0, -3, 2], target=[0, 0, 0], up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": 32, "height": 32, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 16}},
        "quad": {"type": "rectangle", "bsdf": bsdf, "to_world": T().scale([0.8, 0.8, 1.0])},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}},
    }


def test_mi_render_of_a_quad_with_the_tabulated_bsdf(mi, phong):
    """A 32×32 render: finite and plausible; a Lambertian table renders like ``diffuse`` (ρ L)."""

    lambert = lambertian_table(0.5, 0.0)
    image_table = np.array(mi.render(mi.load_dict(_camera_scene(mi, vm.tabulated_bsdf(lambert))), seed=1))
    image_diffuse = np.array(mi.render(mi.load_dict(_camera_scene(mi, {
        "type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.5}})), seed=1))
    assert image_table.shape == (32, 32, 3) and np.all(np.isfinite(image_table))
    quad = np.abs(image_diffuse[..., 1] - 1.0) > 0.05  # pixels on the quad (the sky is 1)
    assert 100 < quad.sum() < 1000
    assert image_table[quad].mean() == pytest.approx(image_diffuse[quad].mean(), rel=0.03)
    assert np.median(image_table[quad]) == pytest.approx(0.5, rel=0.03)  # interior pixels: ρ L (edges mix the sky)
    assert image_table[~quad].mean() == pytest.approx(1.0, abs=0.02)  # the sky (spectral noise per channel)
    lobe = np.array(mi.render(mi.load_dict(_camera_scene(mi, vm.tabulated_bsdf(phong))), seed=1))
    assert np.all(np.isfinite(lobe)) and 0.05 < lobe[quad].mean() < 1.0


def test_xml_filename_and_a_black_row(mi, tmp_path):
    """An XML scene names the file; a row with no escaping ray samples weight 0 and evaluates to 0."""

    table = lambertian_table([0.0, 0.5], [0.0, 0.25], wavelength=[500.0, 600.0])
    path = tmp_path / "black.nc"
    table_dataset(table, 10**6).to_netcdf(path)
    bsdf = mi.load_string(f'<bsdf version="3.0.0" type="tabulated"><string name="filename" value="{path}"/></bsdf>')
    n = 1000
    si = _interaction(mi, n, 20.0, 0.0, (500.0,))
    bs, weight = _sample(mi, bsdf, si, n)
    assert np.all(np.array(weight) == 0) and np.all(np.array(bs.pdf) == 0)
    assert np.all(np.isfinite(np.array(bs.wo)))
    value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, mi.Vector3f(0.0, 0.6, 0.8))
    assert np.all(np.array(value) == 0) and np.all(np.array(pdf) == 0)
    bright = _interaction(mi, n, 20.0, 0.0, (600.0,))
    _, weight = _sample(mi, bsdf, bright, n)
    np.testing.assert_allclose(np.array(weight)[0], 0.75, rtol=1e-6)


def test_mitsuba_chi2_test_of_a_folded_table_and_light_from_below(mi, folded):
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    for wi in ([math.sin(0.6), 0.3, math.cos(0.6)], [0.5, 0.0, -math.sqrt(0.75)]):
        norm = math.sqrt(sum(c * c for c in wi))
        sample_func, pdf_func = BSDFAdapter("tabulated", vm.tabulated_bsdf(folded), wi=[c / norm for c in wi])
        test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
                             sample_dim=3, sample_count=200_000, res=31, ires=16, seed=5)
        assert test.run(significance_level=0.01, test_count=2, quiet=True), test.messages
