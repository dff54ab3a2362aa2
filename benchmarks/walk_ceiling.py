"""
The queued walk against its ceiling: a bare kernel of the walk step (issue 25)
=============================================================================

The **ceiling** is one bare Dr.Jit kernel of the specimen's own ``walk_step`` — the same
traced arithmetic the instrument runs, nothing around it: L lanes step for I iterations in
one symbolic loop; a lane whose walk ended starts again at once from its lane's start
state (read from memory: a select per state variable), its random-number generator
running on. No incident rays, no queue, no refill branch, no tally: every lane steps a walk
at every iteration, so the kernel makes L·I events at full SIMD occupancy. The lanes take the
workload's wavelengths in contiguous blocks (as the queue hands out a reading's rays one
after another), θi and the beam as the workload's (collimated).

The **queued walk** is the instrument's reading of the same workload, ``virtspec_mi.measure``
(the ray kernel's queued lanes, their refills and the tally, plus everything around the
kernel); its events (lane-iterations that stepped a walk, lobe retries included) are
counted once with ``tally_readings(..., walk_stats=...)`` on the same rays (checked: the
same counts as the reading).

Both run in one process, alternately (queued, ceiling, queued, ceiling …), ``--rounds``
rounds; the best CPU time (all threads) and the best wall time of each give ns per event,
and the **ratio** ceiling / queued (events per second of the queued walk as a share of the
ceiling's) — by CPU time, the robust figure on a shared machine, and by wall time. The
SIMD width (8 lanes with AVX2, 16 with AVX-512), the machine, the date and the load
average are printed.

Workloads (``--case``, default all): the soybean spectrum (``abm_b``, 400–2500 nm every
5 nm, θi = 8°, collimated, 20,000 rays per wavelength), soybean at 800 nm (the longest
walks, 2·10⁶ rays), the corn spectrum (``abm_u``, as soybean) and the MCML slab
(``turbid_slab`` μa = 10, μs = 90, g = 0.75, d = 0.02, 551 nm, normal incidence,
4·10⁶ rays). ``--quick``: 10× fewer rays.

``--against REV`` runs the same in a worker process for a throwaway checkout of REV as well
(:class:`revisions.Worker`; the two trees alternate case by case), so both trees' ratios
come from one run. The ceiling restarts a lane from the start state of
``walk_start`` with the generator taken from the current state: it assumes the walk state
is a tuple whose first item is the generator, as every walk of the project keeps it.

Run::

    .venv/bin/python benchmarks/walk_ceiling.py                      # all cases, ~2 min
    .venv/bin/python benchmarks/walk_ceiling.py --case "abm_b spectrum" --rounds 7
    .venv/bin/python benchmarks/walk_ceiling.py --against main --quick
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("VIRTSPEC_LEAF_DATA", str(ROOT / "virtspec_mi" / "data" / "abm-npsg"))  # older trees too
sys.path.insert(0, str(Path(__file__).resolve().parent))

from revisions import (Worker, describe_worktree, find_bench, load_average, machine, machine_lines,  # noqa: E402
                       serve, simd, worktree)

SPECTRUM = np.arange(400, 2501, 5).tolist()
SLAB = {"type": "turbid_slab", "mu_a": 10.0, "mu_s": 90.0, "g": 0.75, "thickness": 0.02}
# name: (specimen, wavelengths, θi, rays per reading)
CASES: dict[str, tuple[dict, list[float], float, int]] = {
    "abm_b spectrum": ({"type": "abm_b"}, SPECTRUM, 8.0, 20_000),
    "abm_b 800 nm": ({"type": "abm_b"}, [800], 8.0, 2_000_000),
    "abm_u spectrum": ({"type": "abm_u"}, SPECTRUM, 8.0, 20_000),
    "MCML slab": (SLAB, [551], 0.0, 4_000_000),
}
CEILING_LANES = 1 << 16
ROW = ["tree", "case", "events per ray", "queued ns/event (CPU / wall)", "ceiling ns/event (CPU / wall)",
       "ceiling / queued (CPU)", "ceiling / queued (wall)", "queued Mray/s (wall)"]


# --- the two kernels (run in the tree under test) ---------------------------------------------


def ceiling(bsdf: Any, wavelengths: list[float], theta_i: float, lanes: int, iterations: int) -> int:
    """
    ``lanes`` × ``iterations`` steps of ``bsdf``'s walk in one bare kernel (see the module
    docstring); returns the number of walks that ended (so the work cannot be optimised away).
    """

    import drjit as dr
    import mitsuba as mi
    from virtspec_mi.kernel.rng import hash32, to_unit

    lane = dr.arange(mi.UInt32, lanes)
    blocks = np.repeat(np.asarray(wavelengths, dtype=np.float32), -(-lanes // len(wavelengths)))[:lanes]
    si = dr.zeros(mi.SurfaceInteraction3f, lanes)
    theta = np.radians(theta_i)
    si.wi = mi.Vector3f(float(np.sin(theta)), 0.0, float(np.cos(theta)))
    si.wavelengths = mi.Spectrum(mi.Float(blocks))
    sample1 = to_unit(hash32(lane ^ 0x6A09E667), mi.Float)
    sample2 = mi.Point2f(to_unit(hash32(lane ^ 0xBB67AE85), mi.Float), to_unit(hash32(lane ^ 0x3C6EF372), mi.Float))
    start = bsdf.walk_start(si, sample1, sample2, True)
    dr.eval(start)

    def body(state: tuple, ended: Any, i: Any) -> tuple:
        state = bsdf.walk_step(state)
        done = bsdf.walk_done(state)
        state = (state[0], *dr.select(done, start[1:], state[1:]))  # restart in place, generator running on
        return state, ended + dr.select(done, mi.UInt32(1), mi.UInt32(0)), i + 1

    total = dr.opaque(mi.UInt32, iterations)
    _, ended, _ = dr.while_loop((start, dr.zeros(mi.UInt32, lanes), mi.UInt32(0)),
                                lambda state, ended, i: i < total, body, label="walk_ceiling")
    return int(dr.sum(ended).numpy()[0])


def _tally(bench: Any, plans: list, walk_stats: dict) -> Any:
    """
    The counts of ``plans`` (collimated, the default settings otherwise) from the ray kernel
    with its ``walk_stats``, by the running tree's kernel interface: plain values since issue 21
    (``engine.plan.kernel_options``), a ``Settings`` before.
    """

    from virtspec_mi.kernel.tracer import WalkQueue, tally_readings
    from virtspec_mi.settings import Settings

    settings = Settings(beam="collimated")
    try:
        from virtspec_mi.engine.plan import kernel_options
    except ImportError:
        return tally_readings(bench, plans, settings, walk=WalkQueue(), walk_stats=walk_stats)
    return tally_readings(bench, plans, walk=WalkQueue(), walk_stats=walk_stats, **kernel_options(settings)).counts


def worker(root: str) -> None:
    """Answer requests (JSON lines): the events of a case, one queued reading or one ceiling run."""

    import virtspec_mi as vm

    mi = vm.mitsuba()
    from virtspec_mi.kernel.tracer import ReadingPlan

    scenes: dict[str, Any] = {}

    def answer(request: dict) -> dict:
        specimen, wavelengths, theta_i, rays = CASES[request["case"]]
        rays = max(1000, rays // request["scale"])
        name = request["case"]
        if name not in scenes:
            scenes[name] = mi.load_dict(vm.instrument_scene(specimen))
        scene = scenes[name]
        bsdf = find_bench(scene).bsdf
        if request["what"] == "events":  # the events of the reading, and whether tally_readings gave its rays
            plans = [ReadingPlan(float(w), theta_i, 0.0, rays) for w in wavelengths]
            stats: dict = {}
            counts = _tally(find_bench(scene), plans, stats)
            reading = vm.measure(scene, wavelengths=wavelengths, theta_i=theta_i, beam="collimated", rays=rays)
            same = np.array_equal(counts.reflected, reading.reflected)
            events = sum(int(np.sum(busy)) for busy in stats["busy"])
            ceiling(bsdf, wavelengths, theta_i, 1024, 8)  # compile
            return {"events": events, "rays": rays * len(wavelengths), "same": bool(same)}
        start, start_cpu = time.perf_counter(), time.process_time()
        if request["what"] == "queued":
            vm.measure(scene, wavelengths=wavelengths, theta_i=theta_i, beam="collimated", rays=rays)
        else:
            ceiling(bsdf, wavelengths, theta_i, CEILING_LANES, request["iterations"])
        return {"wall": time.perf_counter() - start, "cpu": time.process_time() - start_cpu}

    serve(Path(root), answer)


# --- the run ------------------------------------------------------------------------------------


def run(trees: dict[str, Worker], cases: list[str], rounds: int, scale: int) -> list[list[str]]:
    """Every case on every tree, alternately; one row of :data:`ROW` per (tree, case)."""

    rows = []
    for case in cases:
        info = {label: tree.ask(case=case, what="events", scale=scale) for label, tree in trees.items()}
        best: dict[tuple[str, str], dict] = {}
        for _ in range(rounds):
            for label, tree in trees.items():
                iterations = -(-info[label]["events"] // CEILING_LANES)  # about the queued walk's events
                for what in ("queued", "ceiling"):
                    answer = tree.ask(case=case, what=what, scale=scale, iterations=iterations)
                    key = (label, what)
                    previous = best.get(key, {"cpu": np.inf, "wall": np.inf})
                    best[key] = {kind: min(previous[kind], answer[kind]) for kind in ("cpu", "wall")}
        for label in trees:
            events, rays = info[label]["events"], info[label]["rays"]
            ceiling_events = -(-events // CEILING_LANES) * CEILING_LANES
            queued = {kind: best[label, "queued"][kind] * 1e9 / events for kind in ("cpu", "wall")}
            bare = {kind: best[label, "ceiling"][kind] * 1e9 / ceiling_events for kind in ("cpu", "wall")}
            note = "" if info[label]["same"] else " (tally_readings and measure gave different counts!)"
            rows.append([label, case + note, f"{events / rays:.2f}",
                         f"{queued['cpu']:.2f} / {queued['wall']:.2f}", f"{bare['cpu']:.2f} / {bare['wall']:.2f}",
                         f"{bare['cpu'] / queued['cpu']:.3f}", f"{bare['wall'] / queued['wall']:.3f}",
                         f"{rays / best[label, 'queued']['wall'] / 1e6:.2f}"])
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--case", action="append", choices=list(CASES), help="a workload (repeatable; default all)")
    parser.add_argument("--rounds", type=int, default=5, help="alternating rounds (best time of each kind)")
    parser.add_argument("--quick", action="store_true", help="10x fewer rays")
    parser.add_argument("--against", metavar="REV", help="also measure this git revision, side by side")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(args.worker)
        return 0
    cases, scale, script = args.case or list(CASES), 10 if args.quick else 1, Path(__file__).resolve()
    load = [load_average()]
    with worktree(args.against) if args.against else _nothing() as old_root:
        trees = {describe_worktree(): Worker(describe_worktree(), ROOT, script)}
        if old_root is not None:
            trees = {args.against: Worker(args.against, old_root, script), **trees}
        try:
            for tree in trees.values():
                tree.start()
            rows = run(trees, cases, args.rounds, scale)
        finally:
            for tree in trees.values():
                tree.close()
    load.append(load_average())
    import virtspec_mi as vm

    vm.mitsuba()
    info = machine()
    info["load"] = " -> ".join(f"{value:.2f}" for value in load)
    lanes = 16 if info["avx512"] else 8
    print(f"The queued walk against its ceiling (a bare kernel of its own step), {args.rounds} alternating rounds, "
          f"best CPU (all threads) and best wall time of each; {simd(info)}: {lanes}-lane SIMD packets")
    print()
    print("| " + " | ".join(ROW) + " |")
    print("|" + "---|" * len(ROW))
    print("\n".join("| " + " | ".join(row) + " |" for row in rows))
    print()
    print("\n".join(f"- {line}" for line in machine_lines(info)))
    return 0


class _nothing:
    """A context manager that gives ``None`` (no older revision)."""

    def __enter__(self) -> None:
        return None

    def __exit__(self, *_: Any) -> None:
        return None


if __name__ == "__main__":
    raise SystemExit(main())
