"""
The cost of binning on the RGL grid (issue 41)
==============================================

Side by side in one run, a goniophotometer reading of a rough conductor (Mitsuba's
``roughconductor``, GGX, α = 0.3; collimated beam at θi = 20, 40, 60°, 550 nm, seed 1) at N
rays per reading:

1. **theta-phi** — the default binning, 18 × 36 uniform bins per hemisphere (K = 1,296);
2. **rgl** — ``binning="rgl"``, the ``.bsdf``'s grid of n × n nodes (K = 1 + (n − 1)²
   cells, found from the half vector: two ``atan2`` and a square root per ray).

Both warm (a small call of each compiles its kernel first), alternated over ``--rounds``
rounds, best of each; their R must be equal (same rays). Then the cells' solid angles (by
quadrature, once per θi of a reading) and the export of the ``rgl`` reading, ``to_rgl``
(best of three: the reading keeps its solid angles).

Run::

    .venv/bin/python benchmarks/rgl_export.py                  # 10^7 rays per reading, n = 32
    .venv/bin/python benchmarks/rgl_export.py --rays 1e6 --nodes 16
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

SPECIMEN = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3}
THETA_I = [20.0, 40.0, 60.0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--rays", type=float, default=1e7, help="rays per reading")
    parser.add_argument("--nodes", type=int, default=32, help="nodes per axis of the grid")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()

    import virtspec_mi as vm

    scene = vm.instrument_scene(SPECIMEN)
    common = {"theta_i": THETA_I, "wavelengths": [550.0], "beam": "collimated", "seed": 1}
    kinds = {"theta-phi": {"theta_o_bins": 18, "phi_o_bins": 36},
             "rgl": {"binning": "rgl", "rgl_resolution": args.nodes}}
    for options in kinds.values():  # compile
        vm.gonio(scene, rays=10_000, **common, **options)
    best, readings = {name: np.inf for name in kinds}, {}
    for _ in range(args.rounds):
        for name, options in kinds.items():
            start = time.perf_counter()
            readings[name] = vm.gonio(scene, rays=int(args.rays), **common, **options)
            best[name] = min(best[name], time.perf_counter() - start)
    assert np.array_equal(readings["rgl"].result.reflected, readings["theta-phi"].result.reflected)
    total = int(args.rays) * len(THETA_I)
    for name, seconds in best.items():
        print(f"{name:>10}: {seconds:.3f} s for {total:,} rays ({total / seconds / 1e6:.1f} M rays/s), "
              f"K = {readings[name].size}")
    print(f"rgl / theta-phi time: {best['rgl'] / best['theta-phi']:.3f}")
    start = time.perf_counter()
    for theta in THETA_I:
        readings["rgl"].grid.solid_angles(theta)
    print(f"cells' solid angles (once per reading, per theta_i): {(time.perf_counter() - start) / len(THETA_I):.3f} s")
    with tempfile.TemporaryDirectory() as work:
        export = np.inf
        for k in range(3):
            start = time.perf_counter()
            readings["rgl"].to_rgl(Path(work) / f"r{k}.bsdf")
            export = min(export, time.perf_counter() - start)
    print(f"to_rgl ({len(THETA_I)} theta_i, n = {args.nodes}): {export:.3f} s")


if __name__ == "__main__":
    main()
