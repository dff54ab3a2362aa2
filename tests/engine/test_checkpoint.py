"""
Tests of virtspec_mi.engine.checkpoint: one run per checkpoint (an OS lock, checked with real
processes), writability checked before any tracing, tampered checkpoints refused with
the reason — never accepted, never deleted — and what ``virtspec sweep --out`` says
about its checkpoint (Ctrl-C, resume).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from killed_runs import ROUGH_XML, default_signals, kill_then_resume
from virtspec_mi.engine.checkpoint import CheckpointError, checkpoint_for, claim

ROOT = Path(__file__).resolve().parents[2]
KWARGS = dict(theta_i="0:90:10", rays=2000, seed=3, chunk_size=1024 * 2)  # 10 readings, 1 per batch


def _no_tracing(monkeypatch):
    """Make any tracing fail the test: what is checked must be checked before it."""

    import virtspec_mi.engine.readings as engine

    def traced(*args, **kwargs):
        raise AssertionError("traced rays before the check")

    monkeypatch.setattr(engine, "trace_readings", traced)


def _interrupted_checkpoint(scene, path: Path, after: int, **kwargs) -> dict:
    """A real checkpoint: the sweep interrupted (KeyboardInterrupt) after ``after`` batches."""

    import virtspec_mi.engine.readings as engine

    real, calls = engine.trace_readings, []

    def flaky(*args, **kw):
        if len(calls) == after:
            raise KeyboardInterrupt
        calls.append(1)
        return real(*args, **kw)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(engine, "trace_readings", flaky)
        with pytest.raises(KeyboardInterrupt):
            vm.sweep(scene, checkpoint=path, **kwargs)
    return json.loads(path.read_text())


# --- one run per checkpoint ------------------------------------------------------------


def _holder(path: Path) -> subprocess.Popen:
    """Another process holding checkpoint ``path`` until its stdin is closed."""

    code = ("import sys\nfrom virtspec_mi.engine.checkpoint import claim\n"
            "with claim(sys.argv[1]):\n    print('held', flush=True)\n    sys.stdin.read()\n")
    process = subprocess.Popen([sys.executable, "-c", code, str(path)], stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, text=True, cwd=ROOT, preexec_fn=default_signals)
    assert process.stdout.readline().strip() == "held"
    return process


def test_a_checkpoint_held_by_another_process_is_refused_with_its_pid(diamond, tmp_path, monkeypatch, capsys):
    checkpoint = tmp_path / "sweep.nc.partial.json"
    holder = _holder(checkpoint)
    try:
        with monkeypatch.context() as patch:
            _no_tracing(patch)
            with pytest.raises(CheckpointError, match=rf"is in use by another run \(pid {holder.pid}\)"):
                vm.sweep(diamond, checkpoint=checkpoint, **KWARGS)
            with pytest.raises(ValueError, match=rf"{checkpoint} is in use by another run \(pid {holder.pid}\)"):
                vm.sweep(diamond, out=tmp_path / "sweep.nc", **KWARGS)
            from virtspec_mi.cli import main

            scene = str(ROOT / "scenes" / "diamond_collimated.xml")
            assert main(["sweep", scene, "--theta-i", "0", "--rays", "100", "--out", str(tmp_path / "sweep.nc")]) == 1
            assert f"is in use by another run (pid {holder.pid})" in capsys.readouterr().err
    finally:
        holder.stdin.close()
        holder.wait(timeout=30)
    assert holder.returncode == 0
    result = vm.sweep(diamond, out=tmp_path / "sweep.nc", **KWARGS)  # the holder is gone: free again
    assert result.rays.size == 10
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep.nc"]  # no checkpoint, lock or temporary left


def test_a_killed_holder_leaves_the_checkpoint_free(tmp_path):
    checkpoint = tmp_path / "x.partial.json"
    holder = _holder(checkpoint)
    holder.kill()
    holder.wait(timeout=30)
    with claim(checkpoint):  # the OS dropped the dead process's lock (its lock file may remain)
        with pytest.raises(CheckpointError, match=rf"in use by another run \(pid {os.getpid()}\)"):
            with claim(checkpoint):
                pass
    assert not (tmp_path / "x.partial.json.lock").exists()


@pytest.mark.slow
def test_two_cli_sweeps_into_one_out_file(tmp_path):
    """Two real ``virtspec sweep`` processes, one --out: the second is refused at once, the first goes on."""

    out = tmp_path / "sweep.nc"
    command = [sys.executable, "-m", "virtspec_mi.cli", "sweep", str(ROOT / "scenes" / "diamond_collimated.xml"),
               "--theta-i", "0:90:1", "--rays", "2000000", "--chunk-size", "1048576", "--quiet", "--out", str(out)]
    first = subprocess.Popen(command, cwd=tmp_path, stderr=subprocess.PIPE, text=True, preexec_fn=default_signals)
    lock = tmp_path / "sweep.nc.partial.json.lock"
    deadline = time.monotonic() + 120
    while not lock.exists() and first.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    try:
        second = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=120)
        assert first.poll() is None, "the first sweep ended before the second started"
        assert second.returncode == 1
        assert f"is in use by another run (pid {first.pid})" in second.stderr
        assert "No such file or directory" not in second.stderr and "Traceback" not in second.stderr
    finally:
        partial = tmp_path / "sweep.nc.partial.json"
        while not partial.exists() and first.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)  # at least one finished batch, then Ctrl-C
        os.kill(first.pid, signal.SIGINT)
        first.wait(timeout=60)
    assert f"finished readings are kept in {tmp_path / 'sweep.nc.partial.json'}" in first.stderr.read()


# --- writable before tracing -----------------------------------------------------------


@pytest.mark.parametrize("where", ["missing directory", "parent is a file", "is a directory"])
def test_an_unwritable_checkpoint_fails_before_any_tracing(diamond, tmp_path, monkeypatch, where):
    (tmp_path / "file").write_text("")
    (tmp_path / "dir.json").mkdir()
    path = {"missing directory": tmp_path / "missing" / "sweep.partial.json",
            "parent is a file": tmp_path / "file" / "sweep.partial.json",
            "is a directory": tmp_path / "dir.json"}[where]
    _no_tracing(monkeypatch)
    with pytest.raises(CheckpointError, match=f"checkpoint {path} (cannot be written|is a directory)"):
        vm.sweep(diamond, checkpoint=path, **KWARGS)


@pytest.mark.parametrize("name", ["checkpoint", "out"])
@pytest.mark.parametrize("value", [123, 1.5, True, ["a.json"]])
def test_a_path_parameter_that_is_not_a_path_is_a_clear_value_error(diamond, monkeypatch, name, value):
    _no_tracing(monkeypatch)
    with pytest.raises(ValueError, match=f"{name} must be a file path"):
        vm.sweep(diamond, **{name: value}, **KWARGS)


def test_checkpoint_for_an_output_file():
    assert checkpoint_for("fig5.nc") == Path("fig5.nc.partial.json")


# --- tampered checkpoints ----------------------------------------------------------------


@pytest.fixture(scope="module")
def saved(diamond, tmp_path_factory) -> dict:
    """A genuine checkpoint of KWARGS's sweep: 4 of its 10 readings done."""

    data = _interrupted_checkpoint(diamond, tmp_path_factory.mktemp("saved") / "sweep.partial.json", 4, **KWARGS)
    assert len(data["done"]) == 4
    return data


