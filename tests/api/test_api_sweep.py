"""
Tests of virtspec_mi.api.sweep: sweep(), its Result, fluctuation (eq. 24), resumable
checkpoints and the progress bar.

Statistical checks use fixed seeds and a union bound over the readings of a sweep:
each of n readings misses its tolerance with probability ≤ δ'/n, so the whole check
fails for a random seed with probability ≤ δ' (stated per test).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from killed_runs import kill_then_resume
from virtspec_mi.budgets.bounds import hoeffding_mu
from virtspec_mi.references.quadrature import fresnel_reflectance
from virtspec_mi.engine.checkpoint import CheckpointError

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def dielectric(mi):
    """Mitsuba's smooth dielectric (diamond): traced per wavelength."""

    return mi.load_dict(vm.instrument_scene({"type": "dielectric", "int_ior": 2.419, "ext_ior": 1.0}))


def test_fig5_sweep_is_fresnel_at_every_angle(diamond):
    result = vm.sweep(diamond, theta_i="0:90:1", beam="collimated", seed=0)
    assert result.reflectance.shape == (1, 91)
    np.testing.assert_array_equal(result.theta_i, np.arange(91.0))
    np.testing.assert_array_equal(result.rays, 105_967)
    # union bound over 91 readings: false-failure probability <= 1e-4 for a random seed
    tolerance = hoeffding_mu(105_967, 1e-4 / 91)
    expected = fresnel_reflectance(result.theta_i, 2.419)
    assert np.all(np.abs(result.reflectance[0] - expected) < tolerance)
    assert np.all(result.reflected + result.transmitted + result.absorbed == result.rays)
    assert result.seconds > 0 and result.settings.beam == "collimated"


def test_a_one_angle_sweep_equals_measure(dielectric):
    # reading k of a sweep owns rays [k N, (k + 1) N): at one angle those are measure's ranges
    kwargs = dict(wavelengths=[450, 550, 650], rays=5000, seed=4, beam="conical")
    result = vm.sweep(dielectric, theta_i=[35], **kwargs)
    reading = vm.measure(dielectric, theta_i=35, **kwargs)
    np.testing.assert_array_equal(result.reflected[:, 0], reading.reflected)
    np.testing.assert_array_equal(result.transmitted[:, 0], reading.transmitted)
    assert not result.wavelength_independent


def test_sweep_readings_have_independent_rays_and_are_chunk_invariant(dielectric):
    kwargs = dict(theta_i="0:80:20", wavelengths="400:700:100", rays=3000, seed=1)
    small = vm.sweep(dielectric, chunk_size=1024 * 5, **kwargs)
    large = vm.sweep(dielectric, **kwargs)
    np.testing.assert_array_equal(small.reflected, large.reflected)
    assert small.reflected.shape == (4, 5)
    # Mitsuba's dielectric is the same at every wavelength, yet each reading has its own rays
    assert len(np.unique(large.reflected[:, 0])) > 1


def test_wavelength_independent_specimen_is_traced_once_per_angle(diamond):
    result = vm.sweep(diamond, theta_i=[10, 50], wavelengths="400:700:50", rays=4000, seed=3)
    assert result.wavelength_independent
    assert np.all(result.reflected == result.reflected[0])  # every wavelength: the same counts
    assert result.reflected[0, 0] != result.reflected[0, 1]
    assert "traced once per theta_i" in result.summary()


@pytest.mark.parametrize("bad, message", [
    (dict(theta_i="0:100:10"), "theta_i must satisfy 0 <= theta_i <= 90"),
    (dict(theta_i=[]), "theta_i must hold at least one angle"),
    (dict(theta_i=[10, 10]), "theta_i of a sweep must be distinct"),
    (dict(theta_i=[10], wavelengths=[500, 500]), "wavelengths of a sweep must be distinct"),
    (dict(theta_i=[10], mu=0.7), "mu must satisfy"),
])
def test_bad_sweep_input_names_the_parameter(diamond, bad, message):
    with pytest.raises(ValueError, match=message):
        vm.sweep(diamond, **bad)


def test_fluctuation_is_eq_24():
    a = np.array([[0.1, 0.2, 0.3]])
    b = np.array([[0.15, 0.1, 0.3]])
    assert vm.fluctuation(a, b) == pytest.approx((0.05 + 0.1 + 0.0) / 3)
    with pytest.raises(ValueError, match="one shape"):
        vm.fluctuation(a, b[:, :2])


