"""
Certified derived quantities against the present route (issue 30)
=================================================================

The soybean leaf (shipped scene ``soybean_abmb``: ABM-B, collimated at θi = 8°, δ = 0.01),
side by side in one run:

- **ours** — ``vm.measure(scene, target=...)``: the rays of each wavelength ∝ its weight
  (Nₖ ∝ |wₖ|, :mod:`virtspec_mi.applications.targets`), traced (wall time of the whole
  call: pilot, sizing, tracing, certificate), or for ΔE₀₀ ≤ 0.1 planned only (its rays
  from the same pilot and sizing; tracing them would take minutes);
- **present route** — certify every wavelength to μ (Hoeffding, δ/n each: the union
  bound over the n readings), with μ the largest for which the same derived tolerance
  follows (each functional then within μ·Σ|wₖ|, propagated through the same map: the
  ΔE₀₀ bound, the NDVI interval). Its rays are exact (n·N(μ, δ/n)); its wall time is
  traced where it is short (the 10 nm grids of the bands and fAPAR) and elsewhere
  estimated from the ray rate those traced runs measured (stated).

The present route is given on two grids. Grid A: the target's own (bands, NDVI and
fAPAR every 1 nm, as ours) and, for colour, 400–830 nm every 10 nm as the issue words it.
Grid B: 10 nm grids for bands, NDVI and fAPAR (fewer readings: cheaper for it; ours costs
the same rays on any grid) and, for colour, our own 400–780 nm every 10 nm.

Run::

    .venv/bin/python benchmarks/derived.py [--markdown FILE]
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import time

import numpy as np

import virtspec_mi as vm
from virtspec_mi.colorimetry.delta_e import lab_box, radius
from virtspec_mi.applications.targets.measure import plan_target
from virtspec_mi.applications.targets.targets import _white, colour_of
from virtspec_mi.budgets.bounds import hoeffding_rays
from virtspec_mi.engine.readings import trace_allocated
from virtspec_mi.runtime.scene import find_bench
from virtspec_mi.settings import Settings

DELTA = 0.01


def _largest(fits, high: float = 0.5) -> float:
    low = 0.0
    for _ in range(50):
        middle = (low + high) / 2
        low, high = (middle, high) if fits(middle) else (low, middle)
    return low


def present_colour_mu(result, tolerance: float) -> float:
    """The largest per-wavelength μ whose box (XYZ ± μ·Σ|w|) keeps the ΔE₀₀ bound ≤ tolerance here."""

    functionals = result.target.functionals()
    totals = np.array([f.total_weight for f in functionals])
    XYZ = result.colour.XYZ
    estimate = colour_of(XYZ, functionals, result.target)
    white = _white(functionals)
    return _largest(lambda mu: radius(estimate.Lab, lab_box(np.maximum(XYZ - mu * totals, 0), XYZ + mu * totals,
                                                            white))[0] <= tolerance)


def present_index_mu(result, tolerance: float) -> float:
    index = result.target.index
    a, b = result.values[1].value, result.values[2].value
    centre = index.value(a, b)

    def fits(mu: float) -> bool:
        low, high = index.interval((a - mu, a + mu), (b - mu, b + mu))
        return max(centre - low, high - centre) <= tolerance

    return _largest(fits)


def present_rays(mu: float, readings: int) -> int:
    return readings * hoeffding_rays(mu, DELTA / readings)


def trace_present(bench, settings, wavelengths, mu) -> tuple[int, float]:
    """The present route traced: every wavelength at N(μ, δ/n); (rays, seconds)."""

    n = len(wavelengths)
    rays = np.full(n, hoeffding_rays(mu, DELTA / n))
    start = time.perf_counter()
    trace_allocated(bench, settings, [(float(w), 8.0, 0.0) for w in wavelengths], rays,
                    offsets=np.arange(n) * int(rays[0]))
    return int(rays.sum()), time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--markdown", help="also write the table to this file")
    args = parser.parse_args()
    scene = vm.scenes.path("soybean_abmb")
    bench = find_bench(str(scene), None)
    settings = Settings(theta_i=8.0, beam="collimated", delta=DELTA, seed=0, wavelengths=[500.0])
    vm.measure(scene, target=vm.band("B04", tolerance=0.05), delta=DELTA)  # compile the kernel (not timed)

    rows = []
    rates = []

    def row(name, ours_rays, ours_s, present, present_10, traced_note):
        rows.append((name, ours_rays, ours_s, present, present_10, traced_note))

    # bands and fAPAR: the present route traced on 10 nm grids (also its ray rate)
    bands = vm.measure(scene, target=vm.band("B04", "B08", tolerance=0.002), delta=DELTA)
    grid_1nm = len(bands.readings.coords["wavelength"])
    grid_10 = np.concatenate([np.arange(650, 681, 10.0), np.arange(780, 886, 10.0)])
    traced_rays, traced_s = trace_present(bench, settings, grid_10, 0.002)
    rates.append(traced_rays / traced_s)
    row("S2 B04 & B08, +-0.002", bands.total_rays, bands.seconds,
        (present_rays(0.002, grid_1nm), None), (traced_rays, traced_s), "10 nm traced")

    fapar = vm.measure(scene, target=vm.fapar(tolerance=0.002), delta=DELTA)
    grid_10 = np.arange(400, 701, 10.0)
    traced_rays, traced_s = trace_present(bench, settings, grid_10, 0.002)
    rates.append(traced_rays / traced_s)
    row("fAPAR, +-0.002", fapar.total_rays, fapar.seconds, (present_rays(0.002, 301), None),
        (traced_rays, traced_s), "10 nm traced")
    rate = float(np.mean(rates))

    ndvi = vm.measure(scene, target=vm.index("NDVI", tolerance=0.002), delta=DELTA)
    mu = present_index_mu(ndvi, 0.002)
    row(f"NDVI, +-0.002 (present mu = {mu:.2e})", ndvi.total_rays, ndvi.seconds,
        (present_rays(mu, grid_1nm), None), (present_rays(mu, 15), None), "estimated")

    colour = vm.measure(scene, target=vm.colour(tolerance_dE00=0.5), delta=DELTA)
    mu = present_colour_mu(colour, 0.5)
    row(f"colour, dE00 <= 0.5 (present mu = {mu:.2e})", colour.total_rays, colour.seconds,
        (present_rays(mu, 44), None), (present_rays(mu, 39), None),
        "estimated; present on 400-830 (A), 400-780 nm (B)")
    planned = plan_target(bench, settings, vm.colour(tolerance_dE00=0.1))
    mu = present_colour_mu(colour, 0.1)
    row(f"colour, dE00 <= 0.1 (present mu = {mu:.2e})", int(planned.rays.sum()) + planned.pilot_rays, None,
        (present_rays(mu, 44), None), (present_rays(mu, 39), None), "estimated; ours planned only; A, B as above")

    lanes = 16 if "avx512f" in open("/proc/cpuinfo").read() else 8
    head = (f"`python benchmarks/derived.py` on {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
            f"{platform.machine()}, {os.cpu_count()} cores (shared with other work: load "
            f"{os.getloadavg()[0]:.1f}), SIMD {lanes} lanes; soybean_abmb, collimated 8 deg, delta = {DELTA}; "
            f"present-route wall times marked 'estimated' use the ray rate of the traced present runs "
            f"({rate / 1e6:.1f} Mray/s)")
    lines = [head, "",
             "| quantity | ours: rays | ours: s | present (grid A): rays | present: s | ratio | "
             "present (grid B): rays | present: s | ratio | note |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for name, ours_rays, ours_s, (p_rays, p_s), (q_rays, q_s), note in rows:
        p_s = p_rays / rate if p_s is None else p_s
        q_s = q_rays / rate if q_s is None else q_s
        shown = "-" if ours_s is None else f"{ours_s:.2f}"
        lines.append(f"| {name} | {ours_rays:,} | {shown} | {p_rays:,} | {p_s:.1f} | {p_rays / ours_rays:.0f}x | "
                     f"{q_rays:,} | {q_s:.1f} | {q_rays / ours_rays:.0f}x | {note} |")
    text = "\n".join(lines)
    print(text)
    for result in (bands, fapar, ndvi, colour):
        print()
        print(result.summary())
    if args.markdown:
        with open(args.markdown, "w") as handle:
            handle.write(text + "\n")


if __name__ == "__main__":
    main()
