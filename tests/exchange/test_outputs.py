"""
Nothing lost, nothing hangs in the exchange files (issue 33): an albedo table's and a Klems
file's companions never replace a file the format did not write (unless ``overwrite``), a
Klems output is checked before anything is measured, an albedo table interrupted at a safe
point names its checkpoint and resumes to the same counts, two runs on one checkpoint: the
second refuses, a failed write names the file.
"""

from __future__ import annotations

import errno
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
import virtspec_mi.base.interrupts as interrupts
from killed_runs import default_signals
from virtspec_mi.engine.checkpoint import CheckpointError, locked
from virtspec_mi.base.files import atomic_write
from virtspec_mi.base.files import WriteError

ROOT = Path(__file__).resolve().parents[2]
SMALL = dict(model="conductor", engine=None, mu=[0.5, 1.0], alpha=[0.3], epsilon=0.05, progress=False)
"""A table of a few groups, traced in about a second."""


# --- companions ---------------------------------------------------------------------------------------------


def test_an_albedo_tables_npy_companions_never_replace_a_users_files(mi, tmp_path):
    for name, text in (("t.json", "my notes"), ("t_avg.npy", "my array")):
        (tmp_path / name).write_text(text)
        with pytest.raises(ValueError, match=f"companion file .*{name} already exists.*overwrite=True"):
            vm.albedo_table(**SMALL, out=tmp_path / "t.npy")
        assert (tmp_path / name).read_text() == text and not (tmp_path / "t.npy").exists()
        (tmp_path / name).unlink()
    table = vm.albedo_table(**SMALL, out=tmp_path / "t.npy")
    assert json.loads((tmp_path / "t.json").read_text())["format"]
    table.write(tmp_path / "t.npy")  # its own companions: replaced
    (tmp_path / "u.json").write_text("mine")
    with pytest.raises(ValueError, match="u.json already exists"):
        table.write(tmp_path / "u.npy")
    table.write(tmp_path / "u.npy", overwrite=True)  # told to
    assert json.loads((tmp_path / "u.json").read_text())["format"]


def test_a_klems_export_never_replaces_the_users_nc_or_the_scene(mi, tmp_path):
    from virtspec_mi.applications.klems.measure import klems_measure

    reading = vm.gonio(vm.instrument_scene({"type": "simple_dielectric"}), theta_i=[0, 30], rays=2000,
                       theta_o_bins=[0, 45, 90], phi_o_bins=4, progress=False)
    (tmp_path / "sample.nc").write_text("the user's data")
    with pytest.raises(ValueError, match="sample.nc already exists"):
        vm.write_klems(reading, tmp_path / "sample.xml")
    assert (tmp_path / "sample.nc").read_text() == "the user's data" and not (tmp_path / "sample.xml").exists()
    scene = tmp_path / "spec.xml"
    scene.write_text((ROOT / "virtspec_mi" / "scenes" / "diamond_conical.xml").read_text())
    before = scene.read_text()
    started = time.perf_counter()
    for out, words in ((scene, "is the scene file being measured"), (tmp_path / "no" / "k.xml", "does not exist"),
                       (tmp_path / "sample.xml", "sample.nc already exists")):
        with pytest.raises(ValueError, match=words):
            klems_measure(str(scene), basis="quarter", rays=100, isotropic=True, out=out, progress=False)
    assert time.perf_counter() - started < 10 and scene.read_text() == before  # refused before measuring
    leaf = ROOT / "virtspec_mi" / "scenes" / "soybean_abmb.xml"
    with pytest.raises(ValueError, match="wavelength"):
        klems_measure(str(leaf), basis="quarter", wavelengths=3000, rays=100, isotropic=True,
                      out=tmp_path / "leaf.xml", progress=False)


