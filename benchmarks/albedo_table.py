"""
Certified albedo tables and Klems files: time, rays, and a projection (issue 24)
================================================================================

In one run, warm (a small table compiles the kernels first), on this machine:

1. **GGX E table**, Cycles' 32 × 32 grid (+ E_avg 32) of Mitsuba's ``roughconductor``
   (Fresnel = 1), ε = 10⁻³, δ = 0.01 jointly over all 1,056 values, ``two-stage``
   (target ≤ 60 s on 2 cores); its rays beside the fixed Hoeffding budget of the same
   certificate (the union N for every cell), and the ray rate;
2. **glass table** (``--glass``), Cycles' 16 × 16 × 16 grid of ``roughdielectric``,
   outside and inside, + E_avg (8,704 values), ε = 10⁻³ (target ≤ 10 min);
3. **projection** for ε = 10⁻⁴: the second-stage rays each measured table would need,
   from its own certified values standing in for the pilots (a pilot of 4·10⁵ rays per
   cell, its Clopper–Pearson interval at the measured value), divided by 100 workers at
   the ray rate measured here per core (the 2-core rate / 2: every worker a 1-thread
   process), plus the groups' call overhead spread over the workers;
4. **Klems** full basis (145 × 145, front and back) of a rough glass at ε = 0.01 per
   patch fraction.

SIMD width: Dr.Jit's LLVM backend uses the widest vector unit the CPU has; the script
prints whether the CPU has AVX-512 (16 lanes) or AVX2 only (8 lanes).

Run::

    .venv/bin/python benchmarks/albedo_table.py            # GGX table + projection + Klems
    .venv/bin/python benchmarks/albedo_table.py --glass    # … and the 16^3 glass table (minutes)
    .venv/bin/python benchmarks/albedo_table.py --quick    # a 8 x 8 table at 1e-2 (seconds)
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import time

import numpy as np


def _simd() -> str:
    try:
        flags = open("/proc/cpuinfo").read()
    except OSError:
        return "unknown SIMD"
    if " avx512f" in flags:
        return "AVX-512 (16-lane packets)"
    if " avx2" in flags:
        return "AVX2 only (8-lane packets)"
    return "no AVX2"


def _projection(table, epsilon: float, rate_per_core: float, workers: int, call_seconds: float) -> tuple:
    """Second-stage rays at ``epsilon`` from the table's values (see the module docstring) and the time on workers."""

    from virtspec_mi.budgets.binomial import binomial_rays, pilot_intervals, stage_two_shares

    values = [table.E.ravel()] + ([] if table.E_avg is None else [table.E_avg.ravel()])
    cells = sum(v.size for v in values)
    pilot = int(np.ceil(40.0 / epsilon))
    intervals = {str(k): [pilot_intervals(np.rint(v * pilot), pilot, table.delta / 10 / cells)]
                 for k, v in enumerate(values)}
    shares = stage_two_shares(intervals, 0.9 * table.delta)
    rays = sum(float(binomial_rays(*intervals[k][0], epsilon, shares[k]).sum()) for k in intervals)
    rays += pilot * cells
    groups = int(table.provenance.get("groups", 0))
    seconds = rays / (workers * rate_per_core) + groups * call_seconds / workers
    return rays, seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--glass", action="store_true", help="also the 16 x 16 x 16 glass table (minutes)")
    parser.add_argument("--quick", action="store_true", help="small grids at epsilon 0.01 (a smoke run)")
    parser.add_argument("--workers", type=int, default=100, help="workers of the projection (default 100)")
    args = parser.parse_args()

    import drjit as dr
    import mitsuba

    import virtspec_mi as vm
    from virtspec_mi.applications.tables.albedo import albedo_table
    from virtspec_mi.applications.klems.measure import klems_measure
    from virtspec_mi.budgets.binomial import union_hoeffding_rays

    vm.mitsuba()
    print(f"# albedo tables and Klems files — {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC")
    print(f"# machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, {_simd()}; "
          f"Dr.Jit {dr.__version__} ({dr.thread_count()} threads), Mitsuba {mitsuba.__version__}; "
          f"load average {os.getloadavg()[0]:.2f}")
    albedo_table(engine=None, mu=[1.0, 0.5], alpha=[0.5], epsilon=0.05, progress=False)  # compile the kernels
    albedo_table("glass", engine=None, mu=[1.0, 0.5], alpha=[0.5], eta=[1.5], epsilon=0.05, progress=False)

    epsilon = 1e-2 if args.quick else 1e-3
    grid = dict(engine=None, mu=np.linspace(1e-4, 1, 8), roughness=np.linspace(1e-4, 1, 8)) if args.quick else {}
    start = time.perf_counter()
    ggx = albedo_table("conductor", epsilon=epsilon, delta=0.01, progress=False, **grid)
    wall = time.perf_counter() - start
    hoeffding = union_hoeffding_rays(epsilon, 0.01, ggx.cells) * ggx.cells
    rate = ggx.rays / ggx.provenance["seconds_traced"]
    print(f"\nGGX E {ggx.E.shape[0]} x {ggx.E.shape[1]} + E_avg {ggx.E_avg.size} ({ggx.engine} grid), epsilon = {epsilon:g}, "
          f"delta = 0.01 joint, two-stage: wall {wall:.1f} s (traced {ggx.provenance['seconds_traced']:.1f} s, "
          f"{ggx.provenance['groups']} sweep calls); rays {ggx.rays:,} = {ggx.rays / hoeffding:.3f} x the "
          f"Hoeffding budget ({hoeffding:,}); {rate / 1e6:.1f} Mray/s; {ggx.statement()}")
    calls = max(wall - ggx.provenance["seconds_traced"], 0.0) / max(ggx.provenance["groups"], 1)
    tables = [("GGX", ggx, rate)]

    if args.glass:
        glass_grid = dict(engine=None, mu=np.linspace(1e-4, 1, 6), alpha=np.linspace(0.01, 1, 6),
                          eta=[1.0, 1.5, 3.0]) if args.quick else {}
        start = time.perf_counter()
        glass = albedo_table("glass", epsilon=epsilon, delta=0.01, progress=False, **glass_grid)
        wall_glass = time.perf_counter() - start
        rate_glass = glass.rays / glass.provenance["seconds_traced"]
        uncertified = int(np.isnan(glass.certified_epsilon()).sum() + np.isnan(glass.certified_epsilon(True)).sum())
        print(f"\nglass E {' x '.join(map(str, glass.E.shape))} + E_avg {glass.E_avg.size}, epsilon = {epsilon:g}, "
              f"delta = 0.01 joint: wall {wall_glass:.1f} s (traced {glass.provenance['seconds_traced']:.1f} s, "
              f"{glass.provenance['groups']} sweep calls); rays {glass.rays:,}; {rate_glass / 1e6:.1f} Mray/s; "
              f"{uncertified} of {glass.cells} values not certified (invalid directions from the BSDF)")
        tables.append(("glass", glass, rate_glass))

    target = epsilon / 10
    print(f"\nprojection to epsilon = {target:g} on {args.workers} workers (1 thread each, the rate per core "
          "measured here, perfect scaling of the traced rays; the sweep calls' overhead spread over the workers):")
    for name, table, table_rate in tables:
        rays, seconds = _projection(table, target, table_rate / (os.cpu_count() or 1), args.workers, calls)
        print(f"  {name}: {rays:.3g} rays ({rays / table.rays:.0f} x this run) -> {seconds / 60:.1f} min")

    if not args.quick:
        glass_bsdf = {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.2, "int_ior": 1.5, "ext_ior": 1.0}
        start = time.perf_counter()
        klems = klems_measure(vm.instrument_scene(glass_bsdf), basis="full", epsilon=0.01)
        seconds = time.perf_counter() - start
        print(f"\nKlems full basis, front + back, rough glass (alpha 0.2, eta 1.5), epsilon = 0.01 per patch fraction: "
              f"{seconds:.1f} s, {int(klems.rays.sum()):,} rays ({int(klems.rays.ravel()[0]):,} per incidence, "
              f"{klems.rays.size} incidences)")


if __name__ == "__main__":
    main()