def _set(data: dict, where: str, value) -> None:
    *keys, last = where.split(".")
    for key in keys:
        data = data[key] if not key.isdigit() else data[int(key)]
    data[int(last) if last.isdigit() else last] = value


TAMPERED = [
    # (what is set, value, reason in the message)
    ("counts.reflected.0", 1234.7, "whole number"),
    ("counts.reflected.0", 1234.0, "whole number"),
    ("counts.reflected.0", "1234", "whole number"),
    ("counts.reflected.0", None, "whole number"),
    ("counts.reflected.0", True, "whole number"),
    ("counts.reflected.0", -1, "0 <= reflected <= rays"),
    ("counts.reflected.0", 2001, "0 <= reflected <= rays"),
    ("counts.reflected.0", 10**30, "0 <= reflected <= rays"),
    ("counts.rays.0", 10**30, "rays"),
    ("counts.rays.0", 1999, "rays"),
    ("counts.transmitted.0", 2000, "reflected + transmitted + capped <= rays"),
    ("counts.specular_reflected.0", 2000, "specular_reflected <= reflected"),
    ("counts.largest_weight.0", "big", "largest_weight"),
    ("counts.reflected", [1, 2], "one value per done reading"),
    ("counts.reflected", 5, "one value per done reading"),
    ("pilot.rays.0", 5, "pilot rays"),
    ("done.1", "DONE0", "unique"),
    ("done.0", True, "whole number"),
    ("done.0", 1.0, "whole number"),
    ("done.0", 10, "0 <= index < 10"),
    ("done.0", -1, "0 <= index < 10"),
    ("seconds", float("nan"), "seconds"),
    ("seconds", -1.0, "seconds"),
    ("seconds", float("inf"), "seconds"),
    ("seconds", "1", "seconds"),
    ("seconds", True, "seconds"),
    ("identity", "a string", "identity"),
    ("identity", [1, 2], "identity"),
    ("identity", None, "identity"),
    ("counts", None, "counts"),
    ("done", {"0": 1}, "done"),
]


