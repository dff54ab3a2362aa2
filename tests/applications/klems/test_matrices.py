"""
Klems BSDF files (virtspec_mi.applications.klems.matrices*): the bases, exact aggregation, the turned-over
specimen, the XML read back by an independent reader (Radiance's BSDF library through
pyradiance, and the standard library's XML parser), and detection of swapped or corrupted files.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.klems.matrices import check_klems, read_klems, read_klems_sidecar, sidecar_path
from virtspec_mi.exchange.klems_basis import klems_basis
from virtspec_mi.applications.klems.measure import flipped, klems_measure

GLASS = {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.2, "int_ior": 1.5, "ext_ior": 1.0}


def _radiance():
    try:
        from pyradiance import bsdf  # noqa: F401
    except ImportError as error:  # pragma: no cover - pyradiance is in the test extra
        pytest.skip(f"pyradiance (Radiance's BSDF library, the independent reader) is not installed: {error}")


@pytest.mark.parametrize("basis, size, bins", [("full", 145, 480), ("half", 77, 480), ("quarter", 41, 48)])
def test_bases(basis, size, bins):
    b = klems_basis(basis)
    assert b.size == size and b.phi_bins() == bins
    assert b.projected_solid_angle.sum() == pytest.approx(np.pi, rel=1e-12)
    edges = np.linspace(0.0, 360.0, bins + 1)
    for transmitted in (False, True):
        table = b.aggregation(b.theta_edges(), edges, transmitted)
        assert sorted(set(table[table >= 0].ravel())) == list(range(size))
    # every bin centre falls in the patch Radiance's index rule (fo_getndx) gives it
    centres = (b.theta_edges()[:-1] + b.theta_edges()[1:]) / 2
    t, p = np.meshgrid(centres[centres < 90], (edges[:-1] + edges[1:]) / 2, indexing="ij")
    assert np.array_equal(b.patch_of(t, p), b.aggregation(b.theta_edges(), edges, False)[centres < 90])
    with pytest.raises(ValueError, match="phi_o_bins"):
        b.aggregation(b.theta_edges(), np.linspace(0.0, 360.0, bins // 2 + 2), False)
    with pytest.raises(ValueError, match="theta_o_bins"):
        b.aggregation(np.linspace(0, 180, 7), edges, False)
    with pytest.raises(ValueError, match="basis"):
        klems_basis("eighth")


def test_turned_over_glass_is_glass_seen_from_inside(mi):
    """Flipping the frame of n1 -> n2 glass gives exactly the n2 -> n1 interface: same rays, same counts."""

    inside = {**GLASS, "int_ior": 1.0, "ext_ior": 1.5}
    a = vm.sweep(vm.instrument_scene(flipped(GLASS)), theta_i=[0, 40, 70], beam="collimated", rays=20000, seed=4)
    b = vm.sweep(vm.instrument_scene(inside), theta_i=[0, 40, 70], beam="collimated", rays=20000, seed=4)
    assert np.array_equal(a.reflected, b.reflected) and np.array_equal(a.transmitted, b.transmitted)
    lit_from_behind = vm.sweep(vm.instrument_scene(flipped({"type": "diffuse"})), theta_i=[0, 60], rays=2000)
    assert lit_from_behind.reflected.sum() == 0 and lit_from_behind.transmitted.sum() == 0  # one-sided BSDF


@pytest.fixture(scope="module")
def glass_file(mi, tmp_path_factory):
    path = tmp_path_factory.mktemp("klems") / "glass.xml"
    measured = klems_measure(vm.instrument_scene(GLASS), basis="quarter", epsilon=0.03, seed=1, out=path,
                             name="rough glass")
    return path, measured


def test_counts_add_up_and_the_certificate(glass_file):
    _, m = glass_file
    assert m.counts.shape == (2, 1, 41, 2, 41)
    assert np.array_equal(m.counts[..., 0, :].sum(-1), m.reflected)
    assert np.array_equal(m.counts[..., 1, :].sum(-1), m.transmitted)
    assert np.all(m.certified_epsilon <= 0.03) and "0.99" in m.statement()
    lower, upper = m.bsdf_band()
    assert np.all((lower <= m.bsdf) & (m.bsdf <= upper))
    # a smooth-ish glass: most transmitted light of an incidence stays in its straight-through patch
    t = m.fraction[0, 0, :, 1, :]
    assert np.mean(np.diag(t) / t.sum(1)) > 0.2


def test_front_back_matrices_match_the_physics(glass_file):
    """Front: air -> glass (R at normal incidence 4 %); back: glass -> air, total reflection at grazing."""

    _, m = glass_file
    assert m.reflectance[0, 0, 0] == pytest.approx(0.04, abs=0.03 + 0.01)
    assert m.reflectance[1, 0, -1] > 0.7  # 78 deg from inside: beyond the critical angle (41.8 deg)


def test_the_file_reads_back_with_the_standard_library(glass_file):
    path, m = glass_file
    parsed = read_klems(path)
    assert parsed["basis"] == "LBNL/Klems Quarter" and parsed["structure"] == "Columns"
    matrix = parsed["blocks"][("Visible", "Transmission Front")]
    assert np.allclose(matrix, m.bsdf[0, 0, :, 1, :], rtol=1e-8, atol=1e-12)
    report = check_klems(path, reader="xml")
    assert report["passed"] and report["worst"] < 1e-6


def test_the_file_passes_radiance(glass_file):
    """Radiance's own BSDF library parses the file; its direct-hemispherical sums are the certified R and T."""

    _radiance()
    path, m = glass_file
    report = check_klems(path, reader="pyradiance")
    assert report["passed"] and report["checked"] == 2 * 41 * 2 and report["worst"] < 1e-5
    assert read_klems_sidecar(sidecar_path(path)).statement() == m.statement()


