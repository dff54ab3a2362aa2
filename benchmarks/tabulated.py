"""
Throughput of the ``tabulated`` BSDF (issue 15)
===============================================

A conical reading (θi = 45°, 551 nm) of a ``tabulated`` BSDF measured side by side, in
one run, with the same reading of Mitsuba's ``diffuse`` (the cheapest specimen) and of
``roughconductor``, each warm (a small call compiles the kernel first), best of 3:
the table's cost is the binary searches (θi, λ, the bin CDF) and gathers of
``sample``. Tables: a sheen lobe + diffuse R/T (``analytic_tables.phong_model``) over
4 wavelengths × 4 θi × (2 × ``n``) θo bins × 4n φo bins, for n = 9 (648 bins) and
n = 18 (2,592 bins). Ratios to ``diffuse`` are printed; the 1-minute load average too
(the machine may be shared, which slows every figure).

Run::

    .venv/bin/python benchmarks/tabulated.py            # 10⁷ rays per reading
    .venv/bin/python benchmarks/tabulated.py --quick    # 10⁶
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import time

import virtspec_mi as vm
from virtspec_mi.references.analytic_tables import equal_projected_edges, phong_model, quadrature_table, uniform_edges


def rays_per_second(scene: dict, rays: int) -> tuple[float, float]:
    """Best-of-3 rays/s of a warm conical reading, and its reflectance."""

    vm.measure(scene, theta_i=45, rays=10**4, wavelengths=551)
    best, reading = float("inf"), None
    for _ in range(3):
        start = time.perf_counter()
        reading = vm.measure(scene, theta_i=45, rays=rays, wavelengths=551)
        best = min(best, time.perf_counter() - start)
    return rays / best, float(reading.reflectance[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--quick", action="store_true", help="10^6 rays instead of 10^7")
    args = parser.parse_args()
    rays = 10**6 if args.quick else 10**7
    print(f"{datetime.date.today()} {platform.processor() or platform.machine()}, "
          f"load average {os.getloadavg()[0]:.2f}; {rays:,} rays per reading, conical, theta_i = 45")
    scenes = {"diffuse": vm.instrument_scene({"type": "diffuse"}),
              "roughconductor (GGX)": vm.instrument_scene({"type": "roughconductor", "distribution": "ggx"})}
    model = phong_model(specular=0.2, exponent=20, diffuse=0.3, diffuse_transmission=0.2)
    for n in (9, 18):
        table = quadrature_table(model, wavelength=[450, 550, 650, 800], theta_i=[0, 30, 60, 80],
                                 theta_o_edges=equal_projected_edges(n), phi_o_edges=uniform_edges(0, 360, 4 * n))
        bins = table.shape[2] * table.shape[3]
        scenes[f"tabulated, {bins:,} bins"] = vm.instrument_scene(vm.tabulated_bsdf(table))
    results = {name: rays_per_second(scene, rays) for name, scene in scenes.items()}
    base = results["diffuse"][0]
    print("| specimen | Mray/s | / diffuse | R |")
    print("|---|---|---|---|")
    for name, (rate, reflectance) in results.items():
        print(f"| {name} | {rate / 1e6:.1f} | {rate / base:.2f} | {reflectance:.4f} |")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
