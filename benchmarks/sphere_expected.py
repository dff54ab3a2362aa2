"""
The expected-value detector against counting (issue 40 item 6): rays and time to a certified reading.

The shipped 150 mm 8°/d sphere (``scenes/sphere_150mm_8d.xml``: SCI, substitution, grey
Lambertian ρ = 0.5, ρw = 0.98, baffle, 551 nm, δ = 0.01) read to ±TARGET absolute: for each
detector (``counted``: Clopper–Pearson on each detector fraction at δ/2; ``expected``: the
empirical Bernstein interval of each mean score at δ/2; both: the ratio's extreme
combinations), the smallest N per configuration on a ladder N_k = N₀·STEP^k whose certified
reading interval lies within ±TARGET of the reading. N₀ comes from a 200,000-ray pilot of that
detector (the half-width scaled by 1/√N, times 0.8), so both ladders start just below their
answer and climb by the same steps. Each rung is one ``vm.sphere_measure`` call (sample and
standard configurations), timed warm; the found N is then read again with other seeds, and
their half-widths are printed (the half-width at a fixed N is random).

Run: python benchmarks/sphere_expected.py [--target 0.005] [--step 1.1] [--seeds 1 2]
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

import virtspec_mi as vm

SCENE = "sphere_150mm_8d"


def half_width(result) -> float:
    """The largest distance from the reading to an end of its certified interval."""

    low, high = (float(v) for v in result.reading_interval.reshape(-1, 2)[0])
    reading = float(result.reading.reshape(-1)[0])
    return max(reading - low, high - reading)


def read(detector: str, rays: int, seed: int):
    """The reading, its wall seconds and its CPU seconds (every thread's: the busy machine's share aside)."""

    start, cpu = time.perf_counter(), time.process_time()
    result = vm.sphere_measure(SCENE, rays=rays, detector=detector, seed=seed)
    return result, (time.perf_counter() - start, time.process_time() - cpu)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--target", type=float, default=0.005)
    parser.add_argument("--step", type=float, default=1.1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--seeds", type=int, nargs="*", default=[1, 2])
    parser.add_argument("--pilot", type=int, default=200_000)
    args = parser.parse_args()
    lanes = 16 if "avx512f" in open("/proc/cpuinfo").read() else 8
    print(f"{SCENE}: certified SCI reading of a grey 0.5 Lambertian to +-{args.target} (delta 0.01); "
          f"{os.cpu_count()} cores, {platform.processor() or platform.machine()}, {lanes}-lane SIMD, "
          f"load {os.getloadavg()[0]:.2f}")
    found = {}
    for detector in ("counted", "expected"):
        read(detector, 20_000, args.seed)  # warm: the kernels compiled
        pilot, _ = read(detector, args.pilot, args.seed + 1000)
        rays = int(args.pilot * (half_width(pilot) / args.target) ** 2 * 0.8)
        while True:
            result, seconds = read(detector, rays, args.seed)
            width = half_width(result)
            print(f"  {detector:<8} N = {rays:>11,} per configuration: reading {float(result.reading[0]):.5f} "
                  f"+- {width:.5f}  ({seconds[0]:6.2f} s wall, {seconds[1]:6.2f} s CPU, load "
                  f"{os.getloadavg()[0]:.2f})")
            if width <= args.target:
                break
            rays = int(rays * args.step) + 1
        found[detector] = (rays, seconds, result)
        for seed in args.seeds:
            again, seconds_again = read(detector, rays, seed)
            print(f"  {detector:<8} same N, seed {seed}: reading {float(again.reading[0]):.5f} +- "
                  f"{half_width(again):.5f}  ({seconds_again[0]:6.2f} s wall, {seconds_again[1]:6.2f} s CPU)")
    (n_c, t_c, r_c), (n_e, t_e, r_e) = found["counted"], found["expected"]
    print(f"rays to +-{args.target}: counted {n_c:,}, expected {n_e:,} per configuration: {n_c / n_e:.1f}x fewer; "
          f"wall {t_c[0]:.2f} s vs {t_e[0]:.2f} s: {t_c[0] / t_e[0]:.1f}x less; CPU {t_c[1]:.2f} s vs {t_e[1]:.2f} s: "
          f"{t_c[1] / t_e[1]:.1f}x less")
    for name, result in (("counted", r_c), ("expected", r_e)):
        per_ray = result.seconds / (2 * int(np.max(result.rays)))
        print(f"  {name:<8} {per_ray * 1e9:7.1f} ns per ray and configuration; wall reflections per ray "
              f"{float(result.wall_reflections_per_ray[0]):.1f}")


if __name__ == "__main__":
    main()
