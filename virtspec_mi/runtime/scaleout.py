"""
Scale-out: the readings of a sweep on Dask workers
==================================================

:func:`virtspec_mi.sweep`, :func:`virtspec_mi.gonio` and :func:`virtspec_mi.sphere_measure`
with ``workers=`` run the batches of their keyed plan (:func:`virtspec_mi.engine.readings.run`
of an instrument's :class:`~virtspec_mi.engine.plan.Plan`) on ``dask.distributed`` workers
instead of in this process. Nothing else changes: the driver (this process) plans the
batches, keeps the checkpoint and the progress bar, and every batch is traced by the one
function the in-process run calls, :func:`virtspec_mi.engine.readings.take_keyed_readings`
(the plan, plain values, is sent with every task). A reading's tallies depend on (seed,
its key) only, so a run on any number of workers gives tallies bit-identical to the
in-process run.

``workers``
    ``None``: in this process (no Dask). An int N: a ``LocalCluster`` of N worker
    processes (``processes=True``, one thread each, the ``spawn`` start method), closed
    when the sweep ends; at most :data:`WORKERS_PER_CORE` per core of this machine, and
    they ignore SIGINT (the driver stops the run: :mod:`virtspec_mi.base.interrupts`).
    A scheduler address (``"tcp://host:8786"``) or an existing ``distributed.Client``:
    that cluster (left running, not limited).

Per worker process, :class:`WorkerSetup` (a ``distributed.WorkerPlugin``, also run on a
worker that restarts) selects libLLVM and the Mitsuba variant, registers the project's
plugins (:func:`virtspec_mi.runtime.mitsuba`) — in the thread that runs the tasks
(mitsuba3 issue 457: plugins registered in the thread that set the variant), and every
task does it again where it runs (idempotent, microseconds) — and caps Dr.Jit's thread
pool at :data:`DRJIT_THREADS` so that the workers do not compete for the cores. Workers
load the scene themselves (once per process): an XML path must be readable at the same
path on every worker; a scene dict is sent to them (its Mitsuba transforms as 4×4
matrices: they do not pickle). A loaded ``mi.Scene`` cannot be sent (``ValueError``).

Tasks (blocks) are runs of consecutive engine batches. Their size follows one rule:
``readings per task = TASK_SECONDS × readings per second``, where the rate (the ray rate
divided by the rays per reading) is measured on the first task to come back (one probe
task of two batches is sent per worker; the faster batch counts, so the kernel's
compilation does not), and capped so that at least two tasks per worker remain (no idle
worker at the end). A task holds whole batches (``chunk_size`` rays each), so it is never
smaller than one. ``task_readings``
sets it instead. A task's batches come back together and are recorded in the
checkpoint as the tasks finish (``as_completed``); an interrupted sweep resumes without
tracing a recorded reading again. A worker that dies loses only its task: Dask
reschedules it on another worker (``distributed.scheduler.allowed-failures``), and a task
that raises is retried :data:`RETRIES` times before its error reaches the caller (an
error that is deterministic — a bad wavelength for the specimen — is thus raised after
three tries of its task; the other tasks go on meanwhile and are cancelled then).

A cluster with no worker (a scheduler whose workers have not started, or all of them
gone) cannot run a task: the sweep waits for one at most :data:`WORKER_TIMEOUT` seconds,
when it starts and whenever no task has finished for that long, then raises
``TimeoutError`` naming the scheduler. The ``seconds`` of a distributed run's result are
the tracing time summed over the tasks (worker-seconds, several per wall second), not the
wall time.

References
----------
Dask ``distributed`` documentation: LocalCluster, WorkerPlugin, as_completed.
Mitsuba 3 issue 457 (variant and plugins per thread).
"""

from __future__ import annotations

import asyncio
import logging
import math
import os
import pickle
import signal
import threading
import time
from contextlib import contextmanager
from typing import Any, Iterator

import numpy as np
from distributed import WorkerPlugin

from virtspec_mi.base.checks import shown_value
import virtspec_mi.base.interrupts as interrupts
from virtspec_mi.engine.plan import Plan
from virtspec_mi.engine.readings import BatchRunner, take_keyed_readings
from virtspec_mi.engine.tally import Tally
from virtspec_mi.runtime import mitsuba, variant
from virtspec_mi import scenes
from virtspec_mi.runtime.scene import find_bench

