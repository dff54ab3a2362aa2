"""Tests of virtspec_mi.runtime.scaleout: sweeps on a 2-worker Dask LocalCluster (spawned processes).

One cluster serves the module (started with the project's own ``scaleout.connect(2)``):
the counts of a distributed sweep are bit-identical to the in-process sweep's, an
interrupted distributed sweep resumes without tracing a recorded reading again, and a
worker killed mid-sweep (SIGKILL, restarted by its nanny) changes nothing in the result.
"""

from __future__ import annotations

import json
import os
import time

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.runtime import scaleout
from virtspec_mi.engine.checkpoint import Checkpoint
from virtspec_mi.cli import main
from virtspec_mi.kernel.counts import Counts

SMALL = {"theta_i": [0, 40, 75], "wavelengths": "450:650:50", "rays": 20_000, "progress": False}
"""15 readings of 20,000 rays: a sweep of a fraction of a second."""


@pytest.fixture(scope="module")
def client():
    """A 2-worker LocalCluster (processes, spawn, one thread each) with the WorkerSetup plugin."""

    with scaleout.connect(2) as client:
        yield client


@pytest.fixture(scope="module")
def dielectric_dict(mi):
    """A scene dict (its transforms are Mitsuba objects that do not pickle)."""

    return vm.instrument_scene({"type": "simple_dielectric", "eta": 1.5})


def same_counts(a: vm.Result, b: vm.Result) -> None:
    assert a.dims == b.dims and np.array_equal(a.wavelengths, b.wavelengths)
    for name in Counts.names():
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    assert (a.pilot is None) == (b.pilot is None)
    if a.pilot is not None:
        for name in Counts.names():
            assert np.array_equal(getattr(a.pilot, name), getattr(b.pilot, name), equal_nan=True), name


def test_workers_are_separate_processes_set_up_where_their_tasks_run(client):
    workers = list(client.scheduler_info()["workers"])
    assert len(workers) == 2
    states = client.gather([client.submit(scaleout.worker_state, pure=False, workers=[w]) for w in workers])
    assert len({s["pid"] for s in states}) == 2 and os.getpid() not in {s["pid"] for s in states}
    for state in states:
        assert state["variant"] == state["expected_variant"]
        assert state["drjit_threads"] == scaleout.DRJIT_THREADS
        assert state["set_up_here"]  # the plugin set Mitsuba up in the thread that runs the tasks
    methods = client.run(lambda: __import__("dask").config.get("distributed.worker.multiprocessing-method"))
    assert set(methods.values()) == {"spawn"}


@pytest.mark.parametrize("scene, extra", [
    ("dict", {"bound": "hoeffding", "mu": 0.05}),
    ("dict", {"bound": "two-stage", "mu": 0.02, "rays": None}),
    ("scenes/diamond_collimated.xml", {}),  # wavelength-independent: traced once per angle
    ("scenes/soybean_abmb.xml", {"theta_i": [8, 60]}),  # an ABM leaf: every reading traced on its own
    ("scenes/soybean_abmb.xml", {"task_readings": None}),  # tasks sized from the probes' measured rate
], ids=["dict", "two-stage", "xml-shared", "leaf", "leaf-sized-by-rate"])
def test_a_sweep_on_two_worker_processes_is_bit_identical_to_the_in_process_one(client, dielectric_dict, scene,
                                                                                extra):
    scene = dielectric_dict if scene == "dict" else scene
    settings = {**SMALL, "task_readings": 2, **extra}
    if settings["rays"] is None:
        del settings["rays"]
    task_readings = settings.pop("task_readings")
    here = vm.sweep(scene, **settings)
    there = vm.sweep(scene, workers=client, chunk_size=1024, task_readings=task_readings, **settings)
    same_counts(here, there)
    assert there.scene == here.scene  # the same fingerprint: the same scene


