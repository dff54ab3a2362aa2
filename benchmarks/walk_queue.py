"""
Random walks at full SIMD occupancy: queued lanes against the one-loop walk (issue 14)
=====================================================================================

Three parts, printed as one report:

1. **Side by side** (``--against REV``, default ``b0f95e7``, the commit before the queued
   walks): the working tree and a throwaway checkout of REV each run in a worker process
   of their own (``PYTHONPATH`` set to the tree, checked with
   :func:`revisions.foreign_modules`), called alternately case by case, best wall time of
   ``--repeats`` each, with the CPU time (all threads) of that call — the robust figure on
   a shared machine — and whether the two trees gave identical counts (when a change alters
   the random stream, as issue 25's generator did, whether every R and T agrees within the
   sum of the two readings' certified tolerances, :func:`revisions.within_certificates`):

   - ``abm_b`` soybean, collimated, θi = 8°: 800 nm (the longest walks) and 551 nm,
     2·10⁶ rays each; the whole spectrum 400–2500 nm every 5 nm at the certified
     Hoeffding N (μ = 0.005, δ = 0.01), under ``two-stage`` and under ``exact``;
   - ``abm_u`` corn, the same spectrum at the Hoeffding N;
   - the MCML benchmark slab (``turbid_slab`` μa = 10, μs = 90, g = 0.75, d = 0.02),
     collimated and diffuse beams, 4·10⁶ rays.

   ``--case NAME`` (repeatable) runs only those cases.

2. **Occupancy** (working tree only, ``tally_readings`` with its ``walk_stats``): for a
   grid of :class:`~virtspec_mi.kernel.queue.WalkQueue` settings (lanes, queue, refill,
   prestart; the default's refill and prestart come from the specimen's declared mean walk
   length, :func:`~virtspec_mi.kernel.queue.walk_plan`) and chunk sizes, the CPU time and
   the share of lane-iterations that stepped no walk
   ("idle": a lane waiting for its refill, or past the end of its queue while its packet
   still runs), counted per SIMD packet of 16 lanes. ``lanes = 0`` is the one-loop walk
   (one ``sample()`` per ray), whose idle share is measured by queueing one ray per lane.

3. **Goniophotometer on walks** (working tree only): a reading binned in 36 × 36 (θo, φo)
   bins per hemisphere (``tally_readings`` with the bins' layout as its hook) against the plain reading, on the
   queued lanes and as the one-loop walk (CPU time best of 3, all threads), and whether
   the queued and one-loop bin tallies are identical.

Run::

    .venv/bin/python benchmarks/walk_queue.py                     # both parts, ~5 min
    .venv/bin/python benchmarks/walk_queue.py --quick             # 10x fewer rays
    .venv/bin/python benchmarks/walk_queue.py --skip-against      # occupancy grid and gonio only
    .venv/bin/python benchmarks/walk_queue.py --against main --skip-occupancy --skip-gonio --repeats 3

Needs the NPSG leaf data (``VIRTSPEC_LEAF_DATA``, default this checkout's shipped copy,
which older trees read too). Other work on the machine slows every figure; the load average is printed.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("VIRTSPEC_LEAF_DATA", str(ROOT / "virtspec_mi" / "data" / "abm-npsg"))  # older trees too
sys.path.insert(0, str(Path(__file__).resolve().parent))

from revisions import (Worker, describe_worktree, load_average, machine, machine_lines, serve,  # noqa: E402
                       within_certificates, worktree)

SLAB = {"type": "turbid_slab", "mu_a": 10.0, "mu_s": 90.0, "g": 0.75, "thickness": 0.02}
SOYBEAN = {"type": "abm_b"}
# name: (specimen, measure keywords, rays per reading (None: the bound's))
CASES: dict[str, tuple[dict, dict, int | None]] = {
    "abm_b 800 nm": (SOYBEAN, {"theta_i": 8, "beam": "collimated", "wavelengths": [800]}, 2_000_000),
    "abm_b 551 nm": (SOYBEAN, {"theta_i": 8, "beam": "collimated", "wavelengths": [551]}, 2_000_000),
    "abm_b spectrum, hoeffding": (SOYBEAN, {"theta_i": 8, "beam": "collimated", "wavelengths": "400:2500:5"}, None),
    "abm_b spectrum, two-stage": (SOYBEAN, {"theta_i": 8, "beam": "collimated", "wavelengths": "400:2500:5",
                                            "bound": "two-stage"}, None),
    "abm_b spectrum, exact": (SOYBEAN, {"theta_i": 8, "beam": "collimated", "wavelengths": "400:2500:5",
                                        "bound": "exact"}, None),
    "abm_u spectrum, hoeffding": ({"type": "abm_u"}, {"theta_i": 8, "beam": "collimated",
                                                      "wavelengths": "400:2500:5"}, None),
    "MCML slab, collimated": (SLAB, {"beam": "collimated"}, 4_000_000),
    "MCML slab, diffuse": (SLAB, {"beam": "diffuse"}, 4_000_000),
}
NPSG_FULL_SECONDS, NPSG_FULL_RAYS = 58.0, 100_000  # NPSG C++, 421 wavelengths, 2 threads (issue 4)


# --- worker: one tree, one process ---------------------------------------------------------


def worker(root: str) -> None:
    """Answer case requests (JSON lines on stdin) with timings and counts (:func:`revisions.serve`)."""

    import virtspec_mi as vm

    mi = vm.mitsuba()
    scenes = {}

    def answer(request: dict) -> dict:
        specimen, options, rays = CASES[request["case"]]
        key = json.dumps(specimen, sort_keys=True)
        if key not in scenes:
            scenes[key] = mi.load_dict(vm.instrument_scene(specimen))
        scale = request["scale"]
        extra = {} if rays is None else {"rays": max(1000, rays // scale)}
        if rays is None and scale > 1:
            extra = {"mu": 0.005 * np.sqrt(scale)}  # N ∝ 1/μ²: scale times fewer rays
        if request.get("warm"):  # the same call, 100x fewer rays: every kernel compiled
            small = {"rays": max(1000, rays // 100)} if rays else {"mu": 0.05}
            vm.measure(scenes[key], **options, **small)
            return {}
        start, start_cpu = time.perf_counter(), time.process_time()
        result = vm.measure(scenes[key], **options, **extra)
        wall, cpu = time.perf_counter() - start, time.process_time() - start_cpu
        flat = lambda values: np.asarray(values, dtype=np.float64).reshape(-1).tolist()  # noqa: E731
        mu = flat(result.certified_mu)
        return {"wall": wall, "cpu": cpu, "rays": int(np.sum(result.rays)),
                "counts": [np.asarray(result.reflected).tolist(), np.asarray(result.transmitted).tolist(),
                           np.asarray(result.capped).tolist()],
                "values": {"R": (flat(result.reflectance), mu), "T": (flat(result.transmittance), mu)}}

    serve(Path(root), answer)


# --- side by side ------------------------------------------------------------------------------


def against(revision: str, repeats: int, scale: int, cases: list[str]) -> tuple[list[list[str]], list[str]]:
    """Every case on both trees, alternately; rows of the table and notes."""

    rows, notes = [], []
    with worktree(revision) as old_root:
        script = Path(__file__).resolve()
        trees = {"before": Worker(revision, old_root, script), "after": Worker(describe_worktree(), ROOT, script)}
        for tree in trees.values():
            tree.start()
        try:
            for case in cases:
                for tree in trees.values():
                    tree.ask(case=case, scale=scale, warm=True)
                best = {name: None for name in trees}
                for _ in range(repeats):
                    for name, tree in trees.items():
                        answer = tree.ask(case=case, scale=scale)
                        if best[name] is None or answer["wall"] < best[name]["wall"]:
                            best[name] = answer
                before, after = best["before"], best["after"]
                inside, largest, allowance = within_certificates(before["values"], after["values"])
                same = "identical" if before["counts"] == after["counts"] else (
                    f"changed, within certificates (max |dR|, |dT| {largest:.4f} <= {allowance:.4f})" if inside
                    else f"OUTSIDE the certificates (max |dR|, |dT| {largest:.4f} > {allowance:.4f})")
                rows.append([case, f"{after['rays']:,}",
                             f"{before['wall']:.3f} / {after['wall']:.3f}",
                             f"{before['rays'] / before['wall'] / 1e6:.2f} / {after['rays'] / after['wall'] / 1e6:.2f}",
                             f"{before['wall'] / after['wall']:.2f}x",
                             f"{before['cpu']:.3f} / {after['cpu']:.3f}",
                             f"{before['cpu'] / after['cpu']:.2f}x", same])
                if "spectrum" in case:
                    npsg = NPSG_FULL_RAYS * 421 / NPSG_FULL_SECONDS
                    rate = after["rays"] / after["wall"]
                    threads = machine()["threads"]
                    notes.append(f"{case}: {after['wall']:.2f} s wall, {after['cpu'] / threads:.2f} s CPU per core "
                                 f"(projected wall on {threads} idle cores); {rate / 1e6:.2f} Mray/s = "
                                 f"{rate / npsg:.1f}x the NPSG C++ reference ({npsg / 1e6:.2f} Mray/s, 2 threads); "
                                 f"from CPU time {after['rays'] / (after['cpu'] / threads) / npsg:.1f}x")
        finally:
            for tree in trees.values():
                tree.close()
    return rows, notes


# --- occupancy of the queued lanes (working tree) --------------------------------------------


def occupancy(scale: int) -> list[list[str]]:
    """CPU time and idle share of lane-iterations for a grid of walk-queue settings."""

    import virtspec_mi as vm

    vm.mitsuba()
    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.kernel.tracer import ReadingPlan, WalkQueue, tally_readings
    from virtspec_mi.kernel.walk import walk_steps
    from virtspec_mi.runtime.scene import find_bench
    from virtspec_mi.settings import Settings

    workloads = {
        "abm_b 800 nm": (SOYBEAN, [(800.0, 8.0)], 2_000_000 // scale),
        "abm_b 400-2500/5 nm": (SOYBEAN, [(float(w), 8.0) for w in range(400, 2501, 5)], 20_000 // scale),
        "MCML slab": (SLAB, [(551.0, 0.0)], 4_000_000 // scale),
    }
    default = WalkQueue()
    grid = [(WalkQueue(lanes=0), 1 << 22), (default, 1 << 22),
            (WalkQueue(refill=1), 1 << 22), (WalkQueue(refill=2), 1 << 22), (WalkQueue(refill=4), 1 << 22),
            (WalkQueue(prestart=False), 1 << 22), (WalkQueue(prestart=True), 1 << 22),
            (WalkQueue(lanes=32), 1 << 22), (WalkQueue(lanes=1 << 15), 1 << 22),
            (WalkQueue(lanes=1 << 13, queue="group"), 1 << 22), (WalkQueue(lanes=1 << 16, queue="group"), 1 << 22),
            (WalkQueue(lanes=1 << 13, queue="stride"), 1 << 22), (WalkQueue(lanes=1 << 16, queue="stride"), 1 << 22),
            (default, 1 << 20), (default, 1 << 24)]
    rows = []
    for name, (specimen, readings, rays) in workloads.items():
        instrument = find_bench(vm.instrument_scene(specimen))
        plans = [ReadingPlan(w, t, 0.0, rays) for w, t in readings]
        settings = Settings(beam="collimated")
        base = None
        for queue, chunk in grid:
            run = lambda stats=None: tally_readings(  # noqa: E731
                instrument, plans, walk=queue, walk_stats=stats, **kernel_options(settings.updated(chunk_size=chunk)))
            tally_readings(instrument, plans[:1], walk=queue,
                           **kernel_options(settings.updated(chunk_size=1 << 12)))  # compile
            cpu = min(_cpu(run) for _ in range(3))
            stats: dict = {}
            if queue.lanes:
                run(stats)
            else:  # one ray per lane: the one-loop walk's packets
                tally_readings(instrument, plans, walk=WalkQueue(lanes=min(chunk, 1 << 24), queue="stride", refill=1),
                               walk_stats=stats, **kernel_options(settings.updated(chunk_size=chunk)))
            base = base or cpu
            total = rays * len(plans)
            planned = queue.planned(walk_steps(instrument.bsdf))  # refill and prestart as the kernel ran them
            rows.append([name, "one loop" if not queue.lanes else f"{queue.lanes}", queue.queue if queue.lanes else "-",
                         str(planned.refill) if queue.lanes else "-",
                         ("yes" if planned.prestart else "no") if queue.lanes else "-", f"{chunk:,}",
                         ("shared" if queue.queue == "counter" else f"{min(chunk, total) // queue.lanes:,}")
                         if queue.lanes else "1",
                         f"{cpu:.3f}", f"{total / cpu / 1e6:.2f}", f"{base / cpu:.2f}x", f"{_idle(stats):.3f}"])
    return rows


def gonio(scale: int) -> list[list[str]]:
    """Part 3: plain and goniophotometer readings of walk specimens, queued and one loop."""

    import virtspec_mi as vm

    vm.mitsuba()
    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.instruments.goniophotometer.bins import make_bins
    from virtspec_mi.kernel.tracer import ReadingPlan, WalkQueue, tally_readings
    from virtspec_mi.runtime.scene import find_bench
    from virtspec_mi.settings import Settings

    bins = make_bins(36, 36)
    workloads = {
        "abm_b 800 nm": (SOYBEAN, 800.0, 2_000_000 // scale),
        "abm_b 551 nm": (SOYBEAN, 551.0, 2_000_000 // scale),
        "MCML slab": (SLAB, 551.0, 4_000_000 // scale),
    }
    rows = []
    for name, (specimen, wavelength, rays) in workloads.items():
        instrument = find_bench(vm.instrument_scene(specimen))
        plans = [ReadingPlan(wavelength, 8.0, 0.0, rays)]
        settings = Settings(beam="collimated")
        walks = {"queued": WalkQueue(), "one loop": WalkQueue(lanes=0)}
        calls = {}
        for label, queue in walks.items():
            calls[f"plain, {label}"] = lambda queue=queue: tally_readings(instrument, plans, walk=queue,
                                                                          **kernel_options(settings))
            calls[f"gonio, {label}"] = lambda queue=queue: tally_readings(
                instrument, plans, hook=bins.layout(), walk=queue, **kernel_options(settings)).bins
        tallies = {label: call() for label, call in calls.items()}  # compile (and the bins to compare)
        cpu = {label: np.inf for label in calls}
        for _ in range(3):  # interleaved
            for label, call in calls.items():
                cpu[label] = min(cpu[label], _cpu(call))
        same = np.array_equal(tallies["gonio, queued"], tallies["gonio, one loop"])
        base = cpu["plain, queued"]
        rows += [[name, label, f"{cpu[label]:.3f}", f"{rays / cpu[label] / 1e6:.2f}", f"{base / cpu[label]:.2f}",
                  ("identical" if same else "DIFFERENT") if label.startswith("gonio") else "-"] for label in calls]
    return rows


def _cpu(call) -> float:
    start = time.process_time()
    call()
    return time.process_time() - start


def _idle(stats: dict, packet: int = 16) -> float:
    """Share of lane-iterations of every packet (``packet`` lanes) that stepped no walk."""

    used = busy = 0
    for iterations, stepped in zip(stats["iterations"], stats["busy"]):
        padded = np.concatenate([iterations, np.zeros((-len(iterations)) % packet, iterations.dtype)])
        used += int(padded.reshape(-1, packet).max(axis=1).sum()) * packet
        busy += int(stepped.sum())
    return 1.0 - busy / used


def table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--against", default="b0f95e7", metavar="REV", help="the revision to compare with")
    parser.add_argument("--repeats", type=int, default=2, help="calls per tree and case (best wall time)")
    parser.add_argument("--quick", action="store_true", help="10x fewer rays")
    parser.add_argument("--case", action="append", choices=list(CASES), help="a side-by-side case (repeatable; "
                                                                             "default all)")
    parser.add_argument("--skip-against", action="store_true", help="only the occupancy grid")
    parser.add_argument("--skip-occupancy", action="store_true", help="no occupancy grid")
    parser.add_argument("--skip-gonio", action="store_true", help="no goniophotometer readings")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(args.worker)
        return 0
    scale = 10 if args.quick else 1
    out, load = [], [load_average()]
    if not args.skip_against:
        rows, notes = against(args.against, args.repeats, scale, args.case or list(CASES))
        load.append(load_average())
        out += [f"Side by side: {args.against} (before) / {describe_worktree()} (after), best wall of {args.repeats}",
                "", table(["case", "rays", "wall s", "Mray/s", "speed-up (wall)", "CPU s", "speed-up (CPU)", "counts"],
                          rows), ""] + [f"- {note}" for note in notes] + [""]
    if not args.skip_occupancy:
        import virtspec_mi as vm

        vm.mitsuba()
        rows = occupancy(scale)
        load.append(load_average())
        out += ["Occupancy of the queued lanes (working tree; CPU time best of 3, all threads)", "",
                table(["workload", "lanes", "queue", "refill", "prestart", "chunk", "rays per lane", "CPU s",
                       "Mray/s (CPU)", "vs one loop", "idle"], rows), ""]
    if not args.skip_gonio:
        rows = gonio(scale)
        load.append(load_average())
        out += ["Goniophotometer on walks (working tree; 36 x 36 bins per hemisphere; CPU time best of 3, "
                "all threads)", "", table(["workload", "reading, walk", "CPU s", "Mray/s (CPU)",
                                           "vs plain queued", "bins queued vs one loop"], rows), ""]
    import virtspec_mi as vm

    vm.mitsuba()
    info = machine()
    info["load"] = " -> ".join(f"{value:.2f}" for value in load)
    print("\n".join(out + [f"- {line}" for line in machine_lines(info)]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
