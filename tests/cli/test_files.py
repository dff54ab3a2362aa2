"""
Tests of ``virtspec plot|colour|compare`` on the files of every result kind: a
goniophotometer file is plotted (its lobes, or its R and T), coloured and compared
through its R and T; a sphere file through its reading and its hemispherical value;
``--sel NAME=VALUE`` takes the nearest label of a dim; what a kind cannot do is one line
``virtspec: error: …`` and exit status 1.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from result_kinds import gonio_reading, hemispherical_grid, sphere_grid, sphere_reading
from virtspec_mi.cli import main


@pytest.fixture(scope="module")
def files(mi, tmp_path_factory):
    folder = tmp_path_factory.mktemp("kinds")
    gonio, sphere, grid, sweep = gonio_reading(), sphere_reading(), sphere_grid(), hemispherical_grid()
    return {"gonio": (gonio, gonio.write(folder / "gonio.nc")),
            "sphere": (sphere, sphere.write(folder / "sphere.json")),
            "sphere grid": (grid, grid.write(folder / "grid.nc")), "sweep": (sweep, sweep.write(folder / "lut.csv")),
            "folder": folder}


def run(capsys, *args):
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def one_line_error(capsys, *args):
    status, out, err = run(capsys, *args)
    assert status == 1 and err.startswith("virtspec: error: ") and err.count("\n") == 1, err
    return err


def write_measured(path, wavelengths, values):
    path.write_text("wavelength,reflectance\n" + "".join(f"{w:g},{v!r}\n" for w, v in zip(wavelengths, values)))
    return path


# --- the goniophotometer -----------------------------------------------------------------------


def test_plot_of_a_gonio_file_draws_its_lobes_and_says_at_which_wavelength(files, capsys):
    gonio, path = files["gonio"]
    out = files["folder"] / "lobes.png"
    status, printed, _ = run(capsys, "plot", path, "--out", out)
    assert status == 0 and out.read_bytes()[:4] == b"\x89PNG"
    assert f"plot: {out}" in printed
    assert "drew the lobes at 400 nm, the first of 3 wavelengths (another: --sel wavelength=NM)" in printed
    status, printed, note = run(capsys, "plot", path, "--sel", "wavelength=560", "--out", out.with_suffix(".svg"))
    assert status == 0 and "drew the lobes" not in printed
    assert "--sel wavelength=560 took the nearest label, 550" in note
    status, printed, _ = run(capsys, "plot", path, "--quantity", "transmittance", "--theta-i", "50", "--out", out)
    assert status == 0 and printed.strip() == f"plot: {out}"


def test_colour_and_compare_of_a_gonio_file_go_through_its_r_and_t(files, capsys):
    gonio, path = files["gonio"]
    status, printed, _ = run(capsys, "colour", path, "--theta-i", "10", "--json")
    assert status == 0
    np.testing.assert_allclose(json.loads(printed)["XYZ"], gonio.result.colour(theta_i=10).XYZ)
    measured = write_measured(files["folder"] / "r.csv", gonio.wavelengths, gonio.result.reflectance[:, 1])
    status, printed, _ = run(capsys, "compare", path, measured, "--theta-i", "50", "--json")
    data = json.loads(printed)
    assert status == 0 and data["quantity"] == "reflectance" and data["result"] == "gonio.nc"
    assert data["rmse"] == 0 and data["points_within"] == 3
    err = one_line_error(capsys, "colour", path, "--quantity", "brdf", "--theta-i", "10")
    assert "quantity must be one of reflectance, transmittance, absorptance (got 'brdf'): a goniophotometer " \
           "reading's spectra are its R, T and A" in err
    err = one_line_error(capsys, "plot", path, "--sel", "theta_o=40")
    assert "'theta_o' is a dim a goniophotometer reading keeps whole" in err


# --- the sphere --------------------------------------------------------------------------------


def test_plot_colour_and_compare_of_a_sphere_file_go_through_its_reading(files, capsys):
    sphere, path = files["sphere"]
    out = files["folder"] / "sphere.png"
    status, printed, _ = run(capsys, "plot", path, "--out", out)
    assert status == 0 and out.read_bytes()[:4] == b"\x89PNG" and f"plot: {out}" in printed
    status, printed, _ = run(capsys, "plot", path, "--quantity", "corrected", "--out", out.with_suffix(".svg"))
    assert status == 0
    status, printed, _ = run(capsys, "colour", path, "--quantity", "hemispherical", "--json")
    assert status == 0 and json.loads(printed)["quantity"] == "hemispherical"
    np.testing.assert_allclose(json.loads(printed)["XYZ"], sphere.colour("hemispherical").XYZ)
    measured = write_measured(files["folder"] / "hemi.csv", sphere.wavelengths, sphere.hemispherical)
    status, printed, _ = run(capsys, "compare", path, measured, "--json")
    data = json.loads(printed)
    assert status == 0 and data["quantity"] == "reading"
    np.testing.assert_allclose(data["residuals"], sphere.instrument_error, atol=1e-15)  # reading − hemispherical
    interval = sphere.reading_interval
    assert np.all(np.array(data["certified_mu"]) >= np.maximum(sphere.reading - interval[:, 0],
                                                               interval[:, 1] - sphere.reading) - 1e-15)
    status, printed, _ = run(capsys, "compare", path, measured, "--quantity", "corrected", "--json")
    assert status == 0 and json.loads(printed)["quantity"] == "corrected"
    np.testing.assert_allclose(json.loads(printed)["simulated"], sphere.corrected())  # the theory's inverse
    (files["folder"] / "comparison.json").write_text(printed)  # what --json prints is the comparison's file
    import virtspec_mi as vm

    back, data = vm.read_result(files["folder"] / "comparison.json"), json.loads(printed)
    data.pop("checksum")
    assert type(back) is vm.Comparison and back.quantity == "corrected"
    assert json.dumps(back.as_dict(), sort_keys=True) == json.dumps(data, sort_keys=True)
    err = one_line_error(capsys, "colour", path, "--quantity", "absorptance")
    assert "quantity must be one of reading, corrected, hemispherical (got 'absorptance'): a sphere reading" in err


def test_sel_picks_a_parameter_point_and_an_angle_of_any_kind(files, capsys):
    grid, path = files["sphere grid"]
    err = one_line_error(capsys, "colour", path)
    assert "select one parameter point first, e.g. result.isel(point=0) (on the command line: --sel point=0)" in err
    status, printed, _ = run(capsys, "colour", path, "--sel", "point=1", "--sel", "theta_i=8", "--json")
    assert status == 0
    np.testing.assert_allclose(json.loads(printed)["XYZ"], grid.sel(point=1, theta_i=8).colour().XYZ)
    sweep, lut = files["sweep"]
    status, printed, note = run(capsys, "colour", lut, "--sel", "specimen.thickness=1.6e-4", "--sel", "theta_i=29",
                                "--json")
    assert status == 0 and "took the nearest label, 0.0002" in note and "took the nearest label, 30" in note
    np.testing.assert_allclose(json.loads(printed)["XYZ"],
                               sweep.sel(theta_i=30, **{"specimen.thickness": 2e-4}).colour().XYZ)
    assert "--sel takes NAME=VALUE (got 'theta_i')" in one_line_error(capsys, "colour", lut, "--sel", "theta_i")
    assert "--sel theta_i takes a number (got 'x')" in one_line_error(capsys, "colour", lut, "--sel", "theta_i=x")


def test_a_figure_never_replaces_the_file_it_draws(tmp_path, capsys):
    """The figure's name reaching the result or the measured file (a link here) is refused before anything is read."""

    result = hemispherical_grid().write(tmp_path / "r.json")
    before = result.read_bytes()
    (tmp_path / "fig.png").symlink_to(result)
    err = one_line_error(capsys, "plot", result, "--out", tmp_path / "fig.png")
    assert f"--out {tmp_path / 'fig.png'} is FILE {result}" in err
    measured = write_measured(tmp_path / "m.csv", [400, 500], [0.2, 0.3])
    (tmp_path / "cmp.svg").symlink_to(measured)
    err = one_line_error(capsys, "compare", result, measured, "--plot", tmp_path / "cmp.svg")
    assert "is MEASURED" in err and result.read_bytes() == before and measured.read_text().startswith("wavelength")
