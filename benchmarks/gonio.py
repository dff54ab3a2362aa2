"""
Goniophotometer throughput and memory (issue 15)
================================================

Side by side in one run, the conical-hemispherical reading of the paper's diamond
(``scenes/diamond_conical.xml``: ``simple_dielectric``, η = 2.419, θi = 70°, 551 nm,
seed 0) at N rays:

1. **plain** — ``virtspec_mi.measure(scene, rays=N)``: the spectrophotometer reading;
2. **gonio** — ``virtspec_mi.gonio(scene, rays=N, theta_o_bins=T, phi_o_bins=P)``:
   the same rays, also binned into K = 2T × P bins (both hemispheres), with the
   ``uniform`` binning and with the ``projected`` one (equal projected solid angle).
   The cost of the tally depends on how many distinct bins the 16 rays of a SIMD packet
   fall into: the narrow lobes of the diamond spread over more uniform bins than
   projected ones near grazing.

Both warm (one small call of each compiles its kernel first), alternated over
``--rounds`` rounds, best of each; their counts must be equal (same rays) and the
bins must add up to R + T exactly. The ratio gonio/plain rays per second is the
figure (target ≥ 0.6 at ≥ 1,000 bins, issue 21; the median of the per-round ratios is
printed beside the ratio of the best times). Then a 10⁹-ray goniophotometer
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
    binnings = ("uniform", "projected")
    vm.measure(str(SCENE), rays=10_000)
    for binning in binnings:
        vm.gonio(str(SCENE), rays=10_000, binning=binning, **bins)
    load = os.getloadavg()[0]
    best = {name: float("inf") for name in ("plain", *binnings)}
    ratios: dict[str, list[float]] = {name: [] for name in binnings}  # per round: plain seconds / gonio seconds
    for _ in range(args.rounds):
        start = time.perf_counter()
        plain = vm.measure(str(SCENE), rays=rays)
        plain_seconds = time.perf_counter() - start
        best["plain"] = min(best["plain"], plain_seconds)
        for binning in binnings:
            start = time.perf_counter()
            gonio = vm.gonio(str(SCENE), rays=rays, binning=binning, **bins)
            seconds = time.perf_counter() - start
            best[binning] = min(best[binning], seconds)
            ratios[binning].append(plain_seconds / seconds)
            assert np.array_equal(plain.reflected, gonio.result.reflected[:, 0])
            assert np.array_equal(plain.transmitted, gonio.result.transmitted[:, 0])
            assert int(gonio.bin_counts.sum()) == int(plain.reflected.sum() + plain.transmitted.sum())
    print(f"diamond conical, theta_i = 70, N = {rays:.3g} rays, K = {gonio.size} bins "
          f"({2 * args.theta_o_bins} theta_o x {args.phi_o_bins} phi_o), best of {args.rounds}, "
          f"load average {load:.2f} before, {os.getloadavg()[0]:.2f} after")
    print(f"{'reading':>16} {'seconds':>9} {'Mray/s':>8} {'ratio':>7} {'median':>7}")
    for name, seconds in best.items():
        label = name if name == "plain" else f"gonio {name}"
        median = "" if name == "plain" else f"{float(np.median(ratios[name])):>7.3f}"
        print(f"{label:>16} {seconds:>9.3f} {rays / seconds / 1e6:>8.1f} {best['plain'] / seconds:>7.3f} {median}")
    print("ratio: rays/s of the reading / rays/s of the plain reading, of the best times; median: of the per-round "
          "ratios (each round times both back to back: steadier on a shared machine); target >= 0.6")
    if not args.no_billion:
        out = subprocess.run([sys.executable, __file__, "--billion-child", "--rays", "1e9",
                              "--theta-o-bins", str(args.theta_o_bins), "--phi-o-bins", str(args.phi_o_bins)],
                             capture_output=True, text=True, check=True)
        line = [x for x in out.stdout.splitlines() if x.startswith("BILLION")][-1].split()
        print(f"10^9-ray goniophotometer reading (fresh process): {float(line[1]):.1f} s, "
              f"peak memory (max RSS) {float(line[2]):.0f} MiB")


if __name__ == "__main__":
    main()
