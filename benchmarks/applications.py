"""
The applications' calls, side by side with another tree: measure, target, fit, table
====================================================================================

Issue 38 moved every application into a folder of its own and made it take its readings
through the instrument seam (``virtspec_mi.runtime.reading``) instead of the API. This
times, in one process per tree, four whole calls that go through the new seams, with
the public names both trees have (``vm.measure``, ``vm.band``, ``vm.fit``,
``vm.albedo_table``):

1. **measure**: ``vm.measure`` of the diamond at θi = 30°, 2 wavelengths, 1,000 rays;
2. **target**: ``vm.measure(soybean_abmb, target=vm.band("B04", tolerance=0.01))``;
3. **fit**: ``vm.fit`` of PROSPECT-D's Cab to a synthetic spectrum (11 wavelengths,
   evaluations 4, 2, 1, no profile);
4. **table**: ``vm.albedo_table("conductor")`` on a 2 × 2 grid at ε = 0.02.

Each figure is the best of ``--repeat`` calls (after one call that compiles the kernels),
in ms. ``--against TREE`` runs the script in subprocesses for this tree and ``TREE``
alternately (A B A B …, ``--rounds`` times) and prints the best of each and their ratio;
the counts are the same in both trees (checked: the rays each call spent).

Run::

    .venv/bin/python benchmarks/applications.py
    .venv/bin/python benchmarks/applications.py --against ../prev --rounds 3
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]


def best(call, repeat: int) -> tuple[float, int]:
    """The best wall time of ``repeat`` calls (ms) after one warm-up call, and the rays of one call."""

    rays = call()
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        call()
        times.append(1e3 * (time.perf_counter() - started))
    return min(times), rays


def figures(repeat: int) -> dict[str, tuple[float, int]]:
    import virtspec_mi as vm
    from virtspec_mi.plugins.bsdfs.prospect_model import prospect_d

    diamond = vm.mitsuba().load_file(str(HERE / "scenes" / "diamond_collimated.xml"))
    leaf = vm.mitsuba().load_file(str(HERE / "scenes" / "soybean_abmb.xml"))
    wavelengths = np.arange(450.0, 2451.0, 200.0)
    reflectance, transmittance = prospect_d(wavelengths, Cab=52.0, Cm=0.008)
    u = np.full(len(wavelengths), 0.02)
    measured = {"reflectance": (wavelengths, reflectance, u), "transmittance": (wavelengths, transmittance, u)}

    def measure() -> int:
        return int(np.sum(vm.measure(diamond, theta_i=30, wavelengths=[450, 650], rays=1000).rays))

    def target() -> int:
        return int(vm.measure(leaf, target=vm.band("B04", tolerance=0.01)).rays)

    def fit() -> int:
        result = vm.fit(measured, "prospect_d", {"Cab": (10, 90)}, delta=0.1, theta_i=8, beam="collimated",
                        profile_points=0, evaluations=(4, 2, 1), progress=False)
        return int(result.rays)

    def table() -> int:
        result = vm.albedo_table("conductor", engine=None, mu=[1.0, 0.3], roughness=[0.5, 1.0], epsilon=0.02, seed=1,
                                 progress=False)
        return int(sum(np.sum(v) for v in result.counts.values()))

    return {"measure": best(measure, repeat), "target": best(target, repeat), "fit": best(fit, max(1, repeat // 2)),
            "table": best(table, max(1, repeat // 2))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=4, help="timed calls per figure, the best kept (default 4)")
    parser.add_argument("--against", help="another tree (its root) to time side by side, in subprocesses")
    parser.add_argument("--rounds", type=int, default=3, help="alternations with --against (default 3)")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.against is None:
        found = figures(args.repeat)
        if args.json:
            print(json.dumps(found))
            return
        for name, (ms, rays) in found.items():
            print(f"{name:>8}: {ms:10.1f} ms  ({rays:,} counted)")
        return
    trees = {"this": HERE, "against": Path(args.against).resolve()}
    runs: dict[str, list[dict]] = {name: [] for name in trees}
    for _ in range(args.rounds):
        for name, tree in trees.items():
            env = dict(os.environ, PYTHONPATH=str(tree))
            out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--json", "--repeat",
                                  str(args.repeat)], env=env, check=True, capture_output=True, text=True,
                                 cwd=tree).stdout
            runs[name].append(json.loads(out.strip().splitlines()[-1]))
    simd = "AVX-512 (16 lanes)" if "avx512f" in Path("/proc/cpuinfo").read_text() else "AVX2 (8 lanes)"
    print(f"{args.rounds} interleaved rounds, best of each, ms per call; {simd}; load {os.getloadavg()[0]:.1f}")
    print(f"{'call':>8} {'this':>10} {'against':>10} {'ratio':>7} {'same counts':>12}")
    for key in runs["this"][0]:
        mine = min(run[key][0] for run in runs["this"])
        theirs = min(run[key][0] for run in runs["against"])
        same = {run[key][1] for run in runs["this"]} == {run[key][1] for run in runs["against"]}
        print(f"{key:>8} {mine:10.1f} {theirs:10.1f} {mine / theirs:7.2f} {str(same):>12}")


if __name__ == "__main__":
    main()