def test_a_parameter_sweep_with_defines_on_workers_is_bit_identical_and_leaves_the_workers_scene_as_loaded(
        client, tmp_path):
    """Specimen parameters and XML ``$name`` defines travel with the tasks (engine.take_keyed_readings)."""

    settings = {"theta_i": 8, "wavelengths": [550, 800], "rays": 5_000, "progress": False,
                "defines": {"side": "abaxial"}, "parameters": {"specimen.thickness": [1.2e-4, 2e-4]}}
    here = vm.sweep("scenes/soybean_abmb.xml", **settings)
    there = vm.sweep("scenes/soybean_abmb.xml", workers=client, task_readings=1, out=tmp_path / "lut.zarr",
                     **settings)
    same_counts(here, there)
    same_counts(here, vm.read_result(tmp_path / "lut.zarr"))  # streamed into Zarr as the tasks finished
    assert "on Dask workers: worker time, not wall time" in there.summary()  # Result.seconds: summed worker time
    assert there.dims == ("wavelength", "theta_i", "specimen.thickness")
    plain = {k: v for k, v in settings.items() if k != "parameters"}
    # each worker's cached scene got its own thickness back after every task
    same_counts(vm.sweep("scenes/soybean_abmb.xml", **plain),
                vm.sweep("scenes/soybean_abmb.xml", workers=client, task_readings=1, **plain))


def test_an_interrupted_distributed_sweep_resumes_without_tracing_a_finished_reading(client, dielectric_dict,
                                                                                    monkeypatch, tmp_path):
    checkpoint = tmp_path / "sweep.partial.json"
    record = Checkpoint.record
    first: list[np.ndarray] = []

    def interrupting(self, batch, *args):
        if len(first) == 2:
            raise KeyboardInterrupt  # as a Ctrl-C while the workers trace the other blocks
        first.append(batch.copy())
        record(self, batch, *args)

    monkeypatch.setattr(Checkpoint, "record", interrupting)
    with pytest.raises(KeyboardInterrupt):
        vm.sweep(dielectric_dict, workers=client, chunk_size=1024, task_readings=1, checkpoint=checkpoint, **SMALL)
    done = set(json.loads(checkpoint.read_text())["done"])
    assert done == {int(k) for batch in first for k in batch} and 0 < len(done) < 15

    second: list[np.ndarray] = []
    sent: list[int] = []

    def spying(self, batch, *args):
        second.append(batch.copy())
        record(self, batch, *args)

    def submitting(function, *args, **kwargs):  # what the workers are asked to trace
        if function is scaleout._run_block:
            sent.extend(int(k) for batch in args[-1] for k in batch)
        return submit(function, *args, **kwargs)

    submit = client.submit
    monkeypatch.setattr(Checkpoint, "record", spying)
    monkeypatch.setattr(client, "submit", submitting)
    resumed = vm.sweep(dielectric_dict, workers=client, chunk_size=1024, task_readings=1, checkpoint=checkpoint,
                       **SMALL)
    again = [int(k) for batch in second for k in batch]
    assert sorted(sent) == sorted(again)  # every block sent to a worker was recorded once
    assert not done & set(again)  # no finished reading traced again
    assert sorted(done | set(again)) == list(range(15)) and len(again) == len(set(again))
    assert not checkpoint.exists()
    monkeypatch.undo()
    same_counts(resumed, vm.sweep(dielectric_dict, **SMALL))


def test_an_error_on_a_worker_reaches_the_caller_as_itself(client):
    # the ABM leaf refuses wavelengths outside its data, in take_readings: on the worker here
    with pytest.raises(ValueError, match="wavelength"):
        vm.sweep("scenes/soybean_abmb.xml", theta_i=[8], wavelengths="300 500", rays=1000, progress=False,
                 workers=client)


def test_the_cli_runs_a_sweep_on_a_scheduler_address(client, tmp_path):
    address = client.scheduler.address
    out = tmp_path / "sweep.nc"
    assert main(["sweep", "scenes/diamond_collimated.xml", "--theta-i", "0", "45", "--wavelengths", "500", "600",
                 "--rays", "5000", "--scheduler", address, "--task-readings", "1", "--out", str(out),
                 "--quiet"]) == 0
    same_counts(vm.read_result(out), vm.sweep("scenes/diamond_collimated.xml", theta_i=[0, 45],
                                              wavelengths="500 600", rays=5000, progress=False))