@pytest.mark.parametrize("where, value, reason", TAMPERED, ids=[f"{w}={v!r}"[:40] for w, v, _ in TAMPERED])
def test_a_tampered_checkpoint_is_refused_with_the_reason_and_kept(diamond, saved, tmp_path, monkeypatch,
                                                                    where, value, reason):
    data = json.loads(json.dumps(saved))
    _set(data, where, data["done"][0] if value == "DONE0" else value)
    checkpoint = tmp_path / "sweep.partial.json"
    checkpoint.write_text(json.dumps(data))
    before = checkpoint.read_bytes()
    _no_tracing(monkeypatch)
    with pytest.raises(CheckpointError, match=f"checkpoint {checkpoint} is corrupt") as error:
        vm.sweep(diamond, checkpoint=checkpoint, **KWARGS)
    assert reason in str(error.value)
    assert checkpoint.read_bytes() == before  # the user's work is not deleted (nor rewritten)


def test_the_untampered_checkpoint_resumes(diamond, saved, tmp_path):
    checkpoint = tmp_path / "sweep.partial.json"
    checkpoint.write_text(json.dumps(saved))
    resumed = vm.sweep(diamond, checkpoint=checkpoint, **KWARGS)
    whole = vm.sweep(diamond, **KWARGS)
    np.testing.assert_array_equal(resumed.reflected, whole.reflected)
    assert not checkpoint.exists()


def test_readings_traced_together_must_be_done_together(diamond, tmp_path, monkeypatch):
    # diamond: one trace per angle shared by its wavelengths (readings 2k, 2k + 1)
    kwargs = dict(KWARGS, wavelengths=[450, 650])
    checkpoint = tmp_path / "shared.partial.json"
    saved = _interrupted_checkpoint(diamond, checkpoint, 2, **kwargs)
    assert saved["done"] == [0, 1, 2, 3]

    def half_of_a_trace(data: dict) -> None:
        data["done"][3] = 5  # readings 2 and 4 without their partners 3 and 5

    def unequal_counts(data: dict) -> None:
        counts = data["counts"]  # reading 1 no longer has reading 0's counts (still consistent itself)
        for one, other in (("reflected", "transmitted"), ("specular_reflected", "regular_transmitted")):
            counts[one][1], counts[other][1] = counts[other][1], counts[one][1]

    _no_tracing(monkeypatch)
    for change in (half_of_a_trace, unequal_counts):
        data = json.loads(json.dumps(saved))
        change(data)
        checkpoint.write_text(json.dumps(data))
        with pytest.raises(CheckpointError, match="traced together but are not all done with equal counts"):
            vm.sweep(diamond, checkpoint=checkpoint, **kwargs)
        assert json.loads(checkpoint.read_text()) == data


