"""
Real spheres' speed (issue 40): each real feature's readout against the plain sphere's, in
one run, interleaved.

The 150 mm 8°/d sphere of ``scenes/sphere_150mm_8d.xml`` (SCI, grey Lambertian ρ = 0.5,
ρw = 0.98, 105,967 rays per configuration, 551 nm): the whole certified readout (sample and
standard configurations) of the plain sphere, then of the same sphere with one feature
each — a 3 mm black detector tube, a holder mask, a 40° detector field of view, an
elliptical detector port, a 10 % mirror share of the wall, a traced 20 × 8 mm beam with 1°
divergence, a wall BSDF (a rough specular lobe blended with a Lambertian base) — and with
all of them (but the wall BSDF); then the error budget of the all-features sphere (its
nine readings). Warm (one untimed run each first), best of K, the configurations
interleaved so the busy machine's drift falls on all alike; ratio: time over the plain
sphere's in the same round.

Run: python benchmarks/sphere_real.py [--repeat K] [--rays N]
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from dataclasses import replace

import virtspec_mi as vm

SCENE = "scenes/sphere_150mm_8d.xml"


def variants(plain):
    def ports(role, **change):
        return tuple(replace(p, **change) if p.role == role else p for p in plain.ports)

    tube = ports("detector", depth=3.0, edge_reflectance=0.0)
    out = {
        "plain": plain,
        "port wall (3 mm black detector tube)": replace(plain, ports=tube),
        "holder mask (aperture 9 mm)": replace(plain, ports=ports("sample", aperture=9.0, mask_reflectance=0.05)),
        "detector field of view 40 deg": replace(plain, ports=ports("detector", field_of_view=40.0)),
        "elliptical detector 14 x 10 mm": replace(plain, ports=ports("detector", radius=None, shape="ellipse",
                                                                     width=14.0, height=10.0)),
        "wall mirror share 0.1": replace(plain, wall_specular=0.1),
        "wall BSDF (PTFE-like blend)": replace(plain, wall_bsdf={
            "type": "blendbsdf", "weight": 0.2, "lambert": {"type": "diffuse", "reflectance": 0.98},
            "lobe": {"type": "roughconductor", "alpha": 0.3, "material": "none", "specular_reflectance": 0.98}}),
        "traced beam 20 x 8 mm, 1 deg": replace(plain, beam_profile="shape=rectangle width=20 height=8 divergence=1"),
    }
    every = tuple(replace(p, depth=3.0, edge_reflectance=0.0, field_of_view=40.0) if p.role == "detector" else
                  replace(p, aperture=9.0, mask_reflectance=0.05) if p.role == "sample" else p for p in plain.ports)
    out["all of them"] = replace(plain, ports=every, wall_specular=0.1,
                                 beam_profile="shape=rectangle width=20 height=8 divergence=1")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--rays", type=int, default=105_967)
    args = parser.parse_args()
    settings = {"rays": args.rays, "wavelengths": "551", "seed": 0}
    plain = vm.load_scene(SCENE).integrator().sphere_options.sphere
    spheres = variants(plain)
    results = {name: vm.sphere_measure(SCENE, sphere=sphere, **settings) for name, sphere in spheres.items()}  # warm
    times = {name: [] for name in spheres}
    for _ in range(args.repeat):
        for name, sphere in spheres.items():
            start = time.perf_counter()
            vm.sphere_measure(SCENE, sphere=sphere, **settings)
            times[name].append(time.perf_counter() - start)
    base = min(times["plain"])
    print(f"real sphere readouts (sample + standard, {args.rays:,} rays each, 551 nm), best of {args.repeat} (warm), "
          f"{os.cpu_count()} cores, {platform.processor() or platform.machine()}")
    for name, values in times.items():
        r = results[name]
        spill = r.counts["sample"].get("beam_spill")
        extra = "" if spill is None else f"  spill {int(spill[0]) / args.rays:.3f}"
        print(f"  {name:<38} {min(values) * 1e3:8.1f} ms   x{min(values) / base:5.2f}   reading {float(r.reading[0]):.4f}"
              f"{extra}")
    every = spheres["all of them"]
    start = time.perf_counter()
    budget = results["all of them"].budget(lambda sphere, **options: vm.sphere_measure(SCENE, sphere=sphere,
                                                                                         **settings, **options))
    elapsed = time.perf_counter() - start
    print(f"  error budget of 'all of them' ({budget.readings - 2} more readings): {elapsed:.2f} s "
          f"(x{elapsed / base:.1f} the plain readout)")
    print(budget.summary())
    del every


if __name__ == "__main__":
    main()
