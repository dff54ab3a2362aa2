"""
Tests of virtspec_mi.base.files, and of every writer through it (issue 22, item 4): a failed
write — a full disk, a file size limit — names the path and the cause, keeps what was
being written (the result attached to the error; the command line saves it elsewhere),
leaves the old file whole and no temporary, and never removes a file the project did not
write. The file size limit is real (``RLIMIT_FSIZE`` in a child process); a full disk is
simulated (a tiny file system needs root to mount: see ``docs/guide/files.md``).
"""

from __future__ import annotations

import errno
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
import virtspec_mi.base.files as files
from result_kinds import hemispherical_grid, sphere_grid
from result_kinds import gonio_from_counts
from virtspec_mi.base.files import IN_MEMORY, WriteError, atomic_file, cause_of

SUFFIXES = (".nc", ".csv", ".json", ".zarr")
ROOT = Path(__file__).resolve().parents[2]


def _no_temporaries(folder: Path) -> None:
    assert not [p.name for p in folder.iterdir() if p.name.startswith(".")], list(folder.iterdir())


# -- atomic_file ------------------------------------------------------------------------------------------------------


def test_an_atomic_file_replaces_the_old_one_in_one_step_or_not_at_all(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("old")
    theirs = tmp_path / ".a.txt.0123456789ab.tmp"  # a file of someone else's, named like our temporaries
    theirs.write_text("not ours")
    with pytest.raises(KeyboardInterrupt):
        with atomic_file(path) as temporary:
            temporary.write_text("half")
            raise KeyboardInterrupt
    assert path.read_text() == "old" and theirs.read_text() == "not ours"
    assert sorted(p.name for p in tmp_path.iterdir()) == [theirs.name, "a.txt"]
    with atomic_file(path) as temporary:
        assert temporary.parent == tmp_path and not temporary.read_text()
        temporary.write_text("new")
    assert path.read_text() == "new" and theirs.read_text() == "not ours"


def test_a_write_error_names_the_path_and_the_cause(tmp_path, monkeypatch):
    path = tmp_path / "a.txt"
    monkeypatch.setattr(files.os, "replace", lambda *a: (_ for _ in ()).throw(OSError(errno.ENOSPC, "No space "
                                                                                              "left on device")))
    with pytest.raises(WriteError, match=f"^could not write {path}: No space left on device$") as caught:
        with atomic_file(path) as temporary:
            temporary.write_text("x")
    assert caught.value.errno == errno.ENOSPC and isinstance(caught.value, OSError)
    assert caught.value.filename == str(path) and not list(tmp_path.iterdir())


def test_a_nearly_full_disk_is_said_even_when_a_library_reports_another_cause(tmp_path, monkeypatch):
    class Usage:
        free = 12

    monkeypatch.setattr(files.shutil, "disk_usage", lambda folder: Usage())
    assert cause_of(PermissionError(errno.EACCES, "Permission denied"), tmp_path / "x.nc") == (
        "Permission denied (the disk is full: 12 bytes free)", errno.EACCES)
    assert cause_of(RuntimeError("NetCDF: HDF error"), tmp_path / "x.nc") == (
        "NetCDF: HDF error (the disk is full: 12 bytes free)", errno.ENOSPC)
    assert cause_of(OSError(errno.ENOSPC, "No space left on device"), tmp_path / "x.nc")[0] == (
        "No space left on device (12 bytes free)")


# -- every writer on a full disk (simulated): the result kept, the old file whole ---------------------------------------


def _disk_full_midway(monkeypatch, suffix: str) -> None:
    """Writes of ``suffix`` fail half way with ENOSPC, after writing part of what they write."""

    import xarray as xr

    full = OSError(errno.ENOSPC, "No space left on device")
    if suffix == ".zarr":
        real = xr.Dataset.to_zarr

        def half_store(self, store, *args, **kwargs):
            real(self.isel({d: slice(0, 1) for d in self.dims}), store, *args, **kwargs)
            raise full

        monkeypatch.setattr(xr.Dataset, "to_zarr", half_store)
    elif suffix == ".nc":
        def half_netcdf(self, target, *args, **kwargs):
            Path(target).write_bytes(b"CDF\x01 half")
            raise full

        monkeypatch.setattr(xr.Dataset, "to_netcdf", half_netcdf)
    else:
        real_text = Path.write_text

        def half_text(self, text, *args, **kwargs):
            real_text(self, text[: len(text) // 2])
            raise full

        monkeypatch.setattr(Path, "write_text", half_text)


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.parametrize("kind", ["sweep", "gonio", "sphere"])
def test_a_full_disk_keeps_the_result_and_the_old_file(tmp_path, monkeypatch, suffix, kind):
    result = {"sweep": hemispherical_grid, "gonio": gonio_from_counts, "sphere": sphere_grid}[kind]()
    old = {"sweep": lambda: hemispherical_grid(1), "gonio": lambda: gonio_from_counts(1),
           "sphere": lambda: sphere_grid(1)}[kind]()
    path = old.write(tmp_path / f"{kind}{suffix}")
    with monkeypatch.context() as patch:
        _disk_full_midway(patch, suffix)
        with pytest.raises(WriteError) as caught:
            result.write(path)
    error = caught.value
    assert str(error) == f"could not write {path}: No space left on device; {IN_MEMORY}"
    assert error.result is result and error.errno == errno.ENOSPC
    assert vm.read_result(path).as_dict() == old.as_dict()  # the old file, whole
    _no_temporaries(tmp_path)
    assert error.result.write(tmp_path / f"elsewhere{suffix}")  # what was traced is written elsewhere
    assert vm.read_result(tmp_path / f"elsewhere{suffix}").as_dict() == result.as_dict()


def test_the_command_line_saves_a_result_its_file_could_not_take(diamond, tmp_path, monkeypatch):
    """An error carrying a result kept only in memory: the command line writes it elsewhere and says where."""

    import tempfile

    from virtspec_mi.cli import _rescued

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "rescue"))
    (tmp_path / "rescue").mkdir()
    out = tmp_path / "gonio.nc"
    reading = vm.gonio(diamond, rays=300, wavelengths=[450, 550], theta_i=30, theta_o_bins=2, phi_o_bins=2)
    with monkeypatch.context() as patch:
        _disk_full_midway(patch, ".nc")
        with pytest.raises(WriteError) as info:
            reading.write(out)
    from virtspec_mi.base.surface import command_line

    with command_line():
        message = str(_rescued(info.value))
    rescued = next((tmp_path / "rescue").iterdir())
    assert message == (f"could not write {out}: No space left on device; the result was written to "
                       f"{rescued} instead (virtspec plot, colour and compare read it)")  # the command line's words
    saved = vm.read_result(rescued)
    np.testing.assert_array_equal(saved.bin_counts, reading.bin_counts)
    for name in ("rays", "reflected", "transmitted"):
        np.testing.assert_array_equal(getattr(saved.result, name), getattr(reading.result, name))


@pytest.mark.parametrize("command", [
    ["sweep", "scenes/diamond_conical.xml", "--rays", "300", "--wavelengths", "450,550", "--theta-i", "0,30"],
    ["gonio", "scenes/diamond_conical.xml", "--rays", "300", "--wavelengths", "450,550", "--theta-i", "0,30",
     "--theta-o-bins", "2", "--phi-o-bins", "2"],
], ids=["sweep", "gonio"])
def test_a_run_whose_file_fails_says_its_checkpoint_holds_the_readings(command, diamond, tmp_path, monkeypatch,
                                                                       capsys):
    from virtspec_mi.cli import main

    out = tmp_path / "run.nc"
    command = [*command, "--out", str(out)]
    with monkeypatch.context() as patch:
        _disk_full_midway(patch, ".nc")
        assert main(command) == 1
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last.startswith(f"virtspec: error: could not write {out}: No space left on device; every finished "
                           f"reading is kept in {out}.partial.json: re-run the same ")
    assert main(command) == 0 and vm.read_result(out).rays.shape[:2] == (2, 2)
    assert not (tmp_path / f"{out.name}.partial.json").exists()


def test_a_failed_checkpoint_save_warns_and_the_sweep_keeps_its_readings(diamond, tmp_path, monkeypatch):
    import virtspec_mi.engine.checkpoint as checkpoint_module

    kwargs = {"rays": 300, "wavelengths": "450,550", "theta_i": "0,30,60", "chunk_size": 1024, "progress": False}
    whole = vm.sweep(diamond, **kwargs)
    real = checkpoint_module.atomic_file

    def full(path):
        if str(path).endswith(".partial.json"):
            raise WriteError(path, "No space left on device", code=errno.ENOSPC)
        return real(path)

    monkeypatch.setattr(checkpoint_module, "atomic_file", full)
    out = tmp_path / "sweep.json"
    with monkeypatch.context() as patch:
        _disk_full_midway(patch, ".json")
        with pytest.warns(RuntimeWarning, match=f"checkpoint {out}.partial.json could not be saved \\(No space left "
                                                "on device\\): the run goes on") as warned:
            with pytest.raises(WriteError) as caught:
                vm.sweep(diamond, out=out, **kwargs)
    assert len([w for w in warned if "could not be saved" in str(w.message)]) == 1  # once, not per batch
    assert str(caught.value).endswith(f"the checkpoint {out}.partial.json could not be saved either (No space left "
                                      f"on device); {IN_MEMORY}")
    for name in ("rays", "reflected", "transmitted"):  # every traced reading, in memory
        np.testing.assert_array_equal(getattr(caught.value.result, name), getattr(whole, name))
    assert not out.exists() and not (tmp_path / f"{out.name}.partial.json").exists()
    _no_temporaries(tmp_path)


# -- a real file size limit (RLIMIT_FSIZE) in a child process -----------------------------------------------------------

CHILD = textwrap.dedent("""
    import json, resource, signal, sys
    sys.path.insert(0, {tests!r})
    from pathlib import Path
    from result_kinds import hemispherical_grid, sphere_grid
    from virtspec_mi.base.files import WriteError
    folder = Path({folder!r})
    small = hemispherical_grid().isel(wavelength=0, theta_i=0)
    large = {{"sweep": hemispherical_grid(), "sphere": sphere_grid()}}
    for suffix in {suffixes!r}:
        small.write(folder / ("old" + suffix))
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # beyond the limit a write fails with EFBIG instead of a signal
    resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))
    out = {{}}
    for suffix in {suffixes!r}:
        result = large["sphere" if suffix == ".zarr" else "sweep"]
        try:
            result.write(folder / ("old" + suffix))
            out[suffix] = "written"
        except WriteError as error:
            out[suffix] = [str(error), error.errno, error.result is result]
    print(json.dumps(out))
""")


def test_a_file_size_limit_is_named_and_leaves_the_old_files(tmp_path):
    limit = 4096
    code = CHILD.format(tests=str(ROOT / "tests"), folder=str(tmp_path), suffixes=SUFFIXES, limit=limit)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr
    outcomes = json.loads(done.stdout.strip().splitlines()[-1])
    for suffix in SUFFIXES:
        message, code, attached = outcomes[suffix]
        assert message.startswith(f"could not write {tmp_path / ('old' + suffix)}: "), message
        assert "File too large" in message or "files of at most 4.1 kB: ulimit -f" in message, message
        assert attached and code == errno.EFBIG, (suffix, code)
        small = hemispherical_grid().isel(wavelength=0, theta_i=0)
        assert vm.read_result(tmp_path / f"old{suffix}").as_dict() == small.as_dict()  # the old file, whole
    _no_temporaries(tmp_path)


def test_no_output_may_be_an_input_or_another_output(tmp_path):
    from virtspec_mi.base.files import check_distinct, same_file

    measured = tmp_path / "measured.csv"
    measured.write_text("wavelength,value\n")
    (tmp_path / "link.json").symlink_to(measured)
    os_link = tmp_path / "hard.csv"
    os_link.hardlink_to(measured)
    for alias in (measured, tmp_path / "." / "measured.csv", tmp_path / "link.json", os_link):
        assert same_file(alias, measured)
        with pytest.raises(ValueError, match=f"--out {alias} is MEASURED {measured}, an input of this run"):
            check_distinct([("--out", alias)], [("MEASURED", measured)])
    with pytest.raises(ValueError, match="one output would replace the other"):
        check_distinct([("--out", tmp_path / "a.h"), ("--figure", str(tmp_path / "a.h"))])
    check_distinct([("--out", tmp_path / "fit.json"), ("--plot", None)], [("MEASURED", measured), ("scene", {})])
    assert not same_file(tmp_path / "new.nc", tmp_path / "other.nc")


def test_a_long_path_is_shown_by_its_ends_and_length():
    from virtspec_mi.base.files import WriteError, shown_path

    assert shown_path("/tmp/x.nc") == "/tmp/x.nc"
    long = "/tmp/" + "b" * 5000 + ".nc"
    shown = shown_path(long)
    assert len(shown) < 200 and shown.startswith("/tmp/bbb") and shown.endswith("b.nc (5,008 characters)")
    assert "(5,008 characters)" in str(WriteError(long, "File name too long"))