__all__ = [
    "TASK_SECONDS",
    "DRJIT_THREADS",
    "RETRIES",
    "WORKER_TIMEOUT",
    "WorkerSetup",
    "wait_for_a_worker",
    "WORKERS_PER_CORE",
    "local_worker_limit",
    "check_workers",
    "check_task_readings",
    "connect",
    "local_cluster",
    "portable_scene",
    "task_size",
    "dask_runner",
    "worker_state",
]

TASK_SECONDS: float = 5.0
"""Seconds of tracing a task (a block of readings) is sized for, long next to Dask's per-task overhead."""

DRJIT_THREADS: int = 1
"""Dr.Jit threads per worker process (one Dask thread each: the processes share the cores)."""

RETRIES: int = 2
"""Times Dask retries a task that raised (a worker that died is handled by the scheduler)."""

WORKERS_PER_CORE: int = 4
"""
Most local worker processes per core (``workers=N`` ≤ 4 × ``os.cpu_count()``): every worker
is a process with its own Mitsuba and Dr.Jit, so more only compete for the cores and the
memory (a scheduler address is not limited: its cluster's workers are its own).
"""

WORKER_TIMEOUT: float = 60.0
"""Seconds a sweep waits for a first worker (or, once none finishes a task, for any worker) before ``TimeoutError``."""

_POLL_SECONDS = 0.1  # as distributed.as_completed's own wait
_WAIT_STEP = 0.5  # seconds of one wait for a worker between two interrupt checks
_TRANSFORM = "__virtspec_transform4f__"
_setup_threads: set[int] = set()
_benches: dict[str, Any] = {}


def _initialise() -> None:
    """Mitsuba (libLLVM, variant, project plugins) in this thread, and Dr.Jit's pool capped (idempotent)."""

    mitsuba()
    import drjit as dr

    if dr.thread_count() != DRJIT_THREADS:
        dr.set_thread_count(DRJIT_THREADS)
    _setup_threads.add(threading.get_ident())


class WorkerSetup(WorkerPlugin):
    """
    The ``distributed.WorkerPlugin`` that prepares each worker process: runs
    :func:`_initialise` in the worker's task thread (its executor), so the variant is set
    and the plugins registered where the tasks run, and Dr.Jit's pool holds
    :data:`DRJIT_THREADS` threads. Registered once per client; Dask runs it again on
    every worker that joins or restarts.
    """

    name = "virtspec-mi-setup"

    def __init__(self, local: bool = False) -> None:
        self.local = local
        """Workers of a local cluster started for the run: they ignore SIGINT (see :meth:`setup`)."""

    async def setup(self, worker: Any) -> None:
        if self.local and threading.current_thread() is threading.main_thread():
            # Ctrl-C reaches the whole process group: the driver stops the run (its checkpoint saved) and
            # closes the cluster; a worker killed by it would only print a traceback and be restarted.
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        await asyncio.wrap_future(worker.executor.submit(_initialise))


def worker_state() -> dict[str, Any]:
    """What a task sees on its worker: pid, Mitsuba variant, Dr.Jit threads, whether set up in this thread."""

    import drjit as dr
    import mitsuba as mi

    return {"pid": os.getpid(), "variant": mi.variant(), "drjit_threads": dr.thread_count(),
            "set_up_here": threading.get_ident() in _setup_threads, "expected_variant": variant()}


def local_worker_limit() -> int:
    """
    Most worker processes a local cluster (``workers=N``) may start on this machine:
    :data:`WORKERS_PER_CORE` × ``os.cpu_count()``.
    """

    return WORKERS_PER_CORE * (os.cpu_count() or 1)


