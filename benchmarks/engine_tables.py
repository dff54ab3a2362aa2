"""
Each engine's table certified with its own model: time, rays, projection (issue 32)
===================================================================================

In one run, warm (small tables compile each channel's kernel first):

1. **Cycles' full GGX set** — E 32 × 32 + E_avg 32 of the height-correlated GGX
   (``engine_tables("cycles")``), ε = 10⁻³, δ = 0.01 jointly (target ≤ 60 s on 2 cores);
2. **Filament's DFG** — 128 × 128, DFG.x and DFG.y (counted on the same rays:
   ``fresnel="split"``), ε = 10⁻³, δ = 0.01 jointly (target ≤ 10 min): measured on a
   fraction — ``--rows`` of the 128 roughness rows (evenly spaced), each texel at the δ
   the full table would give it on average (δ × texels measured / 16,384) — and
   projected to the whole by its rays (the rate measured);
3. the **projection to ε = 10⁻⁴** on ``--workers`` 1-thread Dask workers
   (``benchmarks/albedo_table.py``'s method: second-stage rays from the certified values
   standing in for the pilots, at the per-core rate measured here);
4. **Cycles' published values** that we can quote (the μ = 1 row of ``table_ggx_E`` and
   ``table_ggx_Eavg``, Blender 5.1 ``intern/cycles/scene/shader.tables``) audited at
   ε = 10⁻³ against a certified table of their model.

Run::

    .venv/bin/python benchmarks/engine_tables.py               # all of it (a few minutes)
    .venv/bin/python benchmarks/engine_tables.py --quick       # epsilon 1e-2 (seconds)
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from albedo_table import _projection, _simd  # noqa: E402  (the same projection as the issue-24 figures)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--quick", action="store_true", help="epsilon 1e-2")
    parser.add_argument("--rows", type=int, default=4, help="Filament roughness rows measured (default 4 of 128)")
    parser.add_argument("--workers", type=int, default=100, help="workers of the projection (default 100)")
    args = parser.parse_args()

    import drjit as dr
    import mitsuba

    import virtspec_mi as vm
    from virtspec_mi.applications.tables.albedo import albedo_table
    from virtspec_mi.applications.tables.audit import audit
    from virtspec_mi.exchange.conventions import convention, cycles_roughness
    from virtspec_mi.applications.tables.engine_tables import engine_tables

    vm.mitsuba()
    print(f"# engine tables — {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC")
    print(f"# machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, {_simd()}; "
          f"Dr.Jit {dr.__version__} ({dr.thread_count()} threads), Mitsuba {mitsuba.__version__}; "
          f"load average {os.getloadavg()[0]:.2f}")
    for fresnel in ("one", "split"):  # compile the kernels
        albedo_table(engine=None, mu=[1.0, 0.5], alpha=[0.5], shadowing="height_correlated", fresnel=fresnel,
                     parts=fresnel == "split", epsilon=0.05, progress=False)
    epsilon = 1e-2 if args.quick else 1e-3

    start = time.perf_counter()
    cycles = engine_tables("cycles", epsilon=epsilon, delta=0.01, progress=False)
    wall = time.perf_counter() - start
    table = cycles.table
    rate = table.rays / table.provenance["seconds_traced"]
    print(f"\nCycles GGX E 32 x 32 + E_avg 32, height-correlated, epsilon = {epsilon:g}, delta = 0.01 jointly: "
          f"wall {wall:.1f} s (traced {table.provenance['seconds_traced']:.1f} s, {table.provenance['groups']} sweep "
          f"calls); rays {table.rays:,}; {rate / 1e6:.1f} Mray/s")
    calls = max(wall - table.provenance["seconds_traced"], 0.0) / max(table.provenance["groups"], 1)

    filament = convention("filament")
    rows = np.linspace(0, 127, args.rows).round().astype(int)
    fraction = len(rows) / 128
    start = time.perf_counter()
    parts = [albedo_table(engine=None, mu=filament.mu, alpha=filament.alpha[rows], shadowing="height_correlated",
                          fresnel="split", parts=True, epsilon=epsilon, delta=0.01 * fraction, average=False, seed=9,
                          progress=False)]  # DFG.x = E_R, DFG.y = E on the same rays
    part_wall = time.perf_counter() - start
    part_rays = sum(p.rays for p in parts)
    part_traced = sum(p.provenance["seconds_traced"] for p in parts)
    print(f"\nFilament DFG.x + DFG.y, {len(rows)} of 128 roughness rows (rows {rows.tolist()}), epsilon = {epsilon:g}, "
          f"delta per cell as in the full table: wall {part_wall:.1f} s (traced {part_traced:.1f} s); rays "
          f"{part_rays:,} ({part_rays / parts[0].E.size:,.0f} per texel, both channels); {part_rays / part_traced / 1e6:.1f} "
          f"Mray/s -> the whole 128 x 128 x 2: {part_rays / fraction:.3g} rays, {part_wall / fraction / 60:.1f} min "
          "projected (the rows are evenly spaced in roughness, so their mean cost stands for all rows)")

    target = epsilon / 10
    per_core = rate / (os.cpu_count() or 1)
    rays, seconds = _projection(table, target, per_core, args.workers, calls)
    print(f"\nprojection to epsilon = {target:g} on {args.workers} workers (1 thread each, {per_core / 1e6:.1f} Mray/s "
          f"per core): Cycles {rays:.3g} rays -> {seconds / 60:.1f} min", end="")
    filament_rays = sum(_projection(p, target, per_core, args.workers, calls)[0] for p in parts) / fraction
    print(f"; Filament {filament_rays:.3g} rays -> {filament_rays / (args.workers * per_core) / 60:.1f} min")

    mu1 = albedo_table(engine=None, mu=[1.0], roughness=cycles_roughness(32), shadowing="height_correlated",
                       epsilon=epsilon, seed=17, progress=False)
    from test_exchange_engine_models import CYCLES_GGX_E_MU1, CYCLES_GGX_EAVG

    mine_e, tol_e = mu1.E[0], mu1.certified_epsilon()[0]
    mine_a, tol_a = mu1.E_avg, mu1.certified_epsilon(average=True)
    out_e = np.abs(np.array(CYCLES_GGX_E_MU1) - mine_e) >= tol_e + 5e-7
    out_a = np.abs(np.array(CYCLES_GGX_EAVG) - mine_a) >= tol_a + 5e-7
    worst = max(np.max(np.abs(np.array(CYCLES_GGX_E_MU1) - mine_e)), np.max(np.abs(np.array(CYCLES_GGX_EAVG) - mine_a)))
    print(f"\nCycles' published mu = 1 row of table_ggx_E and table_ggx_Eavg (Blender 5.1 shader.tables), audited "
          f"at epsilon = {epsilon:g}: {int(out_e.sum())} of 32 E and {int(out_a.sum())} of 32 Eavg values outside the "
          f"certified interval; largest |published - certified| = {worst:.2e} ({worst / epsilon:.2f} epsilon)")
    assert audit  # the full-file audit needs Cycles' whole header: virtspec albedo-table --engine cycles --audit FILE


if __name__ == "__main__":
    main()
