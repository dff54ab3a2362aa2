"""
The goniophotometer's reflection as an RGL .bsdf (instruments/goniophotometer/rgl.py, exchange/rgl.py), measured on
the file's own grid (binning="rgl"):

- Mitsuba loads every file and its measured plugin returns the stored value at every node whose direction is above
  the horizon: relative 1e-4 plus the weight the float32 lookup position gives the node's neighbours, at most
  (n - 1) * 2.5e-4, plus 1e-6 of the file's peak (see _check_mitsuba_returns_the_stored_values);
- the stored certified intervals cover the exact cell means of f·cos θo of a Lambertian (ρ/π · ∫cos/Ω, by
  quadrature) and of Mitsuba's own roughconductor (its eval integrated over each cell at two quadrature orders,
  their difference far below the intervals' widths).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.exchange.rgl import MAGIC, read_tensor, write_tensor

ALBEDO = 0.5
CONDUCTOR = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3}


@pytest.fixture(scope="module")
def lambertian(mi):
    return vm.gonio(vm.instrument_scene({"type": "diffuse", "reflectance": ALBEDO}), theta_i=[0, 30, 60],
                    wavelengths=[500, 600], rays=100_000, binning="rgl", rgl_resolution=12, beam="collimated", seed=1)


@pytest.fixture(scope="module")
def conductor(mi):
    return vm.gonio(vm.instrument_scene(CONDUCTOR), theta_i=[0, 40], wavelengths=[550], rays=200_000,
                    binning="rgl", rgl_resolution=12, beam="collimated", seed=3)


def _evaluate(mi, bsdf, theta_i, phi_i, wavelength, wo):
    shape = wo.shape[:-1]
    wo = wo.reshape(-1, 3)
    k = len(wo)
    t, p = np.radians(theta_i), np.radians(phi_i)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*(np.full(k, c) for c in (np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t))))
    si.wavelengths = mi.Spectrum(*([mi.Float(np.full(k, wavelength))] * 4))
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(wo[:, 0], wo[:, 1], wo[:, 2]))
    return np.array(value[0], dtype=np.float64).reshape(shape)


def _check_mitsuba_returns_the_stored_values(mi, export):
    """
    At every visible node: relative 1e-4, plus the weight a rounded lookup position gives the node's
    neighbours (along theta_m and phi_m): the plugin's float32 half vector puts theta_m off by up to ~1e-7 rad, so
    u_1 = sqrt(2 theta_m / pi) is off by at most sqrt(2e-7 / pi) = 2.5e-4 (near theta_m = 0, where the square root
    is steep): a weight of at most (n - 1) * 2.5e-4 on a neighbour; and 1e-6 of the file's largest value (theta_i
    computed from a float32 wi weighs the next theta_i slice by ~1e-7). Returns the nodes checked and the largest
    relative difference seen.
    """

    bsdf = mi.load_dict({"type": "measured", "filename": str(export.path)})
    checked, worst, n, peak = 0, 0.0, export.values.shape[-1], export.values.max()
    for t, theta_i in enumerate(export.theta_i):
        visible = export.visible[t]
        for w, wavelength in enumerate(export.wavelengths):
            values = export.values[w, t]
            got = _evaluate(mi, bsdf, theta_i, export.phi_i, wavelength, export.wo[t][visible])
            step = np.maximum(np.abs(np.diff(values, axis=1, prepend=values[:, :1])),
                              np.abs(np.diff(values, axis=1, append=values[:, -1:])))
            step[:, 0] = np.max(np.abs(values[:, 1] - values[:, 0]))  # the mirror: the plugin may read any row there
            step = np.maximum(step, np.maximum(np.abs(values - np.roll(values, 1, axis=0)),
                                               np.abs(values - np.roll(values, -1, axis=0))))  # and a phi_m neighbour
            stored = values[visible]
            assert np.all(np.abs(got - stored) <= 1e-4 * stored + (n - 1) * 2.5e-4 * step[visible] + 1e-6 * peak), \
                (theta_i, wavelength)
            worst = max(worst, float(np.max(np.abs(got - stored)[stored > 0] / stored[stored > 0])))
            checked += len(stored)
    return checked, worst


def test_mitsuba_returns_the_stored_values_and_the_lambertian_cell_means_are_in_every_interval(lambertian, mi,
                                                                                               tmp_path):
    export = lambertian.to_rgl(tmp_path / "white.bsdf")
    checked, worst = _check_mitsuba_returns_the_stored_values(mi, export)
    assert checked > 500
    grid = lambertian.grid
    for t, theta_i in enumerate(export.theta_i):
        cells = export.cells[t][export.valid[t]]
        omega = grid.cell_integral(theta_i, export.phi_i, cells=cells)
        exact = ALBEDO / np.pi * grid.cell_integral(theta_i, export.phi_i, lambda wo: wo[..., 2], cells=cells) / omega
        for w in range(len(export.wavelengths)):
            lower, upper = export.lower[w, t][export.valid[t]], export.upper[w, t][export.valid[t]]
            assert np.all((lower <= exact) & (exact <= upper)), (theta_i, w)
    description = json.loads(bytes(read_tensor(export.path)["description"]).decode())
    assert description["specimen"] == lambertian.scene and "not of f cos(theta_o) at the node" in description["stored"]
    assert "Clopper-Pearson" in description["certificate"] and description["readings"] == 6
    assert "binning rgl" in description["grid"]


def test_the_rough_conductors_exact_cell_means_are_in_every_interval(conductor, mi, tmp_path):
    export = conductor.to_rgl(tmp_path / "conductor.bsdf")
    checked, worst = _check_mitsuba_returns_the_stored_values(mi, export)
    assert checked > 150
    specimen = mi.load_dict(CONDUCTOR)
    grid, covered = conductor.grid, 0
    for t, theta_i in enumerate(export.theta_i):
        cells = np.unique(export.cells[t][export.valid[t]])

        def f_cos(wo, theta_i=theta_i):
            return _evaluate(mi, specimen, theta_i, export.phi_i, 550.0, wo)

        omega = grid.cell_integral(theta_i, export.phi_i, cells=cells)
        exact = grid.cell_integral(theta_i, export.phi_i, f_cos, cells=cells) / omega
        coarse = grid.cell_integral(theta_i, export.phi_i, f_cos, cells=cells, order=12) / omega
        lower, upper = conductor.cell_mean_lower[0, t][cells], conductor.cell_mean_upper[0, t][cells]
        assert np.max(np.abs(exact - coarse) / (upper - lower)) < 1e-3  # the quadrature is not what decides
        assert np.all((lower <= exact) & (exact <= upper)), theta_i
        covered += len(cells)
    assert covered > 90


def test_the_file_layout(lambertian, tmp_path):
    export = lambertian.to_rgl(tmp_path / "white.bsdf")
    raw = export.path.read_bytes()
    assert raw[:12] == MAGIC and raw[12:14] == bytes((1, 0))
    fields = read_tensor(export.path)
    assert fields["spectra"].shape == (2, 3, 2, 12, 12) and fields["spectra"].dtype == np.float32
    assert fields["vndf"].shape == (2, 3, 12, 12) and fields["luminance"].shape == (2, 3, 12, 12)
    np.testing.assert_allclose(fields["theta_i"], np.radians([0, 30, 60]), rtol=1e-6)
    np.testing.assert_array_equal(fields["wavelengths"], [500, 600])
    np.testing.assert_array_equal(fields["spectra"][0, 1, 0], export.values[0, 1].astype(np.float32))
    assert fields["jacobian"].tolist() == [0]
    # each node holds its cell's mean: rows 0 and n - 1 one cell, column 0 one cell, at theta_i = 0 rings
    values = export.values[0]
    np.testing.assert_array_equal(values[1, 0], values[1, -1])
    assert np.all(values[1, :, 0] == values[1, 0, 0]) and np.all(values[0] == values[0, :1])
    stored = lambertian.cell_mean[0, 1][export.cells[1][export.valid[1]]]
    np.testing.assert_array_equal(values[1][export.valid[1]], stored)


def test_bad_exports_are_refused(lambertian, tmp_path):
    plain = vm.gonio(vm.instrument_scene({"type": "diffuse", "reflectance": ALBEDO}), theta_i=[30],
                     wavelengths=[500], rays=2000, theta_o_bins=3, phi_o_bins=4)
    with pytest.raises(ValueError, match="measure with binning='rgl'"):
        plain.to_rgl(tmp_path / "t.bsdf")
    assert not (tmp_path / "t.bsdf").exists()
    with pytest.raises(ValueError, match="must be uint8, uint32, float32 or float64"):
        write_tensor(tmp_path / "bad.bsdf", {"x": np.zeros(2, dtype=np.int16)})
    (tmp_path / "cut.bsdf").write_bytes(MAGIC + bytes((1, 0)) + (1).to_bytes(4, "little") + b"\x05\x00")
    with pytest.raises(ValueError, match="cut.bsdf: damaged tensor file header"):
        read_tensor(tmp_path / "cut.bsdf")


def test_write_by_suffix_writes_the_bsdf(lambertian, mi, tmp_path):
    path = lambertian.write(tmp_path / "white.bsdf")
    assert path == tmp_path / "white.bsdf" and mi.load_dict({"type": "measured", "filename": str(path)}) is not None


def test_cli_gonio_rgl(tmp_path, capsys, mi):
    from virtspec_mi.cli import main

    path = tmp_path / "white.bsdf"
    assert main(["gonio", "diamond_collimated", "--theta-i", "30", "--wavelengths", "550", "--rays", "5000",
                 "--rgl", str(path), "--rgl-resolution", "8"]) == 0
    out = capsys.readouterr().out
    assert f"rgl: {path}" in out and "8 x 8 nodes" in out
    assert read_tensor(path)["spectra"].shape == (2, 1, 1, 8, 8)
    assert mi.load_dict({"type": "measured", "filename": str(path)}) is not None
    assert main(["gonio", "diamond_collimated", "--theta-i", "30", "--rays", "5000", "--theta-o-bins", "6",
                 "--rgl", str(tmp_path / "x.bsdf")]) != 0
    assert "theta_o_bins: no meaning with binning 'rgl'" in capsys.readouterr().err
    assert not (tmp_path / "x.bsdf").exists()


def test_a_reading_that_is_not_certified_gets_no_interval(lambertian, tmp_path, monkeypatch):
    from virtspec_mi.instruments.goniophotometer.rgl_reading import RGLReading

    bins_mu = np.array(lambertian.bins_mu, dtype=float)
    bins_mu[1, 2] = np.nan  # 600 nm at 60 degrees: as a reading with weight violations reports itself
    monkeypatch.setattr(RGLReading, "bins_mu", property(lambda self: bins_mu))
    reading = RGLReading(lambertian.result, lambertian.cell_counts, lambertian.resolution, lambertian.guarantee)
    export = reading.to_rgl(tmp_path / "w.bsdf")
    assert np.all(np.isnan(export.lower[1, 2])) and np.all(np.isnan(export.upper[1, 2]))
    assert not np.any(np.isnan(export.lower[0, 2][export.valid[2]]))
    assert np.any(export.values[1, 2] > 0)  # the estimate is written; its interval is not