def check_workers(workers: Any) -> Any:
    """
    ``workers`` as a run takes it — ``None``; a whole number N (an int or a numeric string),
    1 ≤ N ≤ :func:`local_worker_limit` (each local worker is a process of its own); a
    scheduler address (``"tcp://host:8786"``, not limited: that cluster's workers are its
    own); or a ``distributed.Client`` — else ``ValueError`` naming the value and the range.
    """

    if workers is None:
        return None
    if isinstance(workers, str) and workers.strip().isdigit():
        workers = int(workers.strip())  # "2": a number, as everywhere
    if isinstance(workers, str) and workers.strip():
        return _scheduler_address(workers.strip())
    if isinstance(workers, (int, np.integer)) and not isinstance(workers, (bool, np.bool_)):
        limit = local_worker_limit()
        if workers < 1:
            raise ValueError(f"workers must be >= 1 worker processes (got {workers})")
        if workers > limit:
            raise ValueError(
                f"workers must be at most {limit} worker processes of a local cluster (got {shown_value(workers)}): "
                f"at most {WORKERS_PER_CORE} per core of the {os.cpu_count() or 1} of this machine, as each is a "
                "process with its own Mitsuba and more only compete for the cores and the memory; for a larger "
                "cluster give its scheduler address (--scheduler)")
        return int(workers)
    if type(workers).__name__ == "Client" and type(workers).__module__.startswith("distributed"):
        return workers
    raise ValueError("workers must be None (in this process), a whole number >= 1 (a local cluster of that many "
                     "processes), a scheduler address such as 'tcp://host:8786' or a distributed.Client (got "
                     f"{workers!r})")


def _scheduler_address(address: str) -> str:
    """A scheduler address Dask can connect to (``scheme://host:port``; a TCP/TLS one needs its port)."""

    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port

    from distributed.comm.registry import backends

    try:
        scheme, location = parse_address(address)
        if scheme not in backends:
            raise ValueError(f"no Dask transport {scheme!r}; one of {', '.join(sorted(backends))}")
        if scheme in ("tcp", "tls", "ws", "wss"):
            parse_host_port(location)
        if scheme == "inproc" and len(location.split("/")) != 3:  # Dask's own form: inproc://HOST/PID/N
            raise ValueError("an in-process address is inproc://HOST/PID/N, the address of a scheduler started in "
                             "this process (scheduler.address)")
    except ValueError as error:
        raise ValueError(f"workers must be a whole number of local worker processes or a scheduler address such as "
                         f"'tcp://host:8786' (got {address!r}: {error})") from None
    return address


def check_task_readings(task_readings: Any) -> int | None:
    """``task_readings`` when it is ``None`` or an int >= 1; else ``ValueError``."""

    if task_readings is not None and (isinstance(task_readings, bool) or not isinstance(task_readings, int)
                                      or task_readings < 1):
        raise ValueError(f"task_readings must be an int >= 1 readings per task, or None (got {task_readings!r})")
    return task_readings


@contextmanager
def local_cluster(n_workers: int) -> Iterator[Any]:
    """
    A ``distributed.Client`` on a ``LocalCluster`` of ``n_workers`` processes, one thread
    each, started with ``spawn`` (never ``fork``: Dr.Jit's threads do not survive it) — the
    setting held while the cluster lives, so a restarted worker is spawned too. Its
    processes log nothing below ``CRITICAL``: a task's failure reaches the driver through
    its future, and a Ctrl-C that stops the scheduler first must not print a worker's
    heartbeat traceback ("Failed to communicate with scheduler") on the user's terminal.
    """

    import dask
    from distributed import Client, LocalCluster

    with dask.config.set({"distributed.worker.multiprocessing-method": "spawn"}):
        with LocalCluster(n_workers=n_workers, processes=True, threads_per_worker=1, dashboard_address=":0",
                          silence_logs=logging.CRITICAL) as cluster, Client(cluster) as client:
            yield client


@contextmanager
def connect(workers: Any) -> Iterator[Any]:
    """A ``distributed.Client`` for ``workers`` (int, address or ``Client``) with :class:`WorkerSetup` registered."""

    workers = check_workers(workers)
    if workers is None:
        raise ValueError("workers=None runs in this process: there is no cluster to connect to")
    if isinstance(workers, int):
        with local_cluster(workers) as client:
            _register(client, local=True)
            yield client
        return
    if isinstance(workers, str):
        from distributed import Client

        with Client(workers) as client:
            _register(client)
            yield client
        return
    _register(workers)
    yield workers


