"""
The cost of the result type: a result from its counts, a selection, its dataset, its file
==========================================================================================

Issue 29 made every result one ``xarray.Dataset`` (``result.data``). This times, in one
process, what a result costs beside the tracing that fills it, for the readings of a
leaf spectrum (``soybean_abmb``, 421 wavelengths 400–2500/5 nm, at one θi; the counts are
drawn, not traced, so that only the result is timed):

1. **build**: ``vm.Result(...)`` from its counts (what every instrument's ``postprocess``
   does once per call);
2. **select**: ``result.sel(wavelength=550)`` then ``.reflectance``;
3. **dataset**: ``result.to_dataset()`` (every derived variable with its units);
4. **write**: ``result.write("r.nc")`` and ``vm.read_result`` of it;
5. **measure**: ``vm.measure`` of the diamond at θi = 30°, 2 wavelengths, 1,000 rays
   (a whole small call: the share of the result in it).

Each figure is the best of ``--repeat`` runs of ``--number`` calls, in ms per call. To
compare two trees, run the script once with each tree first on ``PYTHONPATH`` (the
``--against`` flag does it in subprocesses, A B A B …, and prints the ratios).

Run::

    .venv/bin/python benchmarks/result_type.py
    .venv/bin/python benchmarks/result_type.py --against ../prev --rounds 3
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent.parent
WAVELENGTHS = np.arange(400.0, 2501.0, 5.0)


def best(call, number: int, repeat: int) -> float:
    """The best of ``repeat`` runs of ``number`` calls, ms per call."""

    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            call()
        times.append((time.perf_counter() - start) / number)
    return 1e3 * min(times)


def figures(number: int, repeat: int) -> dict[str, float]:
    import virtspec_mi as vm
    from virtspec_mi.kernel.counts import Counts

    rng = np.random.default_rng(0)
    n = len(WAVELENGTHS)
    rays = np.full(n, 100_000, dtype=np.int64)
    reflected = rng.integers(20_000, 60_000, n)
    counts = Counts(**{**{name: np.zeros(n, dtype=np.int64) for name in Counts.names()}, "rays": rays,
                       "reflected": reflected, "transmitted": rng.integers(0, 30_000, n),
                       "largest_weight": np.full(n, np.nan)})
    settings = vm.Settings(wavelengths=tuple(WAVELENGTHS), theta_i=8.0)
    geometry = vm.InstrumentGeometry(8, 12.5, 100)

    def build():
        return vm.Result(("wavelength",), {"wavelength": WAVELENGTHS, "theta_i": np.array(8.0)}, counts, None,
                         settings, geometry, 1.0)

    result = build()
    folder = Path(tempfile.mkdtemp())
    scene = vm.mitsuba().load_file(str(HERE / "scenes" / "diamond_collimated.xml"))
    vm.measure(scene, theta_i=30, wavelengths=[450, 650], rays=1000)  # compiles the kernel
    return {
        "build": best(build, number, repeat),
        "select": best(lambda: result.sel(wavelength=550).reflectance, number, repeat),
        "dataset": best(result.to_dataset, max(1, number // 10), repeat),
        "write + read": best(lambda: vm.read_result(result.write(folder / "r.nc")), max(1, number // 20), repeat),
        "measure": best(lambda: vm.measure(scene, theta_i=30, wavelengths=[450, 650], rays=1000),
                        max(1, number // 10), repeat),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--number", type=int, default=100, help="calls per run (default 100)")
    parser.add_argument("--repeat", type=int, default=5, help="runs, the best kept (default 5)")
    parser.add_argument("--against", help="another tree (its root) to time side by side, in subprocesses")
    parser.add_argument("--rounds", type=int, default=3, help="alternations with --against (default 3)")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.against is None:
        found = figures(args.number, args.repeat)
        if args.json:
            print(json.dumps(found))
            return
        for name, ms in found.items():
            print(f"{name:>14}: {ms:9.3f} ms")
        return
    trees = {"this": HERE, "against": Path(args.against).resolve()}
    runs: dict[str, list[dict[str, float]]] = {name: [] for name in trees}
    for _ in range(args.rounds):
        for name, tree in trees.items():
            env = dict(os.environ, PYTHONPATH=str(tree))
            out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--json", "--number",
                                  str(args.number), "--repeat", str(args.repeat)], env=env, check=True,
                                 capture_output=True, text=True, cwd=tree).stdout
            runs[name].append(json.loads(out.strip().splitlines()[-1]))
    simd = "AVX-512 (16 lanes)" if "avx512f" in Path("/proc/cpuinfo").read_text() else "AVX2 (8 lanes)"
    print(f"{args.rounds} interleaved rounds, best of each, ms per call; {simd}")
    print(f"{'figure':>14} {'this':>10} {'against':>10} {'ratio':>7}")
    for key in runs["this"][0]:
        mine = min(run[key] for run in runs["this"])
        theirs = min(run[key] for run in runs["against"])
        print(f"{key:>14} {mine:10.3f} {theirs:10.3f} {mine / theirs:7.2f}")


if __name__ == "__main__":
    main()
