"""
Goniophotometer throughput and memory (issue 15)
================================================

Side by side in one run, the conical-hemispherical reading of the paper's diamond
(``scenes/diamond_conical.xml``: ``simple_dielectric``, η = 2.419, θi = 70°, 551 nm,
seed 0) at N rays:

1. **plain** — ``virtspec_mi.measure(scene, rays=N)``: the spectrophotometer reading;
2. **gonio** — ``virtspec_mi.gonio(scene, rays=N, theta_o_bins=T, phi_o_bins=P)``:
   the same rays, also binned into K = 2T × P bins (both hemispheres).

Both warm (one small call of each compiles its kernel first), alternated over
``--rounds`` rounds, best of each; their counts must be equal (same rays) and the
bins must add up to R + T exactly. The ratio gonio/plain rays per second is the
figure (target ≥ 0.5 at 10⁸ rays and ≥ 1,000 bins). Then a 10⁹-ray goniophotometer
reading in a fresh subprocess reports its peak memory (max RSS) and time.

Run::

    .venv/bin/python benchmarks/gonio.py                 # 10^8 rays, 18 x 36 per hemisphere (1296 bins)
    .venv/bin/python benchmarks/gonio.py --rays 1e7 --no-billion   # quick
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "diamond_conical.xml"


def _billion(rays: int, theta_bins: int, phi_bins: int) -> None:
    """One goniophotometer reading in this (fresh) process; prints seconds and max RSS."""

    import virtspec_mi as vm

    start = time.perf_counter()
    reading = vm.gonio(str(SCENE), rays=rays, theta_o_bins=theta_bins, phi_o_bins=phi_bins)
    seconds = time.perf_counter() - start
    assert int(reading.bin_counts.sum()) == int(reading.result.reflected.sum() + reading.result.transmitted.sum())
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"BILLION {seconds:.2f} {peak:.0f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--rays", type=float, default=1e8)
    parser.add_argument("--theta-o-bins", type=int, default=18, help="per hemisphere")
    parser.add_argument("--phi-o-bins", type=int, default=36)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--no-billion", action="store_true")
    parser.add_argument("--billion-child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    rays = int(args.rays)
    if args.billion_child:
        _billion(rays, args.theta_o_bins, args.phi_o_bins)
        return

    import virtspec_mi as vm

    bins = dict(theta_o_bins=args.theta_o_bins, phi_o_bins=args.phi_o_bins)
    vm.measure(str(SCENE), rays=10_000)
    vm.gonio(str(SCENE), rays=10_000, **bins)
    plain_best = gonio_best = float("inf")
    for _ in range(args.rounds):
        start = time.perf_counter()
        plain = vm.measure(str(SCENE), rays=rays)
        plain_best = min(plain_best, time.perf_counter() - start)
        start = time.perf_counter()
        gonio = vm.gonio(str(SCENE), rays=rays, **bins)
        gonio_best = min(gonio_best, time.perf_counter() - start)
    assert np.array_equal(plain.reflected, gonio.result.reflected[:, 0])
    assert np.array_equal(plain.transmitted, gonio.result.transmitted[:, 0])
    assert int(gonio.bin_counts.sum()) == int(plain.reflected.sum() + plain.transmitted.sum())
    load = os.getloadavg()[0]
    print(f"diamond conical, theta_i = 70, N = {rays:.3g} rays, K = {gonio.size} bins "
          f"({2 * args.theta_o_bins} theta_o x {args.phi_o_bins} phi_o), best of {args.rounds}, "
          f"load average {load:.2f}")
    print(f"{'reading':>10} {'seconds':>9} {'Mray/s':>8}")
    print(f"{'plain':>10} {plain_best:>9.3f} {rays / plain_best / 1e6:>8.1f}")
    print(f"{'gonio':>10} {gonio_best:>9.3f} {rays / gonio_best / 1e6:>8.1f}")
    print(f"ratio gonio/plain rays/s: {plain_best / gonio_best:.3f} (target >= 0.5)")
    if not args.no_billion:
        out = subprocess.run([sys.executable, __file__, "--billion-child", "--rays", "1e9",
                              "--theta-o-bins", str(args.theta_o_bins), "--phi-o-bins", str(args.phi_o_bins)],
                             capture_output=True, text=True, check=True)
        line = [x for x in out.stdout.splitlines() if x.startswith("BILLION")][-1].split()
        print(f"10^9-ray goniophotometer reading (fresh process): {float(line[1]):.1f} s, "
              f"peak memory (max RSS) {float(line[2]):.0f} MiB")


if __name__ == "__main__":
    main()