def _register(client: Any, local: bool = False) -> None:
    """
    Register :class:`WorkerSetup` on every worker of ``client``'s cluster (and on those
    that join later); ``local``: a cluster started for the run (its workers ignore SIGINT).
    """

    register = getattr(client, "register_plugin", None) or client.register_worker_plugin
    register(WorkerSetup(local), name=WorkerSetup.name)


def portable_scene(scene: Any) -> Any:
    """
    ``scene`` as it is sent to the workers: an XML path as a string, a dict with each
    Mitsuba transform replaced by its 4×4 matrix (they do not pickle); ``ValueError`` for
    a loaded ``mi.Scene`` (the workers load the scene themselves).
    """

    scene = scenes.resolve(scene)  # a shipped scene's name: its file, not a name in the workers' directory
    if isinstance(scene, (str, os.PathLike)):
        return os.path.abspath(os.fspath(scene))  # the same path on every worker, whatever its directory
    if isinstance(scene, dict):
        portable = {key: _portable_value(value) for key, value in scene.items()}
        try:
            pickle.dumps(portable)
        except Exception as error:  # a Mitsuba object other than a transform, a lambda …
            raise ValueError(f"scene dict holds a value that cannot be sent to the workers ({error}); give an XML "
                             "path, or plain values and transforms") from None
        return portable
    raise ValueError(f"scene must be an XML path or a scene dict to run on workers (got {type(scene).__name__}): "
                     "each worker loads it itself")


def _portable_value(value: Any) -> Any:
    if isinstance(value, dict):
        return {key: _portable_value(item) for key, item in value.items()}
    if type(value).__name__.endswith("Transform4f") and hasattr(value, "matrix"):
        return {_TRANSFORM: np.array(value.matrix, dtype=np.float64).tolist()}
    return value


def _restored(scene: Any) -> Any:
    """The scene of :func:`portable_scene` as Mitsuba loads it (transforms rebuilt from their matrices)."""

    if not isinstance(scene, dict):
        return scene
    if set(scene) == {_TRANSFORM}:
        return mitsuba().ScalarTransform4f(np.array(scene[_TRANSFORM], dtype=np.float64))
    return {key: _restored(value) for key, value in scene.items()}


def wait_for_a_worker(client: Any) -> int:
    """
    The number of workers of ``client``'s cluster once it has one, waiting at most
    :data:`WORKER_TIMEOUT` seconds; ``TimeoutError`` naming the scheduler otherwise.
    """

    deadline = time.monotonic() + WORKER_TIMEOUT
    while not _a_worker_within(client, max(0.01, min(_WAIT_STEP, deadline - time.monotonic()))):
        interrupts.check()  # waited in steps, each a safe point for an interrupt
        if time.monotonic() < deadline:
            continue
        address = getattr(getattr(client, "scheduler", None), "address", "?")
        raise TimeoutError(f"no Dask worker is connected to the scheduler {address} (waited WORKER_TIMEOUT = "
                           f"{WORKER_TIMEOUT:g} s): start workers for it (`dask worker {address}`), or check the "
                           "address; readings already finished are kept in the sweep's checkpoint, if it has one"
                           ) from None
    return max(1, len(client.scheduler_info().get("workers", {})))


def _a_worker_within(client: Any, seconds: float) -> bool:
    """True once ``client``'s cluster has a worker, False if none came within ``seconds``."""

    try:
        client.wait_for_workers(1, timeout=seconds)
    except TimeoutError:  # distributed's WorkerStartTimeoutError is one
        return False
    return True


def _as_finished(client: Any, finished: Any) -> Iterator[Any]:
    """
    The futures of ``finished`` (a ``distributed.as_completed``, which may grow) as they
    finish; once none has finished for :data:`WORKER_TIMEOUT` seconds, the cluster must
    still have a worker (:func:`wait_for_a_worker`: ``TimeoutError`` otherwise) — tasks
    longer than that on live workers are waited for. ``as_completed`` itself checks every
    0.1 s; so does this.
    """

    quiet_since = time.monotonic()
    while not finished.is_empty():
        interrupts.check()  # a safe point every poll: Ctrl-C or SIGTERM stops the run within 0.1 s
        ready = finished.next_batch(block=False)
        if ready:
            yield from ready
            quiet_since = time.monotonic()
        elif time.monotonic() - quiet_since > WORKER_TIMEOUT:
            wait_for_a_worker(client)
            quiet_since = time.monotonic()
        else:
            time.sleep(_POLL_SECONDS)