def test_slow_saves_are_spaced_out_and_what_is_left_is_saved_on_the_way_out(diamond, tmp_path, monkeypatch):
    import errno

    import virtspec_mi.engine.checkpoint as checkpoint_module
    import virtspec_mi.results.io as results_io
    from virtspec_mi.engine.checkpoint import Checkpoint

    saves, real_save = [], Checkpoint._save

    def counted(self):
        saves.append(self.reused)
        real_save(self)

    monkeypatch.setattr(Checkpoint, "_save", counted)
    monkeypatch.setattr(checkpoint_module, "_SAVE_EVERY", 1e9)  # as if saving took ages next to a batch
    checkpoint = tmp_path / "sweep.nc.partial.json"
    data = _interrupted_checkpoint(diamond, checkpoint, 4, **KWARGS)
    assert saves == [1, 4] and len(data["done"]) == 4  # the first batch at once, the rest when interrupted
    saves.clear()

    real_replace = results_io.os.replace

    def full(source, target):
        if Path(target).suffix == ".nc":
            raise OSError(errno.ENOSPC, "No space left on device")
        real_replace(source, target)

    monkeypatch.setattr(results_io.os, "replace", full)
    with pytest.raises(OSError, match="could not write"):
        vm.sweep(diamond, out=tmp_path / "sweep.nc", **KWARGS)
    assert saves == [5, 10]  # resumed with 4; the last batches were saved before the output was written
    assert len(json.loads(checkpoint.read_text())["done"]) == 10


# --- the command line: Ctrl-C, resume, outputs -------------------------------------------


def _interrupt_after(monkeypatch, batches: int) -> None:
    """Ctrl-C (KeyboardInterrupt) once ``batches`` batches of the sweep have been traced."""

    import virtspec_mi.engine.readings as engine

    real, calls = engine.trace_readings, []

    def flaky(*args, **kwargs):
        if len(calls) == batches:
            raise KeyboardInterrupt
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(engine, "trace_readings", flaky)


def test_ctrl_c_names_the_checkpoint_and_the_rerun_says_what_it_reused(scenes_dir, tmp_path, monkeypatch, capsys):
    from virtspec_mi.cli import main

    out = tmp_path / "fig5.nc"
    partial = tmp_path / "fig5.nc.partial.json"
    command = ["sweep", str(scenes_dir / "diamond_collimated.xml"), "--theta-i", "0:90:10", "--rays", "2000",
               "--chunk-size", "2048", "--out", str(out)]
    with monkeypatch.context() as patch:
        _interrupt_after(patch, 4)
        assert main(command) == 130
    err = capsys.readouterr().err
    assert f"virtspec: interrupted (finished readings are kept in {partial}: re-run the same command" in err
    assert "OUT.partial.json" not in err
    assert main(command) == 0
    captured = capsys.readouterr()
    assert f"resumed from {partial}: 4 of 10 readings reused" in captured.err
    assert f"written: {out}" in captured.out and not partial.exists()
    densities = ["sweep", str(scenes_dir / "diamond_collimated.xml"), "--theta-i", "0:90:10", "--densities", "2",
                 "3", "--chunk-size", "1024", "--out", str(out)]
    with monkeypatch.context() as patch:
        _interrupt_after(patch, 5)  # density 2: 1 batch, density 3: 10 batches
        assert main(densities) == 130
    assert f"kept in {tmp_path / 'fig5_logN3.nc.partial.json'}:" in capsys.readouterr().err


def test_ctrl_c_before_any_reading_finished(scenes_dir, tmp_path, monkeypatch, capsys):
    from virtspec_mi.cli import main

    out = tmp_path / "fig5.csv"
    with monkeypatch.context() as patch:
        _interrupt_after(patch, 0)
        assert main(["sweep", str(scenes_dir / "diamond_collimated.xml"), "--theta-i", "0", "--rays", "100",
                     "--out", str(out)]) == 130
    err = capsys.readouterr().err
    assert err.startswith("virtspec: interrupted") and "kept in" not in err
    assert list(tmp_path.iterdir()) == []


