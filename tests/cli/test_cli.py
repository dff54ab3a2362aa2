"""Tests of the ``virtspec`` command line (run as a real process)."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest


def virtspec(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "virtspec_mi.cli", *args], capture_output=True, text=True)


def test_bounds_prints_table_1():
    result = virtspec("bounds", "--mu", "0.005", "--delta", "0.001", "0.01", "0.1")
    assert result.returncode == 0
    assert "105,967" in result.stdout and "10,000,000" in result.stdout and "152,019" in result.stdout
    assert "5.03" in result.stdout and "truncated" in result.stdout


def test_measure_prints_a_certified_conical_reading(scenes_dir):
    result = virtspec("measure", str(scenes_dir / "diamond_conical.xml"), "--theta-i", "70")
    assert result.returncode == 0, result.stderr
    assert "conical reading, theta_i = 70 deg" in result.stdout and "N = 105,967" in result.stdout


def test_measure_json_has_every_field(scenes_dir):
    result = virtspec(
        "measure", str(scenes_dir / "diamond_collimated.xml"), "--theta-i", "30", "--wavelengths",
        "400:600:100", "700", "--rays", "5000", "--seed", "3", "--sampling", "random", "--json",
    )
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["wavelengths"] == [400.0, 500.0, 600.0, 700.0]
    assert data["rays"] == [5000] * 4 and data["settings"]["seed"] == 3
    assert data["settings"]["beam"] == "collimated" and data["settings"]["theta_i"] == 30.0
    for r, t, a in zip(data["reflected"], data["transmitted"], data["absorbed"]):
        assert r + t + a == 5000


@pytest.mark.parametrize(
    "args, message",
    [
        (["--theta-i", "91"], "theta_i must satisfy 0 <= theta_i <= 90"),
        (["--mu", "0.6"], "mu must satisfy 0 < mu < 0.5"),
        (["--delta", "0"], "delta must satisfy 0 < delta < 1"),
        (["--wavelengths", "-5"], "wavelengths must be finite and > 0"),
        (["--rays", "0"], "rays must satisfy 1 <= rays"),
    ],
)
def test_measure_bad_input_is_one_clear_line(scenes_dir, args, message):
    result = virtspec("measure", str(scenes_dir / "diamond_conical.xml"), *args)
    assert result.returncode == 1
    assert result.stderr.strip().startswith("virtspec: error:") and message in result.stderr
    assert "Traceback" not in result.stderr


def test_measure_missing_scene_file(tmp_path):
    result = virtspec("measure", str(tmp_path / "none.xml"))
    assert result.returncode == 1 and "scene file not found" in result.stderr


# --- sweep and colour ---------------------------------------------------------------------


def test_sweep_writes_the_file_and_plot_and_colour_reads_it(scenes_dir, tmp_path, capsys):
    out, figure = tmp_path / "sweep.nc", tmp_path / "sweep.png"
    result = virtspec("sweep", str(scenes_dir / "diamond_collimated.xml"), "--theta-i", "0:90:45",
                      "--wavelengths", "400:700:100", "--rays", "2000", "--out", str(out), "--plot", str(figure))
    assert result.returncode == 0, result.stderr
    assert "collimated sweep: 3 theta_i x 4 wavelengths" in result.stdout and f"written: {out}" in result.stdout
    assert result.stderr == ""  # no progress bar: not a terminal
    assert figure.read_bytes()[:4] == b"\x89PNG"
    from virtspec_mi.api import read_result as read_sweep

    saved = read_sweep(out)
    assert saved.reflectance.shape == (4, 3) and saved.settings.seed == 0
    colour = virtspec("colour", str(out), "--theta-i", "45")
    assert colour.returncode == 0, colour.stderr
    assert "illuminant D65" in colour.stdout and "Lab  =" in colour.stdout
    assert "Lab  =" in colour.stdout and "sRGB =" in colour.stdout
    # the grey diamond: a* = b* = 0
    lab = [float(v) for v in colour.stdout.split("Lab  =")[1].split()[:3]]
    assert abs(lab[1]) < 1e-6 and abs(lab[2]) < 1e-6
    from virtspec_mi.cli import main  # in-process: one more interpreter start would add ~1.5 s

    assert main(["colour", str(out)]) == 1
    assert "theta_i must be given" in capsys.readouterr().err


def test_sweep_densities_print_seconds_and_delta(scenes_dir):
    result = virtspec("sweep", str(scenes_dir / "diamond_collimated.xml"), "--theta-i", "0:90:1",
                      "--densities", "2", "3", "--quiet")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert "Delta (eq. 24)" in lines[0]
    assert lines[1].split()[:2] == ["2", "100"] and lines[2].split()[:2] == ["3", "1,000"]
    assert 0.005 < float(lines[2].split()[3]) < 0.2  # Delta between 100 and 1000 rays per reading
    # Fig. 6b: no density's seconds include the kernel's compilation (a warm-up sweep ran first)
    assert lines[3].startswith("(seconds after a warm-up sweep at log10 N = 2")


@pytest.mark.parametrize("args, message", [
    (["--theta-i", "0:100:10"], "theta_i must satisfy 0 <= theta_i <= 90"),
    (["--theta-i", "10", "--out", "x.txt"], "out must end in one of .nc, .csv, .json, .zarr"),
    (["--theta-i", "10", "--plot", "x.pdf"], "plot must end in one of .png, .svg"),
])
def test_sweep_bad_input_is_one_line_error(scenes_dir, args, message):
    result = virtspec("sweep", str(scenes_dir / "diamond_collimated.xml"), *args)
    assert result.returncode == 1
    assert result.stderr.startswith("virtspec: error: ") and message in result.stderr


def test_colour_reads_colour_science_csv_spectra(diamond, tmp_path, capsys):
    import virtspec_mi as vm
    from virtspec_mi.cli import main
    from virtspec_mi.results.io import write_spectra_csv

    result = vm.sweep(diamond, theta_i=[20], wavelengths="380:780:20", rays=2000)
    path = write_spectra_csv(result, tmp_path / "spectra.csv")
    assert main(["colour", str(path), "--quantity", "transmittance"]) == 0
    printed = capsys.readouterr().out
    assert f"transmittance of {path}" in printed and "Lab  =" in printed
    assert main(["colour", str(path), "--quantity", "colour"]) == 1
    assert "quantity must be one of the file's columns" in capsys.readouterr().err


@pytest.mark.parametrize("bound, rays", [("exact", [66_501]), ("two-stage", None)])
def test_measure_bounds_and_intervals_in_json(scenes_dir, bound, rays):
    result = virtspec("measure", str(scenes_dir / "diamond_collimated.xml"), "--theta-i", "10",
                      "--bound", bound, "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["bound"] == bound and data["settings"]["bound"] == bound
    if rays is not None:
        assert data["rays"] == rays and data["pilot_rays"] is None
    else:
        assert data["pilot_rays"] == [2000] and data["rays_spent"][0] == data["rays"][0] + 2000
    low, high = data["reflectance_interval"][0]
    assert low <= data["reflectance"][0] <= high


def test_measure_joint_and_pilot_options(scenes_dir):
    result = virtspec("measure", str(scenes_dir / "diamond_collimated.xml"), "--bound", "two-stage",
                      "--mu", "0.05", "--delta", "0.2", "--joint", "--pilot-rays", "150", "--pilot-delta", "0.05")
    assert result.returncode == 0, result.stderr
    assert "+ 150 pilot" in result.stdout and "R and T together" in result.stdout
    bad = virtspec("measure", str(scenes_dir / "diamond_collimated.xml"), "--pilot-delta", "0.5")
    assert bad.returncode == 1 and "pilot_delta must satisfy 0 < pilot_delta < delta" in bad.stderr


# --- the command line as a newcomer meets it ----------------------------------------------


def test_version_and_python_dash_m():
    import virtspec_mi

    for command in ([sys.executable, "-m", "virtspec_mi", "--version"],
                    [sys.executable, "-m", "virtspec_mi.cli", "--version"]):
        result = subprocess.run(command, capture_output=True, text=True)
        assert result.returncode == 0 and result.stdout.strip() == f"virtspec-mi {virtspec_mi.__version__}"


def test_a_closed_pipe_ends_the_command_quietly():
    result = subprocess.run(f"{sys.executable} -m virtspec_mi bounds | head -1", shell=True,
                            capture_output=True, text=True)
    assert result.stdout.startswith("Rays per reading") and result.stderr == ""


def test_bounds_shows_every_budget():
    result = virtspec("bounds", "--delta", "0.01")
    assert result.returncode == 0
    assert all(name in result.stdout for name in ("hoeffding", "chebyshev", "exact", "two-stage"))
    assert "66,501" in result.stdout and "2,000 + at most" in result.stdout


@pytest.mark.parametrize("command", ["bounds", "measure", "sweep", "gonio", "colour", "llvm"])
def test_every_subcommand_has_a_description_and_an_example(command):
    text = re.sub(r"-\s+", "-", virtspec(command, "--help").stdout)  # argparse wraps at hyphens
    assert "example" in text and f"virtspec {command}" in text.split("example", 1)[1]
    if command in ("measure", "sweep", "gonio"):
        assert "conical-hemispherical" in text and "directional-hemispherical" in text
        assert "hemispherical-hemispherical" in text and "default: the scene's" in text
    if command == "colour":
        assert "absorptance" in text


@pytest.mark.parametrize("args, message", [
    (["sweep", "SCENE", "--theta-i", "0", "--densities", "inf"], "densities must satisfy 0 <= log10 N <= 9.63"),
    (["sweep", "SCENE", "--theta-i", "0", "--densities", "nan"], "densities must satisfy"),
    (["sweep", "SCENE", "--theta-i", "0", "--densities", "1e300"], "densities must satisfy"),
    (["colour", "SCENE"], "file must end in one of .nc, .csv, .json, .zarr (a virtspec-mi result file"),
    (["measure", "DIRECTORY"], "is a directory; give a Mitsuba XML scene file"),
    (["measure", "MISSPELT"], "'thetai' is not a setting: did you mean 'theta_i'?"),
])
def test_bad_input_gets_one_line_that_names_it(scenes_dir, tmp_path, args, message):
    misspelt = tmp_path / "misspelt.xml"
    misspelt.write_text((scenes_dir / "diamond_conical.xml").read_text().replace(
        '<float name="theta_i"', '<float name="thetai"'))
    where = {"SCENE": str(scenes_dir / "diamond_collimated.xml"), "DIRECTORY": str(tmp_path),
             "MISSPELT": str(misspelt)}
    result = virtspec(*[where.get(a, a) for a in args])
    assert result.returncode == 1 and result.stderr.startswith("virtspec: error: "), result.stderr
    assert message in result.stderr and "Traceback" not in result.stderr


@pytest.mark.parametrize("args, message", [
    (["--theta-i", "0", "30"], "unrecognized arguments: 30; measure takes one angle: for several, virtspec sweep SCENE "
                               "--theta-i 0 30"),
    (["--theta-i", "0:30:10"], "--theta-i: theta_i must be a number (got '0:30:10'); measure takes one angle"),
    (["--wavelengths", "400-700"], "wavelengths must be a number (got '400-700'); a range is start:stop:step, "
                                   "e.g. 400:700:10"),
    (["--wavelengths", "400", "abc"], "(got 'abc'); write numbers separated by commas or spaces (450,550,650) or "
                                      "start:stop:step ranges (400:700:10)"),
])
def test_a_newcomers_slip_gets_the_form_to_use(args, message):
    result = virtspec("measure", "diamond_conical", *args, "--rays", "100")
    assert result.returncode in (1, 2) and message in result.stderr, result.stderr
    assert "Traceback" not in result.stderr


def test_csv_plain_writes_a_spreadsheet_table_beside_the_result(tmp_path):
    import pandas as pd

    result = virtspec("measure", "diamond_conical", "--theta-i", "70", "--wavelengths", "450,550", "--rays", "1000",
                      "--out", str(tmp_path / "r.nc"), "--csv-plain", str(tmp_path / "r.csv"))
    assert result.returncode == 0, result.stderr
    assert f"written: {tmp_path / 'r.csv'}" in result.stdout
    table = pd.read_csv(tmp_path / "r.csv")
    assert table["wavelength"].tolist() == [450.0, 550.0] and table["rays"].tolist() == [1000, 1000]
    quiet = virtspec("sweep", "diamond_conical", "--theta-i", "0", "70", "--wavelengths", "550", "--rays", "500",
                     "--quiet", "--csv-plain", str(tmp_path / "s.csv"))
    assert quiet.returncode == 0 and pd.read_csv(tmp_path / "s.csv")["theta_i"].tolist() == [0.0, 70.0]
    same = virtspec("measure", "diamond_conical", "--out", str(tmp_path / "r.csv"), "--csv-plain",
                    str(tmp_path / "r.csv"))
    assert same.returncode == 1 and "is also --out" in same.stderr


def test_a_very_long_file_name_is_not_echoed_whole(tmp_path):
    long = "a" * 5000
    result = virtspec("measure", long)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert result.stderr.startswith("virtspec: error: SCENE: a file or folder name holds at most ")  # the argument named
    assert "bytes here (got aaaa" in result.stderr and "(5,000 characters)" in result.stderr
    assert len(result.stderr) < 320 and "[Errno" not in result.stderr and "give a shorter name" in result.stderr
