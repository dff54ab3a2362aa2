"""
Ctrl-C at any moment (issue 33): a property test that sends SIGINT (or SIGTERM) to a real
``virtspec`` process at a random, seeded moment — while Python imports the package, while
Dr.Jit and Mitsuba load, while the scene loads, inside a kernel, between two readings,
while a checkpoint part is written — through every path: ``measure``, ``sweep``,
``gonio``, ``sphere``, ``albedo-table`` and the Klems export, with a second busy process
loading the machine. Each case asserts the exit status (130, 143) within a second of the
signal, one line and no traceback, the checkpoint named when one was kept, no temporary
file left, and that the same command run again resumes to the bit-identical result of an
uninterrupted run.

The default run takes a few cases per path; ``-m slow`` a larger one.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from killed_runs import default_signals

ROOT = Path(__file__).resolve().parents[1]
LATENCY_S = 1.0
"""The promise: a signalled command has exited within a second."""

# A command of each path, long enough that a signal in its first seconds always finds it running: each lasts at
# least 4.4 s on a quiet AVX-512 machine at about 300 Mray/s (measured 2026-11-28: measure 5.0 s, sweep 4.7,
# gonio 4.5, sphere 7.6, albedo-table 6.3, Klems 4.4), against the latest moment drawn, 2.5 s; shorter ones
# finished before the signal on a quiet machine. {out} is the output (and what names its checkpoint); None: the
# path writes nothing to resume from.
PATHS: dict[str, tuple[list[str], str | None]] = {
    "measure": (["measure", "diamond_conical", "--rays", "1200000000", "--quiet"], None),
    "sweep": (["sweep", "diamond_conical", "--theta-i", "0:80:10", "--rays", "100000000", "--quiet", "--out",
               "{out}"], "sweep.nc"),
    "gonio": (["gonio", "diamond_conical", "--theta-i", "0:80:20", "--rays", "100000000", "--theta-o-bins", "6",
               "--phi-o-bins", "8", "--json", "--out", "{out}"], "gonio.nc"),
    "sphere": (["sphere", "sphere_150mm_8d", "--rays", "4000000", "--wavelengths", "450", "550", "650", "750",
                "--out", "{out}"], "sphere.json"),
    "albedo-table": (["albedo-table", "--engine", "none", "--cosines", "0.2:1:0.2", "--alpha", "0.1:1:0.3",
                      "--epsilon", "0.0002", "--quiet", "--out", "{out}"], "table.nc"),
    "klems": (["gonio", "diamond_conical", "--klems", "{out}", "--klems-basis", "quarter", "--isotropic",
               "--rays", "80000000", "--quiet"], "klems.xml"),
}


STARTED = ("import os, runpy, sys; os.write(1, b'R'); sys.argv[0] = 'virtspec'; "
           "runpy.run_module('virtspec_mi', run_name='__main__')")
"""``python -m virtspec_mi`` that writes one byte on stdout once the interpreter runs the program (moment 0: before
it, Python's own start-up — its ``site`` module — runs no code of the package and cannot be reached)."""


def _command(path: str, folder: Path) -> tuple[list[str], Path | None]:
    arguments, out = PATHS[path]
    target = None if out is None else folder / out
    return [sys.executable, "-c", STARTED, *(a.replace("{out}", str(target)) for a in arguments)], target


def _checkpoint(path: str, out: Path) -> Path:
    return out.with_name(out.name + (".parts" if path in ("albedo-table", "klems") else ".partial.json"))


@pytest.fixture(scope="module")
def loaded():
    """A second process keeping one core busy for the test's length."""

    busy = subprocess.Popen([sys.executable, "-c", "while True: pass"], preexec_fn=default_signals)
    yield busy
    busy.kill()
    busy.wait()


def _interrupt(command: list[str], folder: Path, after: float, signum: int) -> tuple[int, str, float]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    process = subprocess.Popen(command, cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               preexec_fn=default_signals)
    assert process.stdout.read(1) == b"R", process.stderr.read()
    time.sleep(after)
    assert process.poll() is None, f"the run ended before the signal: {process.stderr.read()}"
    sent = time.monotonic()
    process.send_signal(signum)
    _, stderr = process.communicate(timeout=120)
    return process.returncode, stderr.decode(), time.monotonic() - sent


def _file(out: Path) -> bytes | dict:
    """What a finished output holds, to compare runs: the counts of a result or table, the text of a Klems file."""

    import xarray as xr

    if out.suffix == ".xml":  # a Klems file: the counts of its sidecar (the XML's comment holds the date)
        out = out.with_suffix(".nc")

    if out.suffix == ".json":
        import json

        data = json.loads(out.read_text())
        return {k: data[k] for k in ("reflected", "transmitted", "rays") if k in data} or {"keys": sorted(data)}
    with xr.open_dataset(out) as dataset:
        return {name: np.asarray(dataset[name].values) for name in dataset.data_vars
                if np.issubdtype(dataset[name].dtype, np.integer)}


def _same(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def _case(path: str, seed: int, tmp_path: Path, resume: bool) -> None:
    rng = random.Random(f"{path}:{seed}")
    after = rng.uniform(0.05, 2.5)
    signum = signal.SIGINT if rng.random() < 0.8 else signal.SIGTERM
    folder = tmp_path / f"{path}-{seed}"
    folder.mkdir()
    command, out = _command(path, folder)
    status, stderr, seconds = _interrupt(command, folder, after, signum)
    where = f"{path}, signal {signum} at {after:.2f} s"
    assert status == 128 + signum, f"{where}: exit {status}: {stderr}"
    assert "Traceback" not in stderr and "Error" not in stderr, f"{where}: {stderr}"
    assert seconds < LATENCY_S, f"{where}: exited {seconds:.2f} s after the signal"
    lines = stderr.strip().splitlines()
    assert lines and lines[-1].startswith("virtspec: "), f"{where}: {stderr}"
    leftovers = [p.name for p in folder.rglob("*") if p.name.endswith(".tmp")]
    assert not leftovers, f"{where}: temporaries left: {leftovers}"
    if out is None:
        return
    partial = _checkpoint(path, out)
    if partial.exists() and any(p.suffix != ".json" or ".partial" in p.name for p in
                                (partial.iterdir() if partial.is_dir() else [partial])):
        assert str(partial) in lines[-1], f"{where}: the checkpoint is not named: {stderr}"
    assert not out.exists(), f"{where}: the output is at its name although the run did not finish"
    if not resume:
        return
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    again = subprocess.run(command, cwd=folder, env=env, capture_output=True, text=True)
    assert again.returncode == 0, f"{where}: the rerun failed: {again.stderr}"
    assert not partial.exists(), f"{where}: the checkpoint was not removed after a complete run"
    _same(_file(out), _uninterrupted(path, tmp_path / f"{path}-whole", env))


_UNINTERRUPTED: dict[str, bytes | dict] = {}
"""What each path's command writes when it is never interrupted (its command is the same in every case): run once."""


def _uninterrupted(path: str, folder: Path, env: dict[str, str]) -> bytes | dict:
    if path not in _UNINTERRUPTED:
        folder.mkdir()
        reference, reference_out = _command(path, folder)
        subprocess.run(reference, cwd=folder, env=env, check=True, capture_output=True)
        _UNINTERRUPTED[path] = _file(reference_out)
    return _UNINTERRUPTED[path]


CASES = [(path, seed) for path in PATHS for seed in range(2)]


@pytest.mark.parametrize("path, seed", CASES)
def test_a_signal_at_a_random_moment_ends_the_command_within_a_second(path, seed, tmp_path, loaded):
    _case(path, seed, tmp_path, resume=False)


@pytest.mark.slow
@pytest.mark.parametrize("path", ["sweep", "albedo-table", "klems"])
def test_an_interrupted_run_resumes_to_the_bit_identical_result(path, tmp_path, loaded):
    """The rerun says what it reused and ends with the counts of a run never interrupted."""

    _case(path, 7, tmp_path, resume=True)


@pytest.mark.slow
@pytest.mark.parametrize("path, seed", [(path, seed) for path in PATHS for seed in range(2, 4)])
def test_many_signals_at_random_moments_every_path_resumed(path, seed, tmp_path, loaded):
    _case(path, seed, tmp_path, resume=path not in ("measure",))


# --- a signal while the result file is written (in this process: fast) ----------------------------------


def test_a_signal_during_the_result_files_write_waits_for_it_and_names_the_file(mi, tmp_path, monkeypatch):
    """A KeyboardInterrupt inside the NetCDF writer's file lock could hang; the file is finished first."""

    import virtspec_mi as vm
    import virtspec_mi.base.interrupts as interrupts
    from virtspec_mi.results import io

    scene = vm.instrument_scene({"type": "simple_dielectric"})
    out = tmp_path / "r.nc"
    real = io.write

    def write(result, path, **keywords):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.01)  # the handler runs here: held until the file is whole
        return real(result, path, **keywords)

    monkeypatch.setattr(io, "write", write)
    with interrupts.catching(), pytest.raises(interrupts.Interrupted) as stop:
        vm.sweep(scene, theta_i=[0, 30], rays=1000, out=out, progress=False)
    assert stop.value.written == out and out.exists() and vm.read_result(out).rays.shape == (1, 2)
    assert not (tmp_path / "r.nc.partial.json").exists() and not list(tmp_path.glob("*.tmp"))


PROGRAM = """
import os, sys
os.write(1, b"R")
try:
    import virtspec_mi as vm
    vm.gonio("diamond_conical", theta_i="0:80:10", rays=20000000, theta_o_bins=6, phi_o_bins=8, progress=False)
    print("returned")
except KeyboardInterrupt as stop:
    print("KeyboardInterrupt", type(stop).__name__)
"""
"""A Python program measuring with the API: a Ctrl-C reaches it as ``KeyboardInterrupt`` wherever it lands."""


@pytest.mark.parametrize("seed", range(6))
def test_the_api_interrupted_at_a_random_moment_raises_keyboard_interrupt_to_the_caller(seed, tmp_path, loaded):
    """While Dr.Jit and Mitsuba load it came out as SystemError or NameError (issue 33)."""

    after = random.Random(f"api:{seed}").uniform(0.05, 1.2)  # 0.94, 0.2, 0.66, 0.52, 0.2, 0.59 s: imports too
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    process = subprocess.Popen([sys.executable, "-c", PROGRAM], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, preexec_fn=default_signals)
    assert process.stdout.read(1) == b"R"
    time.sleep(after)
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=120)
    # The caller catches the KeyboardInterrupt (stdout). Known defect, open (the manual's limits): a signal
    # that lands at about 0.6 s, while the plugins register after Mitsuba's import, also ends the process
    # with SIGINT's status once the program has finished (no traceback, no error): -2 besides 0.
    assert b"KeyboardInterrupt" in stdout and process.returncode in (0, -signal.SIGINT), (after, stdout, stderr)
    assert b"Error" not in stderr and time.monotonic() - sent < LATENCY_S, (after, stderr)
