"""
A goniophotometer and a sphere run of ``virtspec`` killed with SIGKILL mid-run and run
again with the same command line (``--out FILE``: finished readings kept in
``FILE.partial.json``) give exactly the counts of the API's uninterrupted run (slow).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

import virtspec_mi as vm
from killed_runs import kill_then_resume
from result_kinds import counts

SCENES = Path(__file__).resolve().parents[2] / "scenes"

RUNS = {
    "gonio": (["--theta-i", "0:90:1", "--rays", "200000", "--theta-o-bins", "6", "--phi-o-bins", "8",
               "--param", "specimen.eta=1.5,2.4"], "diamond_collimated.xml", 91 * 2, vm.gonio,
              dict(theta_i="0:90:1", rays=200_000, theta_o_bins=6, phi_o_bins=8,
                   parameters={"specimen.eta": [1.5, 2.4]})),
    "sphere": (["--wavelengths", "400:2500:20", "--rays", "40000", "--seed", "2", "--method", "comparison",
                "-D", "wall_reflectance=0.95"], "sphere_150mm_8d.xml", 2 * 106, vm.sphere_measure,
               dict(wavelengths="400:2500:20", rays=40_000, seed=2, method="comparison",
                    defines={"wall_reflectance": "0.95"})),
}
"""Per subcommand: its flags, its scene, its readings, and the same as an API call."""


@pytest.mark.slow
@pytest.mark.parametrize("command", list(RUNS))
def test_a_killed_run_resumes_to_the_uninterrupted_counts(command, mi, tmp_path):
    flags, scene, readings, function, keywords = RUNS[command]
    out = tmp_path / f"{command}.nc"
    kill_then_resume([sys.executable, "-m", "virtspec_mi.cli", command, str(SCENES / scene), *flags, "--quiet",
                      "--out", str(out)], out, readings, tmp_path)
    whole = function(str(SCENES / scene), progress=False, **keywords)
    resumed = vm.read_result(out)
    assert resumed.dims == whole.dims and counts(resumed.as_dict()) == counts(whole.as_dict())
