"""
The double sphere's speed (issue 40 item 1): a certified leaf spectrum read by the double
sphere against the same spectrum read by single spheres.

The shipped ``double_sphere_leaf`` scene (the soybean ABM-B leaf between two 30 mm spheres),
400–2500 nm every 5 nm (421 wavelengths), certified at (μ, δ):

- **double**: one readout, three configurations (leaf, standard, empty position) sharing
  their rays, each of the four detector fractions within μ at δ/4 (R and T at once);
- **single, same spheres**: the reflectance sphere alone (reflectance reading) and the
  transmittance sphere alone (transmittance reading): two readouts of two configurations,
  each fraction within μ at δ/2 (R and T each at δ: the single sphere's certificate);
- **single, 60 mm leaf sphere**: the shipped ``sphere_leaf_60mm`` read twice (reflectance,
  transmittance), for scale.

Warm (one untimed run each first), best of K, interleaved so the busy machine's drift
falls on all alike. The issue's target: the double sphere's certified spectrum in no more
than 2× the single sphere's time (R and T).

Run: python benchmarks/double_sphere.py [--repeat K] [--mu MU] [--delta DELTA] [--step NM]
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import virtspec_mi as vm


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--mu", type=float, default=0.02)
    parser.add_argument("--delta", type=float, default=0.01)
    parser.add_argument("--step", type=int, default=5, help="wavelength step, nm (421 wavelengths at 5)")
    args = parser.parse_args()
    wavelengths = f"400:2500:{args.step}"
    common = {"wavelengths": wavelengths, "mu": args.mu, "delta": args.delta, "seed": 1}
    double_options = vm.load_scene("double_sphere_leaf").integrator().instrument_options
    (single_r, single_t) = double_options.single()

    def double():
        return [vm.double_sphere("double_sphere_leaf", **common)]

    def single_same():
        return [vm.sphere_measure("double_sphere_leaf", **common, **single_r),
                vm.sphere_measure("double_sphere_leaf", **common, **single_t)]

    def single_60mm():
        return [vm.sphere_measure("sphere_leaf_60mm", **common),
                vm.sphere_measure("sphere_leaf_60mm", **common, measurement="transmittance", theta_i=0)]

    runs = {"double (R and T at once)": double, "single, same spheres (R, then T)": single_same,
            "single, 60 mm leaf sphere (R, then T)": single_60mm}
    best = {name: float("inf") for name in runs}
    rays = {}
    for name, run in runs.items():  # warm
        results = run()
        rays[name] = sum(int(r.rays.sum()) for r in results)
    for _ in range(args.repeat):
        for name, run in runs.items():
            start = time.perf_counter()
            run()
            best[name] = min(best[name], time.perf_counter() - start)
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}; "
          f"{wavelengths} nm, mu = {args.mu}, delta = {args.delta}, best of {args.repeat} warm")
    base = best["single, same spheres (R, then T)"]
    for name in runs:
        print(f"  {name:40s} {best[name]:8.2f} s   x {best[name] / base:4.2f}   {rays[name]:,} rays")


if __name__ == "__main__":
    main()
