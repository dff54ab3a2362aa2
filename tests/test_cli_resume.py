"""
A goniophotometer and a sphere run of ``virtspec`` killed with SIGKILL mid-run and run
again with the same command line (``--out FILE``: finished readings kept in
``FILE.partial.json``) give exactly the counts of the API's uninterrupted run (slow).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from killed_runs import kill_then_resume

ROOT = Path(__file__).resolve().parents[1]

_ROUGH_XML = """<scene version="3.0.0">
    <shape type="disk" id="emitter"><transform name="to_world"><rotate x="1" angle="180"/><scale value="8"/>
        <translate z="100"/></transform></shape>
    <shape type="disk" id="specimen"><transform name="to_world"><scale value="12.5"/></transform>
        <bsdf type="roughdielectric"><float name="alpha" value="0.3"/><float name="int_ior" value="1.5"/></bsdf></shape>
</scene>"""

CLI = [sys.executable, "-m", "virtspec_mi.cli"]


@pytest.mark.slow
def test_a_killed_gonio_parameter_sweep_resumes_to_the_uninterrupted_counts(mi, tmp_path):
    scene = tmp_path / "rough.xml"
    scene.write_text(_ROUGH_XML)
    out = tmp_path / "gonio.nc"
    command = [*CLI, "gonio", str(scene), "--theta-i", "0:80:4", "--wavelengths", "400:700:100", "--rays", "200000",
               "--theta-o-bins", "6", "--phi-o-bins", "8", "--param", "specimen.alpha=0.2,0.4", "--quiet",
               "--out", str(out)]
    kill_then_resume(command, out, 21 * 4 * 2, tmp_path)
    resumed = vm.read_result(out)
    whole = vm.gonio(str(scene), theta_i="0:80:4", wavelengths="400:700:100", rays=200_000, theta_o_bins=6,
                     phi_o_bins=8, parameters={"specimen.alpha": [0.2, 0.4]}, progress=False)
    assert resumed.dims == whole.dims
    np.testing.assert_array_equal(resumed.bin_counts, whole.bin_counts)
    for name in ("reflected", "transmitted", "absorbed", "rays"):
        np.testing.assert_array_equal(getattr(resumed.result, name), getattr(whole.result, name))


@pytest.mark.slow
def test_a_killed_sphere_spectrum_resumes_to_the_uninterrupted_counts(mi, tmp_path):
    scene = ROOT / "scenes" / "sphere_150mm_8d.xml"
    out = tmp_path / "sphere.nc"
    command = [*CLI, "sphere", str(scene), "--wavelengths", "400:2500:20", "--rays", "40000", "--seed", "2",
               "--method", "comparison", "-D", "wall_reflectance=0.95", "--quiet", "--out", str(out)]
    kill_then_resume(command, out, 2 * 106, tmp_path)
    resumed = vm.read_result(out)
    whole = vm.sphere_measure(str(scene), wavelengths="400:2500:20", rays=40_000, seed=2, method="comparison",
                              defines={"wall_reflectance": "0.95"}, progress=False)
    for configuration in ("sample", "standard"):
        for name, values in whole.counts[configuration].items():
            np.testing.assert_array_equal(resumed.counts[configuration][name], values, err_msg=name)