def test_sweep_out_that_is_a_directory_fails_before_tracing(scenes_dir, tmp_path, monkeypatch, capsys):
    import virtspec_mi.engine.readings as engine
    from virtspec_mi.cli import main

    (tmp_path / "taken.nc").mkdir()
    monkeypatch.setattr(engine, "trace_readings", lambda *a, **k: pytest.fail("traced before the check"))
    assert main(["sweep", str(scenes_dir / "diamond_collimated.xml"), "--theta-i", "0", "--rays", "100",
                 "--out", str(tmp_path / "taken.nc")]) == 1
    err = capsys.readouterr().err
    assert err.startswith("virtspec: error: --out: out ") and "is a directory" in err


# --- a goniophotometer reading and a sphere spectrum resume after SIGKILL ------------------



@pytest.mark.slow
def test_killing_a_real_goniophotometer_process_and_rerunning_gives_the_uninterrupted_reading(tmp_path):
    scene = tmp_path / "rough.xml"
    scene.write_text(ROUGH_XML)
    options = ["--theta-i", "0:80:2", "--wavelengths", "400:700:50", "--rays", "200000", "--theta-o-bins", "6",
               "--phi-o-bins", "8", "--json"]
    out = tmp_path / "gonio.nc"
    command = [sys.executable, "-m", "virtspec_mi.cli", "gonio", str(scene), *options, "--out", str(out)]
    kill_then_resume(command, out, 41 * 7, tmp_path)
    resumed = vm.read_result(out)
    whole = vm.gonio(str(scene), theta_i="0:80:2", wavelengths="400:700:50", rays=200_000, theta_o_bins=6,
                     phi_o_bins=8)
    np.testing.assert_array_equal(resumed.bin_counts, whole.bin_counts)
    for name in ("reflected", "transmitted", "absorbed", "rays"):
        np.testing.assert_array_equal(getattr(resumed.result, name), getattr(whole.result, name))


@pytest.mark.slow
def test_killing_a_real_sphere_spectrum_process_and_rerunning_gives_the_uninterrupted_reading(tmp_path):
    out = tmp_path / "sphere.json"
    keywords = dict(wavelengths="400:2500:20", rays=40_000, seed=2)
    code = ("import sys, virtspec_mi as vm; "
            f"vm.sphere_measure({str(ROOT / 'scenes' / 'sphere_150mm_8d.xml')!r}, out=sys.argv[1], progress=False, "
            f"**{keywords!r})")
    kill_then_resume([sys.executable, "-c", code, str(out)], out, 2 * 106, tmp_path)
    resumed = vm.read_result(out)
    whole = vm.sphere_measure(str(ROOT / "scenes" / "sphere_150mm_8d.xml"), **keywords)
    for configuration in ("sample", "standard"):
        for name, values in whole.counts[configuration].items():
            np.testing.assert_array_equal(resumed.counts[configuration][name], values, err_msg=name)


def test_a_result_store_keeps_each_calls_result_and_its_own_checkpoint(tmp_path):
    """
    ResultStore, the checkpoint of a run of several API calls (an albedo table's groups, a
    Klems file's): a call given ``path(label)`` as its ``out`` keeps its own checkpoint
    beside it meanwhile — something to resume from, removed with the folder (never a file
    of another program); a folder of another run is refused, naming the run and what differs.
    """

    from virtspec_mi.engine.checkpoint import ResultStore

    folder = tmp_path / "k.xml.parts"
    store = ResultStore(folder, {"seed": 1}, "Klems measurement")
    assert not store.kept() and store.load("front:0", str) is None
    part = store.path("front:0")
    assert part.parent == folder and part.name.endswith(".nc") and part == ResultStore(folder, {"seed": 1}).path(
        "front:0")
    checkpoint_for(part).write_text("{}")  # the call under way
    assert store.kept()
    part.write_text("done")
    again = ResultStore(folder, {"seed": 1}, "Klems measurement")
    assert again.load("front:0", lambda path: path.read_text()) == "done" and again.reused == 1 and again.saved == 1
    (folder / "notes.txt").write_text("someone else's")
    with pytest.raises(ValueError, match=r"belongs to a different Klems measurement \(differs in: seed\)"):
        ResultStore(folder, {"seed": 2}, "Klems measurement")
    again.remove()
    assert sorted(p.name for p in folder.iterdir()) == ["notes.txt"]
    assert not ResultStore(None, {"seed": 1}).kept()