def test_fluctuation_shrinks_with_ray_density(diamond):
    # Fig. 6a: E|rho_N - rho| ~ sqrt(rho(1 - rho)/N), so Delta(1e3 vs 1e4) >> Delta(1e5 vs 1e6)
    sweeps = [vm.sweep(diamond, theta_i="0:90:1", beam="collimated", rays=10**d) for d in (3, 4, 5, 6)]
    deltas = [vm.fluctuation(a, b) for a, b in zip(sweeps, sweeps[1:])]
    assert deltas[0] > 3 * deltas[2]  # expected ratio ~ 10 (sqrt(100)); 3 leaves a wide margin
    with pytest.raises(ValueError, match="same theta_i"):
        vm.fluctuation(sweeps[0], vm.sweep(diamond, theta_i=[0, 1], rays=10))


# --- checkpoints and resume -------------------------------------------------------------


def _interrupting(monkeypatch, after: int):
    """Make the sweep's take_readings raise KeyboardInterrupt after ``after`` batches."""

    import virtspec_mi.engine.readings as engine

    real, calls = engine.trace_readings, []

    def flaky(*args, **kwargs):
        if len(calls) == after:
            raise KeyboardInterrupt
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(engine, "trace_readings", flaky)
    return calls


@pytest.mark.parametrize("specimen", ["dielectric", "diamond"])
def test_an_interrupted_sweep_resumes_to_the_uninterrupted_result(request, monkeypatch, tmp_path, specimen):
    scene = request.getfixturevalue(specimen)
    kwargs = dict(theta_i="0:90:10", wavelengths=[450, 550, 650], rays=2000, seed=8, chunk_size=1024 * 6)
    whole = vm.sweep(scene, **kwargs)
    checkpoint = tmp_path / "sweep.partial.json"
    calls = _interrupting(monkeypatch, after=2)
    with pytest.raises(KeyboardInterrupt):
        vm.sweep(scene, checkpoint=checkpoint, **kwargs)
    saved = json.loads(checkpoint.read_text())
    assert 0 < len(saved["done"]) < whole.rays.size
    monkeypatch.undo()
    resumed = vm.sweep(scene, checkpoint=checkpoint, **kwargs)
    for name in ("reflected", "transmitted", "absorbed", "rays"):
        np.testing.assert_array_equal(getattr(resumed, name), getattr(whole, name))
    assert not checkpoint.exists()  # removed once the sweep is complete
    assert len(calls) == 2


def test_a_mismatched_checkpoint_is_refused(diamond, monkeypatch, tmp_path):
    checkpoint = tmp_path / "sweep.partial.json"
    _interrupting(monkeypatch, after=1)
    kwargs = dict(theta_i="0:90:10", rays=2000, chunk_size=1024 * 2)
    with pytest.raises(KeyboardInterrupt):
        vm.sweep(diamond, checkpoint=checkpoint, **kwargs)
    monkeypatch.undo()
    with pytest.raises(CheckpointError, match=r"different sweep \(differs in: seed\)"):
        vm.sweep(diamond, checkpoint=checkpoint, seed=1, **kwargs)
    other = vm.instrument_scene({"type": "simple_dielectric", "eta": 1.5})
    with pytest.raises(CheckpointError, match="differs in: scene"):
        vm.sweep(other, checkpoint=checkpoint, **kwargs)
    assert checkpoint.exists()  # never overwritten by a mismatched run


@pytest.mark.parametrize("content", ["{not json", '{"format": "something else"}', "[]",
                                     '{"format": "virtspec-mi sweep checkpoint 1"}'])
def test_a_corrupt_checkpoint_is_refused(diamond, tmp_path, content):
    checkpoint = tmp_path / "sweep.partial.json"
    checkpoint.write_text(content)
    with pytest.raises(CheckpointError, match="corrupt|not a virtspec-mi sweep checkpoint"):
        vm.sweep(diamond, theta_i=[0, 10], rays=100, checkpoint=checkpoint)


@pytest.mark.slow
def test_killing_a_real_sweep_process_and_rerunning_gives_the_uninterrupted_result(tmp_path):
    scene = tmp_path / "dielectric.xml"
    scene.write_text((ROOT / "scenes" / "diamond_collimated.xml").read_text().replace(
        '<bsdf type="simple_dielectric">', '<bsdf type="dielectric"><float name="ext_ior" value="1"/>').replace(
        '<float name="eta" value="2.419"/>', '<float name="int_ior" value="2.419"/>'))
    command = [sys.executable, "-m", "virtspec_mi.cli", "sweep", str(scene), "--theta-i", "0:90:1",
               "--wavelengths", "400:700:50", "--rays", "100000", "--quiet"]
    out = tmp_path / "sweep.nc"
    kill_then_resume(command + ["--out", str(out)], out, 91 * 7, tmp_path)  # killed mid-sweep, then resumed
    subprocess.run(command + ["--out", str(tmp_path / "whole.nc")], cwd=tmp_path, check=True)
    from virtspec_mi.api import read_result as read_sweep

    resumed, whole = read_sweep(out), read_sweep(tmp_path / "whole.nc")
    for name in ("reflected", "transmitted", "absorbed", "rays"):
        np.testing.assert_array_equal(getattr(resumed, name), getattr(whole, name))
    assert resumed.settings == whole.settings


