"""
Peak memory of one kernel launch against ``chunk_size``
=======================================================

The evidence behind :data:`virtspec_mi.base.checks.MAX_CHUNK_SIZE`. For each specimen and
each chunk size 2^k, a fresh Python process warms up (imports, kernel compilation with
a tiny reading), then measures two wavelengths at θi (default 30°) with
``rays = chunk_size = 2^k`` and reports the growth of its peak resident memory
(``resource.getrusage(RUSAGE_SELF).ru_maxrss``) over the warmed-up process, in MiB and
bytes per ray. Wavelength-independent specimens trace one reading, others two (one
launch each).

Usage::

    python tools/chunk_memory.py                       # every specimen at 2^22, 2^24, 2^26
    python tools/chunk_memory.py --kinds diamond slab --logs 22 24

Measured on this project's 2-core machine (issue 12): 12 B/ray (``simple_dielectric``,
``diffuse``, ``abm_b``, ``roughconductor``), 20 B/ray (``turbid_slab``: two packed
counts) and 41 B/ray (coloured ``plastic`` at 89°: weight violations take the rare-event
path), the same at every size.
"""

from __future__ import annotations

import argparse
import subprocess
import sys

__all__ = ["SPECIMENS", "measure_one", "main"]

SPECIMENS: dict[str, tuple[dict, float]] = {
    "diamond": ({"type": "simple_dielectric"}, 30.0),
    "diffuse": ({"type": "diffuse"}, 30.0),
    "slab": ({"type": "turbid_slab", "mu_a": 1.0, "mu_s": 9.0, "thickness": 0.1}, 30.0),
    "abm": ({"type": "abm_b"}, 30.0),
    "rough": ({"type": "roughconductor"}, 30.0),
    "plastic": ({"type": "plastic", "diffuse_reflectance": {"type": "rgb", "value": [0.9, 0.1, 0.1]}}, 89.0),
}
"""Specimen name → (BSDF dict, θi in degrees)."""

_CHILD = """
import resource, sys, time, warnings
import virtspec_mi as vm
bsdf, theta, n = eval(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
scene = vm.instrument_scene(bsdf)
warnings.simplefilter("ignore")
vm.measure(scene, rays=1024, chunk_size=1024, wavelengths=[551, 600], theta_i=theta)
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
start = time.perf_counter()
vm.measure(scene, rays=n, chunk_size=n, wavelengths=[551, 600], theta_i=theta)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(before, peak, time.perf_counter() - start)
"""


def measure_one(kind: str, log2: int) -> tuple[float, float, float]:
    """(peak growth in MiB, bytes per ray, seconds) of one launch of 2^``log2`` rays, in a fresh process."""

    bsdf, theta = SPECIMENS[kind]
    n = 1 << log2
    out = subprocess.run([sys.executable, "-c", _CHILD, repr(bsdf), str(theta), str(n)],
                         capture_output=True, text=True, check=True).stdout.split()
    before, peak, seconds = int(out[0]), int(out[1]), float(out[2])
    return (peak - before) / 1024, (peak - before) * 1024 / n, seconds


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kinds", nargs="+", default=list(SPECIMENS), choices=list(SPECIMENS))
    parser.add_argument("--logs", nargs="+", type=int, default=[22, 24, 26], help="chunk sizes as powers of 2")
    args = parser.parse_args(argv)
    print(f"{'specimen':>10} {'chunk':>6} {'peak growth':>12} {'B/ray':>6} {'seconds':>8}")
    for kind in args.kinds:
        for log2 in args.logs:
            mib, per_ray, seconds = measure_one(kind, log2)
            print(f"{kind:>10} {'2^' + str(log2):>6} {mib:>9.0f} MiB {per_ray:>6.1f} {seconds:>8.1f}", flush=True)


if __name__ == "__main__":
    main()
