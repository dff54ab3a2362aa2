"""
Parameter sweeps: what recompiles, and what a new parameter value costs.

A soybean leaf (``abm_b``) at θi = 8°, collimated, over a few wavelengths, swept over
its thickness (``specimen.thickness``). Printed side by side, in one run:

- the first parameter point, which traces and compiles the ray kernel (in a fresh Dr.Jit
  kernel cache when run with ``--cold``: a new process with its own empty cache folder);
- each later point: the seconds per point and the ray kernels Dr.Jit compiled for it
  (kernel history: a kernel whose IR is new gets a new hash; compiled = found neither in
  the in-memory nor in the on-disk cache), expected 0;
- the same values by loading one scene per value (``mi.load_dict``), the way to vary a
  parameter before parameter sweeps: its seconds per value.

Usage::

    .venv/bin/python benchmarks/parameter_sweep.py [--values 5] [--wavelengths 21] [--rays 20000] [--cold]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np


def _history(function):
    import drjit as dr

    dr.kernel_history()
    with dr.scoped_set_flag(dr.JitFlag.KernelHistory):
        start = time.perf_counter()
        function()
        seconds = time.perf_counter() - start
    kernels = [k for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]
    ray_kernels = [k for k in kernels if k["operation_count"] > 100]
    built = sum(not k["cache_hit"] and not k.get("cache_disk", False) for k in ray_kernels)  # neither in memory nor on disk
    return seconds, {k["hash"] for k in ray_kernels}, built


def run(values: int, wavelengths: int, rays: int) -> None:
    import mitsuba as mi

    import virtspec_mi as vm

    vm.mitsuba()
    thickness = np.linspace(1.2e-4, 2.4e-4, values)
    lams = np.linspace(450, 850, wavelengths)
    settings = dict(theta_i=8, beam="collimated", wavelengths=lams, rays=rays, seed=0)
    scene = mi.load_dict(vm.instrument_scene({"type": "abm_b"}))
    first, seen, compiled_first = _history(
        lambda: vm.sweep(scene, parameters={"specimen.thickness": thickness[:1]}, **settings))
    rest, hashes, compiled_rest = _history(
        lambda: vm.sweep(scene, parameters={"specimen.thickness": thickness[1:]}, **settings))
    new = len(hashes - seen)
    start = time.perf_counter()
    for value in thickness[1:]:
        vm.sweep(mi.load_dict(vm.instrument_scene({"type": "abm_b", "thickness": float(value)})), **settings)
    loaded = time.perf_counter() - start
    per_point = rest / (values - 1)
    readings = wavelengths * rays
    print(f"soybean abm_b, theta_i = 8 deg collimated, {wavelengths} wavelengths x {rays:,} rays per point, "
          f"{values} thickness values")
    print(f"{'':44} {'seconds':>9} {'ray kernels compiled':>21} {'new ray kernels':>16}")
    print(f"{'first point (traces, compiles)':44} {first:>9.3f} {compiled_first:>21d} {len(seen):>16d}")
    print(f"{'each later point (parameter sweep)':44} {per_point:>9.3f} {compiled_rest:>21d} {new:>16d}")
    print(f"{'each later value (one scene loaded per value)':44} {loaded / (values - 1):>9.3f}")
    print(f"later points: {readings / per_point / 1e6:.2f} M rays/s; first / later = {first / per_point:.1f}x")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--values", type=int, default=5)
    parser.add_argument("--wavelengths", type=int, default=21)
    parser.add_argument("--rays", type=int, default=20_000)
    parser.add_argument("--cold", action="store_true", help="run in a new process with an empty Dr.Jit kernel cache")
    args = parser.parse_args()
    if args.cold:
        with tempfile.TemporaryDirectory() as home:  # Dr.Jit keeps its disk cache in ~/.drjit
            command = [sys.executable, __file__, "--values", str(args.values), "--wavelengths",
                       str(args.wavelengths), "--rays", str(args.rays)]
            subprocess.run(command, check=True, env={**os.environ, "HOME": home})
        return
    run(args.values, args.wavelengths, args.rays)


if __name__ == "__main__":
    main()