def test_virtspec_gonio_klems_onto_the_scene_itself_is_refused(tmp_path):
    scene = tmp_path / "spec.xml"
    scene.write_text((ROOT / "virtspec_mi" / "scenes" / "diamond_conical.xml").read_text())
    before = scene.read_text()
    run = subprocess.run([sys.executable, "-m", "virtspec_mi", "gonio", str(scene), "--klems", str(scene),
                          "--klems-basis", "quarter", "--rays", "100"], capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 1 and "is the scene file being measured" in run.stderr and scene.read_text() == before


# --- writes -------------------------------------------------------------------------------------------------


def test_an_exchange_write_into_a_missing_folder_names_the_file_not_a_temporary(tmp_path):
    target = tmp_path / "missing" / "table.h"
    with pytest.raises(WriteError) as error:
        atomic_write(target, lambda tmp: Path(tmp).write_text("x"))
    assert str(target) in str(error.value) and ".tmp" not in str(error.value)


def test_a_full_disk_names_the_file(tmp_path, monkeypatch):
    target = tmp_path / "table.h"

    def full(tmp: str) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(WriteError) as error:
        atomic_write(target, full)
    assert str(target) in str(error.value) and "No space left on device" in str(error.value)
    assert error.value.errno == errno.ENOSPC and list(tmp_path.iterdir()) == []


# --- interrupts and locks -----------------------------------------------------------------------------------


def test_an_interrupted_albedo_table_names_its_checkpoint_and_resumes_to_the_same_counts(mi, tmp_path, monkeypatch):
    whole = vm.albedo_table(**SMALL)
    out = tmp_path / "t.nc"
    parts = tmp_path / "t.nc.parts"
    real = interrupts.check

    def check():
        if parts.is_dir() and len(list(parts.glob("*.nc"))) == 2:  # two groups kept: Ctrl-C came in the second
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.01)
        real()

    monkeypatch.setattr(interrupts, "check", check)
    with interrupts.catching(), pytest.raises(interrupts.Interrupted) as stop:
        vm.albedo_table(**SMALL, out=out)
    monkeypatch.undo()
    assert stop.value.checkpoint == parts and stop.value.kept and str(parts) in str(stop.value)
    assert not out.exists() and not [p for p in tmp_path.rglob("*.tmp")]
    kept = sorted(p.name for p in parts.iterdir())
    assert "identity.json" in kept and len(kept) >= 2
    resumed = vm.albedo_table(**SMALL, out=out)
    np.testing.assert_array_equal(resumed.E, whole.E)
    for key in whole.counts:
        np.testing.assert_array_equal(resumed.counts[key], whole.counts[key], err_msg=key)
    assert out.exists() and not parts.exists() and not Path(str(parts) + ".lock").exists()


def test_a_complete_run_removes_the_parts_folder_with_a_temporary_an_old_run_left(mi, tmp_path):
    out = tmp_path / "t.nc"
    parts = tmp_path / "t.nc.parts"
    parts.mkdir()
    (parts / ".0123456789abcdef.nc.1a2b3c4d5e6f.tmp").write_text("half a part (an old run's, killed)")
    mine = parts / "notes.txt"
    mine.write_text("a file of the user's")
    vm.albedo_table(**SMALL, checkpoint=parts, out=out)
    assert sorted(p.name for p in parts.iterdir()) == ["notes.txt"]  # only what the store writes is removed
    mine.unlink()
    vm.albedo_table(**SMALL, out=out)
    assert not parts.exists()


def test_a_second_run_on_one_checkpoint_refuses_and_leaves_the_firsts_parts(mi, tmp_path):
    parts = tmp_path / "t.nc.parts"
    with locked(parts):  # another run holds it
        with pytest.raises(CheckpointError, match=f"checkpoint {parts} is in use by another run \\(pid {os.getpid()}"):
            vm.albedo_table(**SMALL, out=tmp_path / "t.nc")
    assert not parts.exists() and not (tmp_path / "t.nc").exists()


def test_the_command_line_names_the_albedo_checkpoint_and_the_rerun_says_what_it_reused(tmp_path):
    command = [sys.executable, "-m", "virtspec_mi", "albedo-table", "--engine", "none", "--cosines", "0.2:1:0.2",
               "--alpha", "0.1:1:0.3", "--epsilon", "0.01", "--out", str(tmp_path / "t.nc")]
    parts = tmp_path / "t.nc.parts"
    process = subprocess.Popen(command, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                               preexec_fn=default_signals)
    deadline = time.monotonic() + 120
    while not any(parts.glob("*.nc")) and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert process.poll() is None, process.stderr.read()
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130 and time.monotonic() - sent < 3.0, stderr
    assert f"finished readings are kept in {parts}: re-run the same command to resume" in stderr
    assert "Traceback" not in stderr and not list(tmp_path.rglob("*.tmp"))
    again = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True)
    assert again.returncode == 0 and f"resumed from {parts}:" in again.stderr and "reused" in again.stderr
    assert not parts.exists() and (tmp_path / "t.nc").exists()