# --- progress ---------------------------------------------------------------------------


def test_progress_bar_only_when_asked_or_in_a_slow_terminal_sweep(diamond, capsys):
    vm.sweep(diamond, theta_i="0:90:30", rays=1000, chunk_size=1024, progress=True)
    assert "readings" in capsys.readouterr().err  # the bar
    vm.sweep(diamond, theta_i="0:90:30", rays=1000, chunk_size=1024)  # stderr is not a terminal
    assert capsys.readouterr().err == ""
    vm.sweep(diamond, theta_i="0:90:30", rays=1000, chunk_size=1024, progress=False)
    assert capsys.readouterr().err == ""


def test_progress_bar_in_a_terminal_when_the_sweep_is_expected_to_be_slow(diamond, capsys, monkeypatch):
    import virtspec_mi.engine.progress as progress

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    vm.sweep(diamond, theta_i="0:90:10", rays=1000, chunk_size=1024)  # ~ms: under the 2 s threshold
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(progress, "_PROGRESS_AFTER_S", 0.0)  # now every sweep counts as slow
    vm.sweep(diamond, theta_i="0:90:10", rays=1000, chunk_size=1024)
    assert "readings" in capsys.readouterr().err  # the bar


# --- ray budgets in sweeps ---------------------------------------------------------------


def test_two_stage_sweep_sizes_each_reading_and_matches_measure(mi, tmp_path):
    """Two-stage sweeps: each reading its own N2, batched; the sweep's first reading equals
    measure()'s (both start at ray 0; later readings sit at the sweep's stride)."""

    scene = mi.load_dict(vm.instrument_scene({"type": "dielectric", "int_ior": 2.419, "ext_ior": 1.0}))
    kwargs = dict(wavelengths=[450, 650], beam="collimated", bound="two-stage", mu=0.02, delta=0.05, seed=5)
    result = vm.sweep(scene, theta_i=[0, 60, 85], **kwargs)
    assert len(set(result.rays.ravel().tolist())) > 1  # sized per reading from its own pilot
    single = vm.measure(scene, theta_i=0, **kwargs)
    assert result.rays[0, 0] == single.rays[0] and result.reflected[0, 0] == single.reflected[0]
    # every interval holds its estimate, at the sweep's delta, and goes into the files
    lower, upper = result.interval("reflectance")
    assert np.all((lower <= result.reflectance) & (result.reflectance <= upper))
    assert lower[0, 0] == single.reflectance_interval[0, 0]
    dataset = result.to_dataset()
    np.testing.assert_array_equal(dataset["transmittance_upper"].values, result.interval("transmittance")[1])
    assert dataset["reflectance_lower"].attrs["clopper_pearson_delta"] == 0.05
    for suffix, column in ((".csv", "absorptance_upper"), (".json", "absorptance_interval")):
        path = result.write(tmp_path / f"two_stage{suffix}")
        assert column in path.read_text()


def test_sweep_warns_when_the_certificate_does_not_hold(mi):
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": 1.5})
    with pytest.warns(RuntimeWarning, match="outside \\[0, 1\\]"):
        result = vm.sweep(scene, theta_i=[10, 20], rays=500)
    assert result.weight_violations.sum() == 1000


# --- outputs: nothing finished is lost ----------------------------------------------------


def _finished(checkpoint: Path) -> int:
    return len(json.loads(checkpoint.read_text())["done"])


def test_sweep_out_writes_the_file_and_then_removes_the_checkpoint(diamond, tmp_path):
    kwargs = dict(theta_i="0:90:10", rays=2000, chunk_size=1024 * 2)
    out = tmp_path / "sweep.json"
    result = vm.sweep(diamond, out=out, **kwargs)
    np.testing.assert_array_equal(vm.read_result(out).reflected, result.reflected)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep.json"]


