"""
Betting confidence sequences against Hoeffding's route for certified targets (issue 39)
========================================================================================

The soybean leaf (shipped scene ``soybean_abmb``: ABM-B, collimated at θi = 8°,
δ = 0.01, seed 0) and an 18 % grey Lambertian card (same settings), each target measured
twice in one run, side by side:

- ``bound="hoeffding"`` — the one-batch route (Nₖ ∝ |wₖ|, Hoeffding 1963; the previous
  main's route, bit-identical);
- ``bound="betting"`` — batches until the certificate holds, Neyman allocation, a
  stratified betting confidence sequence (:mod:`virtspec_mi.budgets.betting`); a colour
  from one joint region of XYZ (CIELAB facets, :mod:`virtspec_mi.applications.targets.joint`);
  the previous main's default for every target, bit-identical;
- ``bound="two-stage"`` — for a linear target (bands, fAPAR): each functional's
  wavelengths pooled into one binomial proportion, a pilot then one batch sized by the
  exact law (:mod:`virtspec_mi.applications.targets.pooled`); ``bound="auto"``, the
  default, takes it for linear targets and the betting route for the others.

"saved" is Hoeffding's rays over the default's (``auto``'s route); "met" says whether
each route met its target (a route not met stops at 4 times Hoeffding's rays).

Rays are those of the estimates plus the pilot's; seconds are the wall time of the whole
``vm.measure`` call (pilot, sizing, tracing, certificates). The kernel is compiled before
anything is timed.

Run::

    PYTHONPATH=$PWD .venv/bin/python benchmarks/betting.py [--quick] [--avx2] [--markdown FILE]

``--quick`` leaves out the colours to ΔE₀₀ ≤ 0.5 (Hoeffding's route traces about 1.2·10⁸ rays for the leaf).
``--avx2`` compiles the kernels for AVX2 (8 lanes) on a machine with wider vectors
(:mod:`benchmarks.simd`): AVX2 code on this machine's cores, not an AVX2 machine.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform

import virtspec_mi as vm
from simd import lanes, use_avx2
from virtspec_mi.applications.targets.pooled import poolable
from virtspec_mi.applications.targets.sequential import BOUNDS

DELTA = 0.01


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="leave out the colour to dE00 <= 0.5")
    parser.add_argument("--avx2", action="store_true", help="compile the kernels for AVX2 (8 lanes)")
    parser.add_argument("--markdown", help="also write the table to this file")
    args = parser.parse_args()
    if args.avx2:
        use_avx2()
    scene = vm.scenes.path("soybean_abmb")
    options = dict(delta=DELTA, seed=0, theta_i=8.0, beam="collimated")
    for bound in BOUNDS:  # compile the kernels (not timed)
        vm.measure(scene, target=vm.band("B04", tolerance=0.05), bound=bound, **options)
    grey = vm.instrument_scene({"type": "diffuse", "reflectance": {  # an 18 % grey Lambertian card
        "type": "regular", "wavelength_min": 300, "wavelength_max": 1000, "values": "0.18, 0.18"}})
    targets = [("colour, dE00 <= 1.0", lambda: vm.colour(tolerance_dE00=1.0)),
               ("S2 B04 & B08, +-0.002", lambda: vm.band("B04", "B08", tolerance=0.002)),
               ("NDVI, +-0.002", lambda: vm.index("NDVI", tolerance=0.002)),
               ("fAPAR, +-0.002", lambda: vm.fapar(tolerance=0.002)),
               ("S2 B04, +-0.002", lambda: vm.band("B04", tolerance=0.002)),
               ("S2 B08, +-0.002", lambda: vm.band("B08", tolerance=0.002)),
               ("fAPAR, +-0.01", lambda: vm.fapar(tolerance=0.01)),
               ("D65 albedo 400-780 nm, +-0.002", lambda: vm.albedo(tolerance=0.002, low=400, high=780))]
    targets += [("grey 18 %: colour, dE00 <= 1.0", lambda: vm.colour(tolerance_dE00=1.0))]
    if not args.quick:
        targets.insert(0, ("colour, dE00 <= 0.5", lambda: vm.colour(tolerance_dE00=0.5)))
        targets.append(("grey 18 %: colour, dE00 <= 0.5", lambda: vm.colour(tolerance_dE00=0.5)))
    start = datetime.datetime.now(datetime.timezone.utc)
    rows = []
    for name, make in targets:
        specimen = grey if name.startswith("grey") else scene
        pooled = not poolable(make())
        results = {bound: vm.measure(specimen, target=make(), bound=bound, **options)
                   for bound in BOUNDS if pooled or bound != "two-stage"}
        rows.append((name, results))
        h, chosen = results["hoeffding"], results[results["auto"].bound]
        print(f"{name}: " + "; ".join(f"{bound} {r.total_rays:,} rays {r.seconds:.2f} s (met {r.met})"
                                      for bound, r in results.items())
              + f"; saved {h.total_rays / chosen.total_rays:.2f}x ({chosen.bound})", flush=True)
    flags = "".join(f" --{name}" for name in ("quick", "avx2") if getattr(args, name))
    head = (f"`python benchmarks/betting.py{flags}` on {start:%Y-%m-%d %H:%M} UTC, "
            f"{platform.machine()}, {os.cpu_count()} cores (load at the end {os.getloadavg()[0]:.1f}), SIMD {lanes()} "
            f"lanes{' (AVX2 code)' if args.avx2 else ''}; soybean_abmb, collimated 8 deg, delta = {DELTA}, seed 0")
    lines = [head, "", "| target | Hoeffding: rays | s | betting: rays | s | batches | two-stage: rays | s | default "
                       "| saved | met (betting; default) | certified (Hoeffding; default) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---|---|"]
    for name, results in rows:
        h, b, chosen = results["hoeffding"], results["betting"], results[results["auto"].bound]
        t = results.get("two-stage")
        shown = (lambda r: f"dE00 <= {r.colour.dE00_radius:.3f}" if r.colour is not None
                 else f"+-{max(v.half_width for v in r.values):.5f}")
        pooled = "— | —" if t is None else f"{t.total_rays:,} | {t.seconds:.2f}"
        lines.append(f"| {name} | {h.total_rays:,} | {h.seconds:.2f} | {b.total_rays:,} | {b.seconds:.2f} | "
                     f"{len(b.batches)} | {pooled} | {chosen.bound} | {h.total_rays / chosen.total_rays:.2f}x | "
                     f"{b.met}; {chosen.met} | {shown(h)}; {shown(chosen)} |")
    text = "\n".join(lines)
    print()
    print(text)
    if args.markdown:
        with open(args.markdown, "w") as handle:
            handle.write(text + "\n")


if __name__ == "__main__":
    main()