# --- the comparison ---------------------------------------------------------------------------------------


def test_a_table_compared_with_its_own_nc_in_any_memory_order_flags_nothing(mi, tmp_path):
    """The .nc is in canonical (mu, alpha) order; a Filament-order table's memory order is (alpha, mu)."""

    import dataclasses

    table = vm.albedo_table(model="conductor", engine=None, mu=[0.3, 0.6, 1.0], alpha=[0.1, 0.5], epsilon=0.05,
                            progress=False)
    transposed = dataclasses.replace(table, order=("alpha", "mu"))
    assert transposed.layout().shape == (2, 3)
    for each in (table, transposed):
        each.write(tmp_path / "own.nc")
        for average in (False, True):
            comparison = each.compare(tmp_path / "own.nc", average=average)
            assert comparison.outside == [] and comparison.cells == (2 if average else 6)
    with pytest.raises(ValueError, match="side='inside' names a glass table's block"):
        table.compare(tmp_path / "own.nc", side="inside")


# --- an albedo table's file read as strictly as a result file -------------------------------------------


@pytest.mark.parametrize("edit, words", [
    (lambda d: d["reflected"].values.__setitem__((0, 0), d["rays"].values[0, 0] + 5), "'reflected' holds a count above"),
    (lambda d: d["rays"].values.__setitem__((0, 0), 0), "'rays' holds 0"),
    (lambda d: d["E"].values.__setitem__((0, 0), 0.5), "'E' disagrees with the counts"),
    (lambda d: d.attrs.__setitem__("epsilon", 1e-9), "epsilon = 1e-09 cannot be certified"),
    (lambda d: d.attrs.__setitem__("certificate", "all exact"), "'certificate' disagrees"),
])
def test_an_edited_albedo_table_file_is_refused_not_stated_as_certified(mi, tmp_path, edit, words):
    import xarray as xr

    vm.albedo_table(**SMALL, out=tmp_path / "t.nc")
    assert vm.read_albedo_table(tmp_path / "t.nc").certified  # as written: read
    with xr.open_dataset(tmp_path / "t.nc") as opened:
        dataset = opened.load()
    edit(dataset)
    dataset.to_netcdf(tmp_path / "edited.nc")
    with pytest.raises(ValueError, match=f"albedo table {tmp_path / 'edited.nc'}: .*{words}"):
        vm.read_albedo_table(tmp_path / "edited.nc")


def test_a_glass_table_compared_with_its_own_nc_on_either_side_flags_nothing(mi, tmp_path):
    table = vm.albedo_table(model="glass", engine=None, mu=[0.5, 1.0], alpha=[0.3], eta=[1.5], epsilon=0.05,
                            progress=False, out=tmp_path / "g.nc")
    for average in (False, True):
        for side in ("outside", "inside"):
            assert table.compare(tmp_path / "g.nc", average=average, side=side).outside == []


def test_an_interrupted_klems_run_names_its_parts_and_resumes_to_the_same_counts(mi, tmp_path, monkeypatch):
    from virtspec_mi.applications.klems.measure import klems_measure

    run = dict(basis="quarter", rays=2000, isotropic=True, progress=False)
    whole = klems_measure("diamond_conical", **run)
    out, parts = tmp_path / "k.xml", tmp_path / "k.xml.parts"
    real = interrupts.check

    def check():
        if parts.is_dir() and len(list(parts.glob("*.nc"))) == 2:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.01)
        real()

    monkeypatch.setattr(interrupts, "check", check)
    with interrupts.catching(), pytest.raises(interrupts.Interrupted) as stop:
        klems_measure("diamond_conical", **run, out=out)
    monkeypatch.undo()
    assert stop.value.checkpoint == parts and str(parts) in str(stop.value) and not out.exists()
    resumed = klems_measure("diamond_conical", **run, out=out)
    for name in ("counts", "rays", "reflected", "transmitted"):
        np.testing.assert_array_equal(getattr(resumed, name), getattr(whole, name), err_msg=name)
    assert out.exists() and (tmp_path / "k.nc").exists() and not parts.exists()
    (tmp_path / "k.xml").unlink()
    parts.mkdir()
    (parts / "identity.json").write_text("{}")  # another measurement's parts: refused, not mixed in
    with pytest.raises(ValueError, match="belongs to a different Klems measurement"):
        klems_measure("diamond_conical", **run, out=out, overwrite=True)
