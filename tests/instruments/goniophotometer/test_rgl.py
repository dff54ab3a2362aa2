"""
The goniophotometer's reflection as an RGL .bsdf (instruments/goniophotometer/rgl.py, exchange/rgl.py): the
file loads in Mitsuba's measured plugin, which returns the stored value at every node (float32 lookups:
relative 1e-4), and a Lambertian specimen's f·cos θo lies in every node's certified interval.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.exchange.rgl import MAGIC, read_tensor, write_tensor
from virtspec_mi.instruments.goniophotometer.rgl import node_directions

ALBEDO = 0.5


@pytest.fixture(scope="module")
def lambertian(mi):
    return vm.gonio(vm.instrument_scene({"type": "diffuse", "reflectance": ALBEDO}), theta_i=[0, 30, 60],
                    wavelengths=[500, 600], rays=100_000, theta_o_bins=9, phi_o_bins=12, binning="projected",
                    beam="collimated", seed=1)


def _evaluate(mi, bsdf, theta_i, phi_i, wavelength, wo):
    k = len(wo)
    t, p = np.radians(theta_i), np.radians(phi_i)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*(np.full(k, c) for c in (np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t))))
    si.wavelengths = mi.Spectrum(*([mi.Float(np.full(k, wavelength))] * 4))
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(wo[:, 0], wo[:, 1], wo[:, 2]))
    return np.array(value[0], dtype=np.float64)


def test_mitsuba_returns_the_stored_values_at_the_nodes_and_the_lambertian_is_in_every_interval(lambertian, mi,
                                                                                               tmp_path):
    export = lambertian.to_rgl(tmp_path / "white.bsdf", resolution=16)
    bsdf = mi.load_dict({"type": "measured", "filename": str(export.path)})
    checked = 0
    for t, theta_i in enumerate(export.theta_i):
        valid = export.valid[t]
        wo = export.wo[t][valid]
        for w, wavelength in enumerate(export.wavelengths):
            got = _evaluate(mi, bsdf, theta_i, export.phi_i, wavelength, wo)
            stored = export.values[w, t][valid]
            np.testing.assert_allclose(got, stored, rtol=1e-4, err_msg=f"theta_i {theta_i}, {wavelength} nm")
            truth = ALBEDO / np.pi * wo[:, 2]  # a Lambertian's f cos(theta_o): f_k = rho/pi in every bin exactly
            assert np.all((export.lower[w, t][valid] <= truth) & (truth <= export.upper[w, t][valid]))
            checked += len(wo)
    assert checked > 900
    description = json.loads(bytes(read_tensor(export.path)["description"]).decode())
    assert description["specimen"] == lambertian.scene and "not of f at the node" in description["stored"]
    assert "Clopper-Pearson" in description["certificate"] and description["readings"] == 6


def test_the_file_layout(lambertian, tmp_path):
    export = lambertian.to_rgl(tmp_path / "white.bsdf", resolution=8)
    raw = export.path.read_bytes()
    assert raw[:12] == MAGIC and raw[12:14] == bytes((1, 0))
    fields = read_tensor(export.path)
    assert fields["spectra"].shape == (2, 3, 2, 8, 8) and fields["spectra"].dtype == np.float32
    assert fields["vndf"].shape == (2, 3, 8, 8) and fields["luminance"].shape == (2, 3, 8, 8)
    np.testing.assert_allclose(fields["theta_i"], np.radians([0, 30, 60]), rtol=1e-6)
    np.testing.assert_array_equal(fields["wavelengths"], [500, 600])
    np.testing.assert_array_equal(fields["spectra"][0, 1, 0], export.values[0, 1].astype(np.float32))
    assert fields["jacobian"].tolist() == [0]


def test_node_directions_are_mirrors_about_the_half_vectors():
    wo = node_directions(30.0, 0.0, 5)
    assert wo.shape == (5, 5, 3)
    np.testing.assert_allclose(np.linalg.norm(wo, axis=-1), 1.0)
    np.testing.assert_allclose(wo[:, 0], [[-0.5, 0.0, np.sqrt(0.75)]] * 5, atol=1e-12)  # theta_m = 0: the mirror


def test_bad_exports_are_refused(lambertian, tmp_path):
    with pytest.raises(ValueError, match="resolution must be a whole number, 2 <= resolution <= 512"):
        lambertian.to_rgl(tmp_path / "x.bsdf", resolution=1)
    transmission = vm.gonio(vm.instrument_scene({"type": "diffuse", "reflectance": ALBEDO}), theta_i=[30],
                            wavelengths=[500], rays=2000, theta_o_bins=3, phi_o_bins=4, hemispheres="transmission")
    with pytest.raises(ValueError, match="the bins must cover theta_o from 0 to 90"):
        transmission.to_rgl(tmp_path / "t.bsdf")
    with pytest.raises(ValueError, match="must be uint8, uint32, float32 or float64"):
        write_tensor(tmp_path / "bad.bsdf", {"x": np.zeros(2, dtype=np.int16)})
    (tmp_path / "cut.bsdf").write_bytes(MAGIC + bytes((1, 0)) + (1).to_bytes(4, "little") + b"\x05\x00")
    with pytest.raises(ValueError, match="cut.bsdf: damaged tensor file header"):
        read_tensor(tmp_path / "cut.bsdf")


def test_cli_gonio_rgl(tmp_path, capsys, mi):
    from virtspec_mi.cli import main

    path = tmp_path / "white.bsdf"
    assert main(["gonio", "diamond_collimated", "--theta-i", "30", "--wavelengths", "550", "--rays", "5000",
                 "--theta-o-bins", "6", "--phi-o-bins", "8", "--rgl", str(path), "--quiet"]) == 0
    assert f"rgl: {path}" in capsys.readouterr().out
    assert mi.load_dict({"type": "measured", "filename": str(path)}) is not None


def test_a_reading_that_is_not_certified_gets_no_interval(lambertian, tmp_path, monkeypatch):
    from virtspec_mi.instruments.goniophotometer.result import GonioResult

    bins_mu = np.array(lambertian.bins_mu, dtype=float)
    bins_mu[1, 2] = np.nan  # 600 nm at 60 degrees: as a reading with weight violations reports itself
    monkeypatch.setattr(GonioResult, "bins_mu", property(lambda self: bins_mu))
    export = lambertian.to_rgl(tmp_path / "w.bsdf", resolution=8)
    assert np.all(np.isnan(export.lower[1, 2])) and np.all(np.isnan(export.upper[1, 2]))
    assert not np.any(np.isnan(export.lower[0, 2][export.valid[2]]))
    assert np.any(export.values[1, 2] > 0)  # the estimate is written; its interval is not
