"""
Throughput of the turbid slab walk (issue 6)
============================================

The MCML benchmark slab (μa = 10 cm⁻¹, μs = 90 cm⁻¹, g = 0.75, d = 0.02 cm, n = 1;
albedo 0.9, optical thickness 2; collimated normal incidence) measured two ways,
side by side in one run:

1. **Mitsuba** — ``virtspec_mi.measure`` of ``turbid_slab`` in the instrument: the
   fused integrator kernel running the plugin's walk (its steps on queued SIMD lanes,
   ``virtspec_mi.kernel.queue.WalkQueue``). Warm (a small call compiles the kernel first); best of 3.
2. **NumPy** — :func:`virtspec_mi.references.slab.walk_slab`, the same analog walk in
   float64 NumPy, vectorised over rays (compacting the live photons every step).

Each method's reflectance and transmittance are printed with their agreement
(difference in combined standard deviations) and the published values
(Rd = 0.09739, Tt = 0.66096, van de Hulst 1980). A diffuse-beam reading of the
same slab is timed too. The 1-minute load average is printed: the machine may be
shared, which slows every figure.

Run::

    .venv/bin/python benchmarks/turbid_slab.py            # 10⁷ rays Mitsuba, 10⁶ NumPy
    .venv/bin/python benchmarks/turbid_slab.py --quick    # 10⁶ / 2·10⁵
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import time


SLAB = {"type": "turbid_slab", "mu_a": 10.0, "mu_s": 90.0, "g": 0.75, "thickness": 0.02}
RD, TT = 0.09739, 0.66096


def mitsuba_rows(rays: int, repeats: int) -> list[tuple]:
    import virtspec_mi as vm

    vm.mitsuba()
    scene = vm.mitsuba().load_dict(vm.instrument_scene(SLAB))
    rows = []
    for beam in ("collimated", "diffuse"):
        vm.measure(scene, beam=beam, rays=10_000)  # compile
        best = None
        for _ in range(repeats):
            reading = vm.measure(scene, beam=beam, rays=rays)
            best = reading if best is None or reading.seconds < best.seconds else best
        rows.append((f"Mitsuba ({beam})", rays, best.seconds, best.reflectance[0], best.transmittance[0]))
    return rows


def numpy_row(rays: int) -> tuple:
    from virtspec_mi.references.slab import walk_slab

    start = time.perf_counter()
    counts = walk_slab(rays, 10.0, 90.0, 0.75, 0.02, seed=0)
    seconds = time.perf_counter() - start
    return ("NumPy float64 (collimated)", rays, seconds, counts.reflectance, counts.transmittance)


def _cpu() -> str:
    try:
        with open("/proc/cpuinfo") as info:
            return next(line.split(":", 1)[1].strip() for line in info if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--quick", action="store_true", help="10^6 Mitsuba / 2*10^5 NumPy rays")
    args = parser.parse_args()
    mitsuba_rays, numpy_rays = (10**6, 2 * 10**5) if args.quick else (10**7, 10**6)
    load_before = os.getloadavg()[0]
    started = datetime.datetime.now(datetime.timezone.utc)
    rows = mitsuba_rows(mitsuba_rays, 3)
    rows.append(numpy_row(numpy_rays))
    load_after = os.getloadavg()[0]

    print("| method | rays | seconds | Mray/s | R | T |")
    print("|---|---|---|---|---|---|")
    for name, rays, seconds, r, t in rows:
        print(f"| {name} | {rays:.0e} | {seconds:.3f} | {rays / seconds / 1e6:.2f} | {r:.5f} | {t:.5f} |")
    (_, n_m, s_m, r_m, t_m), (_, n_n, s_n, r_n, t_n) = rows[0], rows[2]
    print()
    print(f"- ratio Mitsuba / NumPy (rays/s, collimated): {(n_m / s_m) / (n_n / s_n):.1f}")
    for name, a, b in (("R", r_m, r_n), ("T", t_m, t_n)):
        sigma = math.sqrt(a * (1 - a) / n_m + b * (1 - b) / n_n)
        print(f"- {name} Mitsuba - NumPy: {a - b:+.2e} ({abs(a - b) / sigma:.1f} combined sigma)")
    for name, a, ref in (("R (= Rd, n = 1)", r_m, RD), ("T (Tt)", t_m, TT)):
        sigma = math.sqrt(ref * (1 - ref) / n_m)
        print(f"- {name} Mitsuba - van de Hulst {ref}: {a - ref:+.2e} ({abs(a - ref) / sigma:.1f} sigma)")
    print(f"- date: {started:%Y-%m-%d %H:%M} UTC; machine: {_cpu()}, "
          f"{os.cpu_count()} cores; load average (1 min) {load_before:.2f} before, {load_after:.2f} after")


if __name__ == "__main__":
    main()