@pytest.mark.parametrize("parameters", [None, {"specimen.eta": [1.3, 1.6]}], ids=["grid", "parameter-sweep"])
def test_killing_a_worker_mid_sweep_gives_the_identical_result(client, dielectric_dict, tmp_path, parameters):
    # 48 readings (3 traced rows of the wavelength-independent dielectric), x 2 parameter points.
    # Every worker is armed: the first task to trace a batch SIGKILLs its own process (a flag
    # file, created exclusively, makes it exactly one kill), so the kill is mid-sweep by
    # construction, not by timing.
    settings = {**SMALL, "wavelengths": "400:700:20", "rays": 100_000, "parameters": parameters}
    flag = str(tmp_path / "killed")

    def arm(flag: str) -> None:
        import os
        import signal

        from virtspec_mi.runtime import scaleout as worker_side

        original = worker_side.take_keyed_readings

        def dying(*args, **kwargs):
            try:
                handle = os.open(flag, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                return original(*args, **kwargs)
            os.write(handle, str(os.getpid()).encode())
            os.close(handle)
            os.kill(os.getpid(), signal.SIGKILL)

        worker_side.armed_original = original
        worker_side.take_keyed_readings = dying

    def disarm() -> None:
        from virtspec_mi.runtime import scaleout as worker_side

        if hasattr(worker_side, "armed_original"):
            worker_side.take_keyed_readings = worker_side.armed_original
            del worker_side.armed_original

    client.run(arm, flag)
    try:
        there = vm.sweep(dielectric_dict, workers=client, chunk_size=1024, task_readings=2, **settings)
    finally:
        client.run(disarm)
    with open(flag) as handle:
        killed = int(handle.read())
    same_counts(there, vm.sweep(dielectric_dict, **settings))
    client.wait_for_workers(2, timeout=120)  # the nanny restarted it, set up by the plugin again
    states = client.gather([client.submit(scaleout.worker_state, pure=False, workers=[w])
                            for w in client.scheduler_info()["workers"]])
    assert killed not in {s["pid"] for s in states}
    assert all(s["set_up_here"] and s["drjit_threads"] == scaleout.DRJIT_THREADS for s in states)


def test_a_scheduler_without_workers_raises_after_the_worker_timeout(dielectric_dict, monkeypatch):
    from distributed import LocalCluster

    monkeypatch.setattr(scaleout, "WORKER_TIMEOUT", 0.5)
    with LocalCluster(n_workers=0, processes=False, dashboard_address=":0") as empty:
        start = time.perf_counter()
        with pytest.raises(TimeoutError, match="no Dask worker is connected to the scheduler .*WORKER_TIMEOUT = 0.5 s"):
            vm.sweep(dielectric_dict, workers=empty.scheduler_address, **SMALL)
        assert time.perf_counter() - start < 30  # not forever


def test_tasks_left_without_any_worker_mid_sweep_raise_after_the_worker_timeout(monkeypatch):
    """``_as_finished``: quiet for WORKER_TIMEOUT s -> a worker must still be there; long tasks on live ones wait."""

    class Pending:  # an as_completed whose futures finish after `after` polls (never: None)
        def __init__(self, after):
            self.after, self.polls, self.left = after, 0, 1

        def is_empty(self):
            return not self.left

        def next_batch(self, block):
            self.polls += 1
            if self.after is not None and self.polls > self.after:
                self.left = 0
                return ["future"]
            return []

    class Cluster:
        def __init__(self, workers):
            self.workers, self.asked = workers, 0
            self.scheduler = type("Scheduler", (), {"address": "tcp://10.0.0.1:8786"})()

        def wait_for_workers(self, n, timeout):
            self.asked += 1
            if not self.workers:
                raise TimeoutError

        def scheduler_info(self):
            return {"workers": dict.fromkeys(range(self.workers))}

    monkeypatch.setattr(scaleout, "WORKER_TIMEOUT", 0.15)
    with pytest.raises(TimeoutError, match="no Dask worker is connected to the scheduler tcp://10.0.0.1:8786"):
        list(scaleout._as_finished(Cluster(0), Pending(None)))
    alive = Cluster(2)
    assert list(scaleout._as_finished(alive, Pending(5))) == ["future"]  # 0.5 s of a long task: still waited for
    assert alive.asked >= 1


def test_densities_on_workers_hold_one_cluster_for_every_density(client, monkeypatch, capsys):
    connected = []
    connect = scaleout.connect

    def counting(workers):
        connected.append(workers)
        return connect(workers)

    monkeypatch.setattr(scaleout, "connect", counting)
    address = client.scheduler.address
    assert main(["sweep", "scenes/diamond_collimated.xml", "--theta-i", "0", "45", "--wavelengths", "500",
                 "--densities", "2", "3", "--scheduler", address, "--quiet"]) == 0
    assert connected[0] == address and len(connected) == 4  # the CLI's, then the warm-up and 2 sweeps through it
    assert all(type(w).__name__ == "Client" for w in connected[1:])
    assert "summed over the workers" in capsys.readouterr().out


@pytest.mark.parametrize("workers, message", [
    (0, "workers must be >= 1"),
    (True, "workers must be None"),
    (2.5, "workers must be None"),
])
def test_bad_workers_name_the_parameter(dielectric_dict, workers, message):
    with pytest.raises(ValueError, match=message):
        vm.sweep(dielectric_dict, workers=workers, **SMALL)


def test_a_loaded_scene_or_task_readings_without_workers_is_refused_before_any_cluster(diamond, dielectric_dict):
    with pytest.raises(ValueError, match="XML path or a scene dict"):
        vm.sweep(diamond, workers=2, **SMALL)
    unsendable = {**dielectric_dict, "note": {"type": "scene", "hook": lambda: None}}
    with pytest.raises(ValueError, match="cannot be sent to the workers"):
        scaleout.portable_scene(unsendable)
    with pytest.raises(ValueError, match="task_readings needs workers"):
        vm.sweep(dielectric_dict, task_readings=3, **SMALL)
    with pytest.raises(ValueError, match="task_readings must be an int >= 1"):
        vm.sweep(dielectric_dict, workers=2, task_readings=0, **SMALL)


def test_task_size_is_the_task_seconds_of_tracing_with_two_tasks_per_worker_left():
    assert scaleout.task_size(rate=100.0, remaining=100_000, n_workers=2) == int(scaleout.TASK_SECONDS * 100)
    assert scaleout.task_size(rate=100.0, remaining=400, n_workers=2) == 100  # two tasks per worker
    assert scaleout.task_size(rate=0.01, remaining=400, n_workers=2) == 1
    tasks = scaleout._tasks([np.arange(i, i + 3) for i in range(0, 30, 3)], 7)
    assert [sum(len(b) for b in t) for t in tasks] == [9, 9, 9, 3]
    assert np.array_equal(np.concatenate([b for t in tasks for b in t]), np.arange(30))


def test_a_portable_scene_dict_rebuilds_the_same_transforms(dielectric_dict):
    portable = scaleout.portable_scene(dielectric_dict)
    import pickle

    restored = scaleout._restored(pickle.loads(pickle.dumps(portable)))
    for shape in ("emitter", "specimen"):
        assert np.array_equal(np.array(restored[shape]["to_world"].matrix),
                              np.array(dielectric_dict[shape]["to_world"].matrix))
    assert restored["specimen"]["bsdf"] == dielectric_dict["specimen"]["bsdf"]


@pytest.mark.slow
def test_a_goniophotometer_reading_and_a_sphere_spectrum_on_two_workers_are_bit_identical(client, tmp_path):
    """Every instrument's plan runs on the workers (engine.take_keyed_readings): bins, sums and both groups."""

    rough = vm.instrument_scene({"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5})
    gonio = dict(theta_i=[0, 40, 75], wavelengths="450:650:100", rays=20_000, theta_o_bins=4, phi_o_bins=6,
                 progress=False)
    here = vm.gonio(rough, **gonio)
    there = vm.gonio(rough, workers=client, chunk_size=1024, task_readings=2, **gonio)
    assert np.array_equal(here.bin_counts, there.bin_counts)
    same_counts(here.result, there.result)
    sphere = dict(wavelengths="400:2500:300", rays=5_000, progress=False)
    here = vm.sphere_measure("scenes/sphere_150mm_8d.xml", **sphere)
    there = vm.sphere_measure("scenes/sphere_150mm_8d.xml", workers=client, task_readings=3,
                              out=tmp_path / "sphere.nc", **sphere)
    for configuration in ("sample", "standard"):
        for name, values in here.counts[configuration].items():
            assert np.array_equal(values, there.counts[configuration][name]), (configuration, name)
    assert np.array_equal(vm.read_result(tmp_path / "sphere.nc").counts["sample"]["detected"],
                          here.counts["sample"]["detected"])
