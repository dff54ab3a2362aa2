"""
Nonsense refused where it enters, messages that name the parameter and the fix, valid
input accepted (issue 33): each case one the held-out pass found.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.runtime.scaleout import check_workers

SMALL = dict(model="conductor", engine=None, mu=[0.5, 1.0], alpha=[0.3], epsilon=0.05, progress=False)


@pytest.fixture(scope="module")
def dielectric(mi):
    return vm.instrument_scene({"type": "simple_dielectric", "eta": 1.5})


# --- nonsense refused ---------------------------------------------------------------------------------------


def test_points_must_be_true_or_false(dielectric):
    with pytest.raises(ValueError, match="points must be true or false \\(got 'yes'\\)"):
        vm.sweep(dielectric, rays=100, parameters={"eta": [1.3, 1.5]}, points="yes", progress=False)


def test_a_relative_tolerance_without_the_relative_guarantee_is_refused_not_ignored(dielectric):
    with pytest.raises(ValueError, match="relative_tolerance applies only with guarantee='relative'"):
        vm.gonio(dielectric, relative_tolerance=0.1, progress=False)
    with pytest.raises(ValueError, match="brdf_floor applies only with guarantee='relative'"):
        vm.gonio(dielectric, guarantee="union", brdf_floor=0.5, progress=False)


def test_a_gloss_meter_has_no_diffuse_beam(dielectric):
    with pytest.raises(ValueError, match="beam must be collimated or conical for a gloss meter"):
        vm.take("gloss", dielectric, beam="diffuse", rays=100, progress=False)


@pytest.mark.parametrize("keywords, words", [
    ({"pilot_rays": 1.5}, "pilot_rays must be a whole number"),
    ({"pilot_rays": True}, "pilot_rays must be a whole number"),
    ({"pilot_rays": "100"}, "pilot_rays must be a whole number, not a string"),
    ({"seed": 1.5}, "seed must be a whole number"),
    ({"mu": [True]}, "mu must be a sequence of numbers"),
    ({"average": "no"}, "average must be true or false"),
])
def test_an_albedo_tables_settings_are_checked_where_they_enter(keywords, words):
    with pytest.raises(ValueError, match=words):
        vm.albedo_table(**{**SMALL, **keywords})


@pytest.mark.parametrize("text, words", [
    ("400,0,52\n500,0,61\n", "decimal commas in a comma-separated file"),
    ("1,0\n400,0.5\n500,0.6\n", "line 1: '1,0' is not a row of a wavelength in nm"),
])
def test_a_measured_csv_that_would_be_misread_is_refused(tmp_path, text, words):
    path = tmp_path / "measured.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=words):
        vm.read_measured(path)


def test_a_semicolon_csv_with_decimal_commas_is_read_as_written(tmp_path):
    path = tmp_path / "measured.csv"
    path.write_text("wavelength;reflectance\n400;0,52\n500;0,61\n")
    measured = vm.read_measured(path)
    assert measured.wavelengths.tolist() == [400.0, 500.0] and measured.values.tolist() == [0.52, 0.61]


# --- messages ---------------------------------------------------------------------------------------------


def test_a_python_bsdf_whose_sample_returns_one_value_is_named_with_the_fix(mi):
    class OneValue(mi.BSDF):
        def __init__(self, props):
            super().__init__(props)
            self.m_flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = mi.BSDFSample3f()
            bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.pdf = 1.0
            return bs

        def eval(self, *args, **kwargs):
            return 0.0

        def pdf(self, *args, **kwargs):
            return 0.0

    mi.register_bsdf("issue33_one_value", lambda props: OneValue(props))
    with pytest.raises(ValueError, match="OneValue: sample\\(\\) must return the pair \\(mi.BSDFSample3f, weight\\)"):
        vm.measure(vm.instrument_scene({"type": "issue33_one_value"}), rays=100, progress=False)


def test_a_spheres_wall_reflectance_that_is_not_a_number_says_what_it_takes(mi):
    with pytest.raises(ValueError, match="wall_reflectance must be a number 0 <= rho_w <= 1 or 'nm:value' pairs"):
        vm.sphere_measure("sphere_150mm_8d", rays=100, defines={"wall_reflectance": "abc"}, progress=False)


@pytest.mark.parametrize("content, words", [(b"just some notes\n", "is not a NetCDF file \\(plain text\\)"),
                                            (bytes(range(200, 256)) * 4, "first bytes are not those of NetCDF")])
def test_a_tabulated_bsdf_file_that_is_not_netcdf_is_named(mi, tmp_path, content, words):
    path = tmp_path / "table.nc"
    path.write_bytes(content)
    with pytest.raises(ValueError, match=words) as error:
        vm.measure(vm.instrument_scene({"type": "tabulated", "filename": str(path)}), rays=100, progress=False)
    assert "https://" not in str(error.value) and str(path) in str(error.value)


@pytest.mark.parametrize("suffix, words", [(".npy", "is not a .npy array of numbers"), (".csv", "is not text"),
                                           (".h", "is not text"), (".nc", "is not a NetCDF file")])
def test_a_malformed_published_table_is_named(tmp_path, suffix, words):
    from virtspec_mi.exchange.header import read_table_values

    path = tmp_path / f"published{suffix}"
    path.write_bytes(bytes(range(128, 256)) * 3)
    with pytest.raises(ValueError, match=words):
        read_table_values(path)


def test_an_albedo_table_file_that_is_not_netcdf_is_named(tmp_path):
    path = tmp_path / "t.nc"
    path.write_text("E = 0.5\n")
    with pytest.raises(ValueError, match=f"albedo table {path} is not a NetCDF file"):
        vm.read_albedo_table(path)


@pytest.mark.parametrize("address, words", [("inproc://nothing", "an in-process address is inproc://HOST/PID/N"),
                                            ("carrier://pigeon:1", "no Dask transport 'carrier'")])
def test_a_scheduler_address_dask_cannot_use_is_named(address, words):
    with pytest.raises(ValueError, match=words):
        check_workers(address)


# --- valid input accepted ---------------------------------------------------------------------------------


def test_numpy_float32_epsilon_and_delta_are_numbers(mi):
    table = vm.albedo_table(**{**SMALL, "epsilon": np.float32(0.05), "delta": np.float32(0.01)})
    assert table.epsilon == pytest.approx(0.05) and table.delta == pytest.approx(0.01)


# --- result files whose settings disagree with their labels or counts ------------------------------------


def _edited(tmp_path: Path, result, change) -> Path:
    import json

    path = tmp_path / "original.json"
    result.write(path)
    data = json.loads(path.read_text())
    data.pop("checksum")  # as a file written by hand or by another program: the rules alone decide
    change(data)
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(data))
    return edited


def test_a_result_file_whose_theta_i_label_is_not_its_settings_is_refused(dielectric, tmp_path):
    reading = vm.sweep(dielectric, theta_i=[0], rays=100, progress=False)
    edited = _edited(tmp_path, reading, lambda data: data.__setitem__("theta_i", [45.0]))
    with pytest.raises(ValueError, match="the settings' theta_i 0 is not the theta_i label 45"):
        vm.read_result(edited)


def test_a_result_file_whose_two_stage_mu_is_impossible_for_its_rays_is_refused(dielectric, tmp_path):
    reading = vm.sweep(dielectric, theta_i=[0], mu=0.05, bound="two-stage", progress=False)
    edited = _edited(tmp_path, reading, lambda data: data["settings"].__setitem__("mu", 1e-6))
    with pytest.raises(ValueError, match="mu = 1e-06 \\(two-stage\\) cannot be certified with"):
        vm.read_result(edited)


def test_a_selection_restates_its_settings_and_its_file_reads_back(dielectric, tmp_path):
    sweep = vm.sweep(dielectric, theta_i=[10, 20], wavelengths=[500, 600], rays=100, progress=False)
    one = sweep.sel(theta_i=20, wavelength=600)
    assert one.settings.theta_i == 20 and one.settings.wavelengths == (600.0,)
    one.write(tmp_path / "one.json")
    assert vm.read_result(tmp_path / "one.json").theta_i == 20
    gonio = vm.gonio(dielectric, theta_i=[10, 20], rays=100, theta_o_bins=3, phi_o_bins=4, progress=False)
    gonio.sel(theta_i=20).write(tmp_path / "one.nc")
    assert vm.read_gonio(tmp_path / "one.nc").theta_i.tolist() == [20.0]


@pytest.mark.parametrize("keywords, words", [({"seed": "abc"}, "seed must be a number"),
                                             ({"rays": "x"}, "rays must be a number"),
                                             ({"isotropic": "maybe"}, "isotropic must be true or false"),
                                             ({"epsilon": "abc"}, "epsilon must be a number")])
def test_a_klems_measurements_settings_are_named_not_raw_conversion_errors(keywords, words):
    from virtspec_mi.applications.klems.measure import klems_measure

    with pytest.raises(ValueError, match=words):
        klems_measure("diamond_conical", basis="quarter", **keywords)


def test_an_albedo_tables_wavelength_is_named():
    with pytest.raises(ValueError, match="wavelength must be a number, not text \\(got 'abc'\\)"):
        vm.albedo_table(**{**SMALL, "wavelength": "abc"})
