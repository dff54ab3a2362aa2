"""Tests of the ``virtspec`` command line (run as a real process)."""

from __future__ import annotations

import json
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
