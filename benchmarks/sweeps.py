"""
Sweeps in few kernel launches (issue 3)
=======================================

Prints, in one run:

(a) **Fig. 5 sweep** — the paper's directional-hemispherical sweep: the diamond
    (``simple_dielectric``, η = 2.419), collimated beam, θi = 0:90:1 (91 angles),
    551 nm, certified N = 105,967 rays each (μ = 0.005, δ = 0.01, eq. 23), seed 0.
    Warm (one call first compiles the kernels); median and best of the repeats.
    Target: ≤ 0.25 s.
(b) **301-wavelength spectrum** — 400:700:1 nm at θi = 8°, collimated, certified N each,
    of a wavelength-*dependent* specimen: Mitsuba ``diffuse`` with a ``regular``
    reflectance spectrum (0.1 → 0.9 → 0.3 over 400–700 nm). It is traced per
    wavelength (not flagged wavelength-independent; the script checks). Side by side:
    one ``virtspec_mi.sweep`` call vs a loop of 301 single-wavelength
    ``virtspec_mi.measure`` calls; seconds, rays/s and the ratio.
(c) **CSV of a large sweep** — a 91 θi × 1000 wavelength result (91,000 readings, built
    from counts: nothing traced) written as CSV: ``virtspec_mi.results.io.csv_text`` of
    its dataset, in cells (rows × columns) per second (target ≥ 10⁶ cells/s; the text
    grows linearly with the cells), best of the repeats; and the whole
    ``Result.write(".csv")`` (which also builds the dataset: every Clopper–Pearson
    interval).

Run::

    .venv/bin/python benchmarks/sweeps.py              # 5 repeats of (a), 3 of (b) and (c)
    .venv/bin/python benchmarks/sweeps.py --quick      # 2 repeats of (a), 1 of (b) and (c)
    .venv/bin/python benchmarks/sweeps.py --markdown   # the results as a markdown block
    .venv/bin/python benchmarks/sweeps.py --csv-only   # (c) alone (no Mitsuba)

Takes 10–30 s on a 2-core machine. Other work on the machine slows every figure, so
the 1-minute load average is printed with the results; the ratio (b) is the figure
to compare across machines.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from revisions import machine, machine_lines  # noqa: E402  (one machine description for all benchmarks)

import virtspec_mi as vm  # noqa: E402

SPECTRUM = {"type": "regular", "wavelength_min": 400.0, "wavelength_max": 700.0, "values": "0.1, 0.9, 0.3"}


def fig5(repeats: int) -> dict:
    scene = vm.mitsuba().load_dict(vm.instrument_scene({"type": "simple_dielectric"}))
    kwargs = dict(theta_i="0:90:1", beam="collimated", seed=0)
    vm.sweep(scene, **kwargs)  # warm-up: compiles the kernels
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = vm.sweep(scene, **kwargs)
        times.append(time.perf_counter() - start)
    return {"median": statistics.median(times), "best": min(times), "rays": int(result.rays.sum()),
            "readings": result.rays.size, "traced": len(result.theta_i)}


def spectrum(repeats: int) -> dict:
    scene = vm.mitsuba().load_dict(vm.instrument_scene({"type": "diffuse", "reflectance": SPECTRUM}))
    wavelengths = np.arange(400.0, 701.0, 1.0)
    kwargs = dict(beam="collimated", seed=0)
    vm.sweep(scene, theta_i=[8], wavelengths=wavelengths[:3], **kwargs)  # warm-up
    vm.measure(scene, theta_i=8, wavelengths=[400.0], **kwargs)
    sweep_times, loop_times = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        result = vm.sweep(scene, theta_i=[8], wavelengths=wavelengths, **kwargs)
        sweep_times.append(time.perf_counter() - start)
        start = time.perf_counter()
        for w in wavelengths:
            vm.measure(scene, theta_i=8, wavelengths=[w], **kwargs)
        loop_times.append(time.perf_counter() - start)
    assert not result.wavelength_independent, "the specimen must be traced per wavelength"
    rays = int(result.rays.sum())
    return {"sweep": min(sweep_times), "loop": min(loop_times), "rays": rays,
            "spread": float(result.reflectance.max() - result.reflectance.min())}


def csv_grid(repeats: int) -> dict:
    from dataclasses import replace
    from tempfile import TemporaryDirectory

    from virtspec_mi.kernel.counts import Counts
    from virtspec_mi.geometry.disks import InstrumentGeometry
    from virtspec_mi.results.readings import Result
    from virtspec_mi.results.io import csv_text
    from virtspec_mi.settings import Settings

    wavelengths, angles = np.arange(400.0, 1400.0, 1.0), np.arange(91.0)
    shape, rng = (len(wavelengths), len(angles)), np.random.default_rng(0)
    reflected = rng.integers(0, 50_000, shape)
    counts = replace(Counts.zeros(shape), rays=np.full(shape, 100_000, dtype=np.int64), reflected=reflected,
                     transmitted=rng.integers(0, 50_000, shape), specular_reflected=reflected // 3)
    result = Result(("wavelength", "theta_i"), {"wavelength": wavelengths, "theta_i": angles}, counts, None,
                    Settings(wavelengths=list(wavelengths)), InstrumentGeometry(8, 12.5, 100), 0.0)
    dataset = result.to_dataset()
    cells = dataset.sizes["wavelength"] * dataset.sizes["theta_i"] * (len(dataset.data_vars) + 2)
    text_times, write_times = [], []
    with TemporaryDirectory() as folder:
        for _ in range(repeats):
            start = time.perf_counter()
            text = csv_text(dataset)
            text_times.append(time.perf_counter() - start)
            start = time.perf_counter()
            result.write(Path(folder) / "grid.csv")
            write_times.append(time.perf_counter() - start)
    return {"cells": cells, "text": min(text_times), "write": min(write_times), "mb": len(text) / 1e6,
            "readings": result.rays.size}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--quick", action="store_true", help="fewer repeats")
    parser.add_argument("--markdown", action="store_true", help="print a markdown block for RESULTS.md")
    parser.add_argument("--csv-only", action="store_true", help="only (c), the CSV of a large sweep")
    args = parser.parse_args(argv)
    load_before = os.getloadavg()[0]
    rows = []
    if not args.csv_only:
        a = fig5(2 if args.quick else 5)
        b = spectrum(1 if args.quick else 3)
        target = "met" if a["median"] <= 0.25 else "NOT met"
        rows += [
            ["(a) Fig. 5 sweep, 91 angles, diamond, collimated", f"{a['rays']:,} rays",
             f"{a['median']:.3f} (best {a['best']:.3f})", f"{a['rays'] / a['median'] / 1e6:.0f} Mray/s",
             f"target <= 0.25 s: {target}; traced once per angle"],
            ["(b) 301 wavelengths, one sweep() call", f"{b['rays']:,} rays", f"{b['sweep']:.3f}",
             f"{b['rays'] / b['sweep'] / 1e6:.0f} Mray/s", "diffuse, regular spectrum, traced per wavelength"],
            ["(b) 301 wavelengths, loop of 301 measure() calls", f"{b['rays']:,} rays", f"{b['loop']:.3f}",
             f"{b['rays'] / b['loop'] / 1e6:.0f} Mray/s", f"ratio loop / sweep = {b['loop'] / b['sweep']:.1f}"],
        ]
    c = csv_grid(1 if args.quick else 3)
    rate = c["cells"] / c["text"]
    rows += [
        ["(c) CSV of 91 theta_i x 1000 wavelengths: csv_text", f"{c['cells']:,} cells", f"{c['text']:.3f}",
         f"{rate / 1e6:.2f} Mcell/s", f"target >= 1 Mcell/s: {'met' if rate >= 1e6 else 'NOT met'}; "
                                        f"{c['readings']:,} rows, {c['mb']:.0f} MB"],
        ["(c) the same, Result.write('.csv') in all", f"{c['cells']:,} cells", f"{c['write']:.3f}",
         f"{c['cells'] / c['write'] / 1e6:.2f} Mcell/s", "builds the dataset (intervals) and writes atomically"],
    ]
    info = machine()
    info["load"] = f"{load_before:.2f} before the run, {os.getloadavg()[0]:.2f} after"
    header = ["case", "work", "seconds", "rate", "note"]
    if args.markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
        for row in rows:
            print("| " + " | ".join(row) + " |")
        print()
        for line in machine_lines(info):
            print(f"- {line}")
    else:
        for row in rows:
            print(f"{row[0]:<50} {row[1]:>18} {row[2]:>22} s {row[3]:>14}  {row[4]}")
        print("\n".join(machine_lines(info)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