@pytest.mark.parametrize("fault", ["directory appears", "disk full at rename", "disk full mid-write"])
def test_a_failed_output_write_keeps_every_finished_reading(diamond, monkeypatch, tmp_path, fault):
    import errno

    import virtspec_mi.engine.readings as engine
    import virtspec_mi.results.io as results_io

    kwargs = dict(theta_i="0:90:10", rays=2000, seed=6, chunk_size=1024 * 2)
    whole = vm.sweep(diamond, **kwargs)
    out = tmp_path / "sweep.csv"
    checkpoint = tmp_path / "sweep.csv.partial.json"
    with monkeypatch.context() as patch:
        if fault == "directory appears":  # e.g. another program made a directory of that name meanwhile
            real = engine.trace_readings

            def making_a_directory(*args, **kw):
                out.mkdir(exist_ok=True)
                return real(*args, **kw)

            patch.setattr(engine, "trace_readings", making_a_directory)
        elif fault == "disk full at rename":
            real_replace = os.replace

            def full(source, target):
                if Path(target) == out:
                    raise OSError(errno.ENOSPC, "No space left on device")
                return real_replace(source, target)

            patch.setattr(results_io.os, "replace", full)
        else:
            real_write = Path.write_text

            def half_written(self, text, *args, **kw):
                if ".partial.json" in self.name:  # the checkpoint's own writes go through
                    return real_write(self, text, *args, **kw)
                with open(self, "w") as handle:
                    handle.write(text[: len(text) // 2])
                raise OSError(errno.ENOSPC, "No space left on device")

            patch.setattr(Path, "write_text", half_written)
        with pytest.raises(OSError, match=f"could not write {out}.*kept in {checkpoint}"):
            vm.sweep(diamond, out=out, **kwargs)
    assert _finished(checkpoint) == 10  # the whole sweep is still on disk
    assert not out.is_file()
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp") or p.name.endswith(".lock")]
    if out.is_dir():
        out.rmdir()
    with monkeypatch.context() as patch:  # the re-run traces nothing: every reading is reused
        patch.setattr(engine, "trace_readings", lambda *a, **k: pytest.fail("traced again"))
        resumed = vm.sweep(diamond, out=out, **kwargs)
    for name in ("reflected", "transmitted", "rays"):
        np.testing.assert_array_equal(getattr(vm.read_result(out), name), getattr(whole, name))
        np.testing.assert_array_equal(getattr(resumed, name), getattr(whole, name))
    assert not checkpoint.exists()


def test_an_output_that_cannot_be_written_fails_before_any_tracing(diamond, monkeypatch, tmp_path):
    import virtspec_mi.engine.readings as engine

    monkeypatch.setattr(engine, "trace_readings", lambda *a, **k: pytest.fail("traced before the check"))
    (tmp_path / "taken.nc").mkdir()
    (tmp_path / "file").write_text("")
    for out, message in ((tmp_path / "taken.nc", "is a directory"),
                         (tmp_path / "missing" / "a.nc", "does not exist"),
                         (tmp_path / "file" / "a.nc", "is not a directory"),
                         (tmp_path / "a.txt", "out must end in one of")):
        with pytest.raises(ValueError, match=message):
            vm.sweep(diamond, theta_i=[0, 10], rays=100, out=out)


def test_a_resumed_sweep_says_so_on_stderr(diamond, monkeypatch, tmp_path, capsys):
    kwargs = dict(theta_i="0:90:10", rays=2000, chunk_size=1024 * 2)
    checkpoint = tmp_path / "sweep.partial.json"
    _interrupting(monkeypatch, after=3)
    with pytest.raises(KeyboardInterrupt):
        vm.sweep(diamond, checkpoint=checkpoint, **kwargs)
    monkeypatch.undo()
    capsys.readouterr()
    vm.sweep(diamond, checkpoint=checkpoint, progress=False, **kwargs)  # progress=False: silent
    assert capsys.readouterr().err == ""
    _interrupting(monkeypatch, after=3)
    with pytest.raises(KeyboardInterrupt):
        vm.sweep(diamond, checkpoint=checkpoint, **kwargs)
    monkeypatch.undo()
    vm.sweep(diamond, checkpoint=checkpoint, **kwargs)
    assert f"resumed from {checkpoint}: 3 of 10 readings reused" in capsys.readouterr().err


def test_out_reaching_the_scene_file_is_refused_before_any_ray(mi, tmp_path):
    """An output named through a link to the scene read (or the scene itself) never replaces it."""

    scene = tmp_path / "s.xml"
    scene.write_text((ROOT / "scenes" / "diamond_conical.xml").read_text())
    (tmp_path / "o.nc").symlink_to(scene)
    with pytest.raises(ValueError, match=r"out .*o.nc is scene .*s.xml, an input of this run"):
        vm.sweep(str(scene), rays=100, out=tmp_path / "o.nc")
    assert scene.read_text().startswith("<?xml")
