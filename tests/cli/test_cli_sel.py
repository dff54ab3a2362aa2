"""
``--sel NAME=VALUE`` of ``virtspec plot|colour|compare`` on files written by the measuring
subcommands: a goniophotometer reading over θi × explicit parameter points and a sphere
reading over θi × a parameter grid — every dim of each kind is selectable (the nearest
label, said on stderr when it differs), and the selected readings are the API's.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.cli import main

FLAGS = {
    "gonio": ["scenes/diamond_collimated.xml", "--theta-i", "0", "45", "--wavelengths", "400:700:50", "--rays", "2000",
              "--theta-o-bins", "2", "--phi-o-bins", "2", "--param", "specimen.eta=1.5,2.4", "--points"],
    "sphere": ["scenes/sphere_150mm_8d.xml", "--theta-i", "6", "10", "--wavelengths", "400:700:50", "--rays", "2000",
               "--param", "specimen.reflectance=0.2,0.5"],
}


@pytest.fixture(scope="module")
def files(mi, scenes_dir, tmp_path_factory):
    """A file of each kind written by its subcommand, and the result it holds."""

    folder = tmp_path_factory.mktemp("sel")
    written = {}
    for command, flags in FLAGS.items():
        out = folder / f"{command}.nc"
        assert main([command, str(scenes_dir.parent / flags[0]), *flags[1:], "--out", str(out), "--quiet"]) == 0
        written[command] = (vm.read_result(out), out)
    return written


def run(capsys, *args):
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def test_sel_of_a_gonio_file_picks_a_point_and_an_angle(files, capsys, tmp_path):
    reading, path = files["gonio"]
    assert reading.dims[:3] == ("wavelength", "theta_i", "point")
    status, out, note = run(capsys, "colour", path, "--sel", "point=1", "--sel", "theta_i=40", "--json")
    assert status == 0 and "--sel theta_i=40 took the nearest label, 45" in note
    np.testing.assert_allclose(json.loads(out)["XYZ"], reading.isel(point=1).result.colour(theta_i=45).XYZ)
    picked = reading.isel(point=0).sel(theta_i=0)
    measured = tmp_path / "r.csv"
    measured.write_text("wavelength,reflectance\n" + "".join(
        f"{w:g},{v!r}\n" for w, v in zip(picked.wavelengths, picked.result.reflectance.ravel())))
    status, out, _ = run(capsys, "compare", path, measured, "--sel", "point=0", "--sel", "theta_i=0", "--json")
    assert status == 0 and json.loads(out)["rmse"] == 0
    figure = tmp_path / "lobes.png"
    status, out, _ = run(capsys, "plot", path, "--sel", "point=1", "--sel", "wavelength=550", "--out", figure)
    assert status == 0 and figure.read_bytes()[:4] == b"\x89PNG" and "drew the lobes" not in out


def test_sel_of_a_sphere_file_picks_a_parameter_and_an_angle(files, capsys, tmp_path):
    result, path = files["sphere"]
    assert result.reading_dims == ("wavelength", "theta_i", "specimen.reflectance")
    status, out, _ = run(capsys, "colour", path, "--sel", "specimen.reflectance=0.5", "--sel", "theta_i=10",
                         "--quantity", "hemispherical", "--json")
    assert status == 0
    chosen = result.sel(theta_i=10, **{"specimen.reflectance": 0.5})
    np.testing.assert_allclose(json.loads(out)["XYZ"], chosen.colour("hemispherical").XYZ)
    measured = tmp_path / "m.csv"
    measured.write_text("wavelength,reflectance\n" + "".join(
        f"{w:g},{v!r}\n" for w, v in zip(chosen.wavelengths, chosen.reading)))
    status, out, _ = run(capsys, "compare", path, measured, "--sel", "specimen.reflectance=0.5", "--sel",
                         "theta_i=10", "--json")
    assert status == 0 and json.loads(out)["rmse"] == 0
    figure = tmp_path / "sphere.svg"
    status, out, note = run(capsys, "plot", path, "--sel", "specimen.reflectance=0.3", "--sel", "theta_i=6",
                            "--out", figure)
    assert status == 0 and figure.is_file() and "took the nearest label, 0.2" in note
    status, _, err = run(capsys, "colour", path, "--sel", "theta_i=6")
    assert status == 1 and "(on the command line: --sel specimen.reflectance=0.2)" in err
