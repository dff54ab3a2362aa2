"""
``virtspec gonio`` and ``virtspec sphere`` with ``--workers 2`` (a local Dask cluster of
two processes) give the counts of the same readings taken in this process (slow).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import virtspec_mi as vm
from virtspec_mi.cli import main

ROOT = Path(__file__).resolve().parents[2]


def printed_json(capsys, *args) -> dict:
    assert main([str(a) for a in args]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.slow
def test_gonio_on_two_workers_gives_the_in_process_counts(mi, capsys):
    scene = ROOT / "scenes" / "soybean_abmb.xml"
    flags = ["--theta-i", "0", "30", "60", "--wavelengths", "550", "650", "--rays", "5000", "--theta-o-bins", "3",
             "--phi-o-bins", "4", "--fold-phi", "--param", "specimen.thickness=1.2e-4,2e-4"]
    there = printed_json(capsys, "gonio", scene, *flags, "--workers", "2", "--task-readings", "2", "--json")
    here = vm.gonio(str(scene), theta_i=[0, 30, 60], wavelengths=[550, 650], rays=5000, theta_o_bins=3, phi_o_bins=4,
                    fold_phi=True, parameters={"specimen.thickness": [1.2e-4, 2e-4]}, progress=False)
    assert there["bin_counts"] == here.bin_counts.tolist()
    for name in ("rays", "reflected", "transmitted", "absorbed"):
        assert there["result"][name] == getattr(here.result, name).tolist(), name


@pytest.mark.slow
def test_sphere_on_two_workers_gives_the_in_process_counts(mi, capsys):
    scene = ROOT / "scenes" / "sphere_150mm_8d.xml"
    there = printed_json(capsys, "sphere", scene, "--wavelengths", "400:700:50", "--rays", "20000", "--workers", "2",
                         "--json")
    here = vm.sphere_measure(str(scene), wavelengths="400:700:50", rays=20_000, progress=False)
    assert there["counts"] == here.as_dict()["counts"]
