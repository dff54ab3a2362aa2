"""
A soybean leaf table in one process and on a 2-worker Dask cluster (issue 17)
=============================================================================

Prints, in one run, side by side:

(a) **The table** — the soybean leaf (``scenes/soybean_abmb.xml``, ``abm_b``) at θi = 8°,
    421 wavelengths (400:2500:5 nm) × a grid of two specimen parameters, 5 values each
    (``specimen.thickness`` 1.2e-4:2.0e-4:2e-5 m × ``specimen.chlorophyll_a``
    2:6:1 kg m⁻³; ``--quick``: 2 values each), certified at μ = 0.01, δ = 0.01
    (Hoeffding N = 26,492 rays per reading), seed 0: 10,525 readings (``--quick``:
    1,684). One in-process ``sweep(..., parameters=...)`` and the same sweep with
    ``workers=client`` on a ``LocalCluster`` of 2 worker processes (one thread and one
    Dr.Jit thread each, tasks sized by the rule of :mod:`virtspec_mi.runtime.scaleout`). Both
    warm (one small parameter sweep first compiles the kernel, on every worker too).
    Wall time, rays/s, the ratio, tasks, and that the counts are identical.
(b) **Per-task overhead** — 400 empty tasks (``client.submit`` of a no-op, then gather):
    wall ms per task; 20 sequential round trips; and 200 tiny sweep tasks (one reading
    of 1,024 rays each, ``task_readings=1``) against the same sweep in process: wall ms per
    task.
(c) **Projection** — a 10⁶-reading table of the same readings on 100 workers, on paper:
    compute = 10⁶ / (100 × readings per worker-second, from (a)), tasks of
    ``TASK_SECONDS`` each, each costing the worker time Dask adds to a tiny task (b: 2 ×
    its wall ms on 2 workers − the in-process ms per batch), and the scheduler's floor
    (every task through one scheduler at the empty-task rate); the larger of the two.

Run::

    .venv/bin/python benchmarks/dask_sweep.py            # the 5 x 5 x 421 table (≈ 6–10 min on 2 busy cores)
    .venv/bin/python benchmarks/dask_sweep.py --quick    # 2 x 2 x 421

2 workers on a 2-core machine share the cores the in-process sweep already uses (Dr.Jit
runs 2 threads there): the ratio shows the cost of the scale-out, not a gain. Other work
on the machine slows every figure: the 1-minute load average is printed (before and
after).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from revisions import load_average, machine, machine_lines  # noqa: E402

import virtspec_mi as vm  # noqa: E402
from virtspec_mi.runtime import scaleout  # noqa: E402
from virtspec_mi.kernel.counts import Counts  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
LEAF = str(ROOT / "scenes" / "soybean_abmb.xml")
TABLE = {"theta_i": 8, "wavelengths": "400:2500:5", "mu": 0.01, "delta": 0.01, "seed": 0, "progress": False}
PARAMETERS = {"specimen.thickness": "1.2e-4:2.0e-4:2e-5", "specimen.chlorophyll_a": "2:6:1"}  # 5 x 5
QUICK = {"specimen.thickness": [1.2e-4, 2.0e-4], "specimen.chlorophyll_a": [2, 6]}  # 2 x 2
TARGET_READINGS, TARGET_WORKERS = 1_000_000, 100


def _noop(i: int) -> int:
    return i


def identical(a: vm.Result, b: vm.Result) -> bool:
    return all(np.array_equal(getattr(a, n), getattr(b, n), equal_nan=True) for n in Counts.names())


def table(client, parameters: dict) -> dict:
    warm = {"theta_i": [8], "wavelengths": "500:600:20", "rays": 1000, "progress": False,
            "parameters": {"specimen.thickness": [1.5e-4, 1.6e-4]}}
    vm.sweep(LEAF, **warm)  # compiles the kernel here
    start = time.perf_counter()
    here = vm.sweep(LEAF, parameters=parameters, **TABLE)
    here_s = time.perf_counter() - start
    vm.sweep(LEAF, workers=client, task_readings=1, **warm)  # every worker compiles (or loads) the kernel
    tasks = []
    submit = client.submit

    def counting(*args, **kwargs):
        if args and args[0] is scaleout._run_block:
            tasks.append(len(args[-1]))
        return submit(*args, **kwargs)

    client.submit = counting
    try:
        start = time.perf_counter()
        there = vm.sweep(LEAF, parameters=parameters, workers=client, **TABLE)
        there_s = time.perf_counter() - start
    finally:
        client.submit = submit
    rays = int(here.rays.sum())
    return {"readings": here.rays.size, "dims": " x ".join(f"{n} {d}" for d, n in zip(here.dims, here.shape)),
            "rays": rays, "rays_per_reading": int(here.rays.flat[0]),
            "here_s": here_s, "there_s": there_s, "here_traced_s": here.seconds, "worker_s": there.seconds,
            "tasks": len(tasks), "identical": identical(here, there)}


def overhead(client) -> dict:
    futures = [client.submit(_noop, i, pure=False) for i in range(10)]
    client.gather(futures)
    start = time.perf_counter()
    client.gather([client.submit(_noop, i, pure=False) for i in range(400)])
    empty_ms = (time.perf_counter() - start) / 400 * 1e3
    start = time.perf_counter()
    for i in range(20):
        client.submit(_noop, i, pure=False).result()
    round_ms = (time.perf_counter() - start) / 20 * 1e3
    tiny = {"theta_i": [8], "wavelengths": "400:2390:10", "rays": 1024, "chunk_size": 1024, "progress": False}
    vm.sweep(LEAF, **tiny)
    start = time.perf_counter()
    vm.sweep(LEAF, **tiny)
    here_ms = (time.perf_counter() - start) / 200 * 1e3
    start = time.perf_counter()
    vm.sweep(LEAF, workers=client, task_readings=1, **tiny)
    there_ms = (time.perf_counter() - start) / 200 * 1e3
    return {"empty_ms": empty_ms, "round_ms": round_ms, "tiny_here_ms": here_ms, "tiny_there_ms": there_ms}


def projection(t: dict, o: dict, n_workers: int = 2) -> dict:
    rate = t["readings"] / t["worker_s"]  # readings per worker-second (tracing only)
    per_task = max(1, int(scaleout.TASK_SECONDS * rate))
    tasks = math.ceil(TARGET_READINGS / per_task)
    compute = TARGET_READINGS / (TARGET_WORKERS * rate)
    # worker-seconds a task costs beyond the same batch in process (its launch is paid either way)
    task_cost = max(0.0, o["tiny_there_ms"] * n_workers - o["tiny_here_ms"]) / 1e3
    with_overhead = compute * (1 + task_cost / scaleout.TASK_SECONDS)
    floor = tasks * o["empty_ms"] / 1e3  # one scheduler, every task through it
    return {"rate": rate, "per_task": per_task, "tasks": tasks, "compute_s": compute, "task_cost_s": task_cost,
            "projected_s": max(with_overhead, floor), "floor_s": floor}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--quick", action="store_true", help="2 x 2 parameter values x 421 wavelengths")
    args = parser.parse_args()
    info = machine()
    load_before = load_average()
    start = time.perf_counter()
    with scaleout.connect(2) as client:
        startup = time.perf_counter() - start
        t = table(client, QUICK if args.quick else PARAMETERS)
        o = overhead(client)
    info["load"] = round(load_average(), 2)
    p = projection(t, o)
    n = t["rays_per_reading"]
    print(f"table: {t['dims']} (theta_i = 8 deg, mu = delta = 0.01)")
    print()
    print("| case | readings | rays | wall s | Mray/s | tasks |")
    print("|---|---|---|---|---|---|")
    print(f"| in process (Dr.Jit 2 threads) | {t['readings']:,} | {n:,} x {t['readings']:,} | {t['here_s']:.2f} | "
          f"{t['rays'] / t['here_s'] / 1e6:.2f} | - |")
    print(f"| 2-worker LocalCluster (1 thread each) | {t['readings']:,} | {n:,} x {t['readings']:,} | "
          f"{t['there_s']:.2f} | {t['rays'] / t['there_s'] / 1e6:.2f} | {t['tasks']} |")
    print()
    print(f"- ratio in-process / 2 workers (wall): {t['here_s'] / t['there_s']:.2f}; counts identical: "
          f"{t['identical']}")
    print(f"- tracing seconds summed over the workers: {t['worker_s']:.2f} (in process: {t['here_traced_s']:.2f}); "
          f"cluster start-up (2 spawned workers, plugin set-up): {startup:.2f} s, not in the wall times")
    print(f"- per-task overhead: empty tasks {o['empty_ms']:.2f} ms each (400 in flight), sequential round trip "
          f"{o['round_ms']:.2f} ms; tiny sweep tasks (1 reading of 1,024 rays) {o['tiny_there_ms']:.2f} ms of wall "
          f"each on 2 workers vs {o['tiny_here_ms']:.2f} ms per batch in process -> Dask adds "
          f"{max(0.0, o['tiny_there_ms'] * 2 - o['tiny_here_ms']):.2f} ms of worker time per task")
    print(f"- projection, {TARGET_READINGS:.0e} readings (these, N = {n:,}) on {TARGET_WORKERS} workers: "
          f"{p['rate']:.1f} readings per worker-second -> tasks of {p['per_task']:,} readings "
          f"({scaleout.TASK_SECONDS:g} s), {p['tasks']:,} tasks; compute {p['compute_s']:.0f} s, overhead "
          f"{p['task_cost_s'] * 1e3:.1f} ms per task ({p['task_cost_s'] / scaleout.TASK_SECONDS:.2%}), "
          f"scheduler floor {p['floor_s']:.1f} s -> about {p['projected_s']:.0f} s "
          f"({p['projected_s'] / 60:.1f} min)")
    per_task = t["there_s"] * 2 / max(1, t["tasks"]) * 1e3  # worker ms per table task: wall x 2 workers / tasks
    tracing = t["worker_s"] / max(1, t["tasks"]) * 1e3
    print(f"- per table task: {per_task:,.0f} ms of worker time (wall x 2 workers / tasks), {tracing:,.0f} ms of it "
          f"tracing -> {per_task - tracing:,.0f} ms ({(per_task - tracing) / per_task:.1%}) not tracing (Dask, "
          "transfers, the driver's checkpoint, a worker idle at the end)")
    print(f"- load average (1 min) before the run: {load_before:.2f}")
    for line in machine_lines(info):
        print(f"- {line}")


if __name__ == "__main__":
    main()
