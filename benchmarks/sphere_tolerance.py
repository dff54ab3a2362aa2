"""
A sphere reading to a stated tolerance: the rays a pilot sizes against the least (issue 39)
============================================================================================

The shipped 150 mm 8°/d sphere (``sphere_150mm_8d``: grey 0.5 Lambertian sample, counted
detector, δ = 0.01), read at 550 nm to ``tolerance`` ±0.005 on the reading
(``vm.sphere_measure(..., tolerance=...)``) with pilots of 2,000 and 50,000 rays (the
default), side by side in one run; "least" is :func:`virtspec_mi.budgets.ratio.ratio_rays`
at the fractions of the 50,000-ray reading's own main stage taken as exact (a pilot that
knew them). Seconds are the whole call's (pilot included).

Run::

    PYTHONPATH=$PWD .venv/bin/python benchmarks/sphere_tolerance.py [--tolerance 0.005]
"""

from __future__ import annotations

import argparse
import datetime
import os
import time

import numpy as np

import virtspec_mi as vm
from virtspec_mi.budgets.ratio import ratio_half_width, ratio_rays
from simd import lanes


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--tolerance", type=float, default=0.005)
    args = parser.parse_args()
    t = args.tolerance
    vm.sphere_measure("sphere_150mm_8d", rays=1000, wavelengths=[550])  # compile (not timed)
    print(f"`python benchmarks/sphere_tolerance.py --tolerance {t:g}` on {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} "
          f"UTC, {os.cpu_count()} cores, SIMD {lanes()} lanes, load {os.getloadavg()[0]:.1f}; sphere_150mm_8d, 550 nm, "
          "delta = 0.01, seed 1\n")
    print("| pilot rays | N per configuration | reading | half-width | met | s |")
    print("|---:|---:|---:|---:|---|---:|")
    fractions = None
    for pilot in (2_000, 50_000):
        start = time.perf_counter()
        r = vm.sphere_measure("sphere_150mm_8d", tolerance=t, pilot_rays=pilot, wavelengths=[550], seed=1)
        seconds = time.perf_counter() - start
        interval, reading = r.reading_interval[0], float(r.reading[0])
        half = max(reading - interval[0], interval[1] - reading)
        print(f"| {pilot:,} | {int(r.rays[0, 0]):,} | {reading:.4f} | {half:.5f} | {bool(r.tolerance_met.all())} | "
              f"{seconds:.2f} |")
        fractions = (float(r.detector_fraction[0]), float(r.standard_fraction[0]))
    n = 10**9  # counts of a pilot this long: the fractions taken as exact
    least = int(ratio_rays(np.round(fractions[0] * n), np.round(fractions[1] * n), n, t, 0.99, 0.01, 0.001)[0])
    check = float(ratio_half_width(np.round(fractions[0] * least), least, np.round(fractions[1] * least), least, 0.99,
                                   0.01))
    print(f"\nleast N at the fractions {fractions[0]:.4f}, {fractions[1]:.4f} taken as exact: {least:,} "
          f"(half-width {check:.5f})")


if __name__ == "__main__":
    main()