def test_swapped_and_corrupted_files_are_detected(glass_file, tmp_path):
    _radiance()
    path, _ = glass_file
    text = path.read_text()
    swapped = tmp_path / "swapped.xml"
    swapped.write_text(text.replace("Reflection Front", "@").replace("Transmission Front", "Reflection Front")
                       .replace("@", "Transmission Front"))
    sidecar_path(swapped).write_bytes(sidecar_path(path).read_bytes())
    for reader in ("pyradiance", "xml"):
        with pytest.raises(ValueError, match="differs from the certified"):
            check_klems(swapped, reader=reader)
    truncated = tmp_path / "truncated.xml"
    start = text.index("<ScatteringData>") + len("<ScatteringData>") + 2000
    truncated.write_text(text[:start] + text[text.index("</ScatteringData>", start):])
    sidecar_path(truncated).write_bytes(sidecar_path(path).read_bytes())
    for reader in ("pyradiance", "xml"):
        with pytest.raises(ValueError):
            check_klems(truncated, reader=reader)
    garbage = tmp_path / "garbage.xml"
    garbage.write_text("<WindowElement><Optical>")
    sidecar_path(garbage).write_bytes(sidecar_path(path).read_bytes())
    for reader in ("pyradiance", "xml"):
        with pytest.raises(ValueError):
            check_klems(garbage, reader=reader)


def test_isotropic_shortcut_and_write_klems_of_a_gonio_reading(mi, tmp_path):
    """A rotation-invariant specimen: per-ring readings rotated agree with per-patch readings within the certificate."""

    scene = vm.instrument_scene(GLASS)
    each = klems_measure(scene, basis="quarter", epsilon=0.05, back=False, seed=2)
    rotated = klems_measure(scene, basis="quarter", epsilon=0.05, back=False, seed=3, isotropic=True)
    tolerance = each.certified_epsilon + rotated.certified_epsilon
    assert np.all(np.abs(each.fraction - rotated.fraction) < tolerance[..., None, None])
    b = klems_basis("quarter")
    reading = vm.gonio(scene, theta_i=b.theta_centres.tolist(), beam="collimated", rays=3000, seed=3, phi_i=180,
                       theta_o_bins=b.theta_edges().tolist(), phi_o_bins=b.phi_bins())
    out = vm.write_klems(reading, tmp_path / "g.xml", basis="quarter", isotropic=True)
    assert check_klems(out, reader="xml")["passed"]
    assert "Mitsuba None" not in out.read_text() and f"Mitsuba {mi.__version__}" in out.read_text()
    from_reading = read_klems_sidecar(sidecar_path(out))
    assert np.all(np.abs(from_reading.fraction - rotated.fraction)
                  < (from_reading.certified_epsilon + rotated.certified_epsilon)[..., None, None])
    with pytest.raises(ValueError, match="isotropic"):
        vm.write_klems(reading, tmp_path / "h.xml", basis="quarter")


def test_cli_gonio_klems(mi, tmp_path, capsys, scenes_dir):
    from virtspec_mi.cli import main

    out = tmp_path / "diamond.xml"
    assert main(["gonio", str(scenes_dir / "diamond_collimated.xml"), "--klems", str(out), "--klems-basis", "quarter",
                 "--mu", "0.1", "--isotropic"]) == 0
    text = capsys.readouterr().out
    assert "within 0.1" in text and sidecar_path(out).exists()
    m = read_klems_sidecar(sidecar_path(out))
    # a smooth diamond: every reflected ray in the mirror patch, every refracted one in the straight-through ring
    r = m.fraction[0, 0, :, 0, :]
    assert np.allclose(np.diag(r), r.sum(1))


def test_a_scene_given_by_name_is_loaded_once(mi, monkeypatch):
    """Each side's scene is loaded once (vm.scene.loaded), every goniophotometer reading of that side takes it."""

    from virtspec_mi.runtime import scene

    real, loads = scene.find_bench, []
    monkeypatch.setattr(scene, "find_bench", lambda given, defines=None: loads.append(given) or real(given, defines))
    measured = klems_measure("diamond_collimated", basis="quarter", isotropic=True, rays=2000, seed=4)
    assert measured.sides == ("front", "back") and len(loads) == 2  # the front, then its specimen turned over
    assert loads[0] == "diamond_collimated" and loads[1]["specimen"]["bsdf"]["type"] == "virtspec_flipped"


@pytest.mark.slow
def test_full_basis_file_passes_radiance(mi, tmp_path):
    _radiance()
    path = tmp_path / "full.xml"
    m = klems_measure(vm.instrument_scene(GLASS), basis="full", epsilon=0.02, out=path, seed=9)
    assert m.counts.shape == (2, 1, 145, 2, 145)
    report = check_klems(path, reader="pyradiance")
    assert report["passed"] and report["checked"] == 580


def test_wavelengths_without_photopic_weight_are_refused_before_any_ray(tmp_path, monkeypatch):
    import virtspec_mi.runtime.reading as reading

    def traced(*args, **kwargs):
        raise AssertionError("rays were traced before the Visible block's weights were checked")

    monkeypatch.setattr(reading, "take", traced)
    with pytest.raises(ValueError, match="wavelengths 1000, 1100 nm carry no photopic weight"):
        klems_measure("diamond_collimated", basis="quarter", wavelengths=[1000, 1100], rays=100,
                      out=tmp_path / "ir.xml")
    assert list(tmp_path.iterdir()) == []