def _run_block(scene: Any, defines: dict[str, Any] | None, fingerprint: str, plan: Plan,
               batches: list[np.ndarray]) -> list[tuple[np.ndarray, Tally]]:
    """
    The task: each batch of the block traced by ``take_keyed_readings(bench, plan, batch)``
    — exactly the in-process runner's call — its tally carrying its seconds. The scene is
    loaded (with ``defines``) once per worker process and kept by its fingerprint.
    """

    _initialise()  # in the thread this task runs in (idempotent)
    bench = _benches.get(fingerprint)
    if bench is None:
        bench = _benches[fingerprint] = find_bench(_restored(scene), defines)
    done = []
    for batch in batches:
        start = time.perf_counter()
        done.append((batch, take_keyed_readings(bench, plan, batch).with_seconds(time.perf_counter() - start)))
    return done


def _tasks(batches: list[np.ndarray], readings: int) -> list[list[np.ndarray]]:
    """Consecutive ``batches`` grouped into tasks of at least ``readings`` readings (the last may hold fewer)."""

    tasks: list[list[np.ndarray]] = [[]]
    count = 0
    for batch in batches:
        if count >= readings:
            tasks.append([])
            count = 0
        tasks[-1].append(batch)
        count += len(batch)
    return [task for task in tasks if task]


def task_size(rate: float, remaining: int, n_workers: int, seconds: float = TASK_SECONDS) -> int:
    """
    Readings per task: ``seconds × rate`` (``rate``: readings per second of one worker),
    at most ``⌈remaining / (2 × n_workers)⌉`` so every worker gets two tasks or more, at least 1.
    """

    wanted = int(seconds * rate) if math.isfinite(rate) else remaining
    return max(1, min(wanted, math.ceil(remaining / (2 * max(1, n_workers)))))


def dask_runner(client: Any, scene: Any, fingerprint: str, plan: Plan, task_readings: int | None = None,
                defines: dict[str, Any] | None = None) -> BatchRunner:
    """
    A :data:`~virtspec_mi.engine.readings.BatchRunner` that runs the batches of ``plan``
    on ``client``'s workers in tasks sized by :func:`task_size` (or of ``task_readings``
    readings), yields each task's batches as it finishes and cancels what is left when it
    is closed. Every task receives the plan (plain values) and traces its batches with
    :func:`~virtspec_mi.engine.readings.take_keyed_readings`, as the in-process runner
    does; ``defines``: the XML scene's ``$name`` values, with which every worker loads it.
    """

    check_task_readings(task_readings)
    portable = portable_scene(scene)

    def runner(batches: list[np.ndarray]) -> Iterator[tuple[np.ndarray, Tally]]:
        from distributed import as_completed

        n_workers = wait_for_a_worker(client)

        def submit(tasks: list[list[np.ndarray]]) -> list[Any]:
            return [client.submit(_run_block, portable, defines, fingerprint, plan, task, pure=False,
                                  retries=RETRIES) for task in tasks]

        left = list(batches)
        if task_readings is not None:
            first, left = _tasks(left, task_readings), []
        else:  # one probe task of two batches per worker measures the rate
            probes = min(len(left), 2 * n_workers)
            first, left = [left[i:i + 2] for i in range(0, probes, 2)], left[probes:]
        futures = submit(first)
        finished = as_completed(futures)
        try:
            for future in _as_finished(client, finished):
                results = future.result()
                if left:  # sized from the first probe back, submitted before its results are recorded
                    rate = max(len(b) / max(t.seconds, 1e-9) for b, t in results)
                    remaining = sum(len(b) for b in left)
                    more = submit(_tasks(left, task_size(rate, remaining, n_workers)))
                    futures += more
                    finished.update(more)
                    left = []
                yield from results
        finally:
            client.cancel([f for f in futures if not f.done()])

    return runner
