"""
A target certified at every θi (applications/targets/sweep.py): ``virtspec sweep --target``
gives ``vm.sweep(scene, target=...)``'s results, keeps its batches in ``--checkpoint`` and
resumes from it after an interruption to the same results, and refuses what it does not take.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from killed_runs import Interrupting
from virtspec_mi.cli import main

ARGV = ["sweep", "diamond_collimated", "--theta-i", "0", "45", "--target", "band:B04,tolerance=0.05", "--seed", "1",
        "--bound", "betting"]


def _values(data: dict) -> list:
    return [(angle["values"], angle["rays"], angle["pilot_rays"], angle["batches"]) for angle in data["results"]]


def test_the_command_line_sweep_is_the_apis(mi, capsys):
    assert main([*ARGV, "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    result = vm.sweep("diamond_collimated", theta_i=[0, 45], target=vm.band("B04", tolerance=0.05), seed=1,
                      bound="betting")
    assert printed["theta_i"] == [0.0, 45.0] == list(result.theta_i)
    assert _values(printed) == _values(json.loads(result.sealed_json()))


def test_the_summary_names_every_angle(mi, capsys):
    assert main(ARGV) == 0
    out = capsys.readouterr().out
    assert "theta_i = 0 deg" in out and "theta_i = 45 deg" in out and "band_B04" in out


def test_an_interrupted_command_line_sweep_resumes_to_the_same_results(mi, tmp_path, capsys, monkeypatch):
    import virtspec_mi.instruments.hemispherical.allocated as allocated

    assert main([*ARGV, "--json"]) == 0
    whole = json.loads(capsys.readouterr().out)
    traces = Interrupting(monkeypatch, allocated, "trace_allocated", after=3)  # the second angle under way
    path = tmp_path / "sweep.json"
    assert main([*ARGV, "--json", "--checkpoint", str(path)]) == 130
    assert str(path) in capsys.readouterr().err and len(json.loads(path.read_text())["traces"]) == 3
    traces.calls, traces.after = 0, -1
    assert main([*ARGV, "--json", "--checkpoint", str(path)]) == 0
    resumed = json.loads(capsys.readouterr().out)
    assert _values(resumed) == _values(whole) and not path.exists()
    assert traces.calls == sum(len(angle["batches"]) + 1 for angle in whole["results"]) - 3


@pytest.mark.parametrize("extra, message", [
    (["--out", "x.nc"], "--target takes none of --out"),
    (["--rays", "1000"], "--target takes none of --rays"),
    (["--workers", "2", "--checkpoint", "c.json"], "checkpoint and workers"),
])
def test_what_a_targets_sweep_does_not_take_is_refused_naming_the_flag(mi, tmp_path, capsys, monkeypatch, extra,
                                                                       message):
    monkeypatch.chdir(tmp_path)
    assert main([*ARGV, *extra]) != 0
    assert message in capsys.readouterr().err
    assert not (tmp_path / "x.nc").exists()


@pytest.mark.parametrize("command", ["measure", "sweep"])
def test_a_checkpoint_without_a_target_names_both_flags(mi, tmp_path, capsys, command):
    assert main([command, "diamond_collimated", "--checkpoint", str(tmp_path / "c.json"), "--mu", "0.01"]) != 0
    err = capsys.readouterr().err
    assert "--checkpoint acts only with --target: give --target too" in err and "--mu" not in err


def test_target_sweep_resolves_the_scenes_angle(mi):
    from virtspec_mi.applications.targets.sweep import target_sweep
    from virtspec_mi.runtime.scene import loaded

    result = target_sweep(loaded("diamond_collimated"), vm.band("B04", tolerance=0.05), {"seed": 1})
    scene_theta = vm.measure("diamond_collimated", wavelengths=[550], rays=10).coords["theta_i"]
    assert np.allclose(result.theta_i, np.atleast_1d(scene_theta))
