"""
A 3-parameter ABM-B fit, 400–2500 nm, forward error ≤ 0.002 at the optimum (issue 31)
=====================================================================================

A synthetic soybean leaf (``soybean_abmb``: ABM-B at its LOPEX 0219/0220 defaults, θi = 8°,
collimated) is measured at 400–2500 nm (``--step`` nm) to μ = 0.004 with its own seed: its
reflectance and transmittance, with their certified tolerance as the measurement uncertainty,
are the "measured" spectra. :func:`virtspec_mi.fit` then fits chlorophyll a, carotenoids and the
leaf thickness to both, the forward tolerance at the optimum ``forward_mu`` = 0.002 (half the
measurement uncertainty). Printed: wall time of the fit, the estimate against the truth, the
intervals, the forward error at the optimum, the rays traced and their rate, the SIMD width,
the 1-minute load average (the machine may be shared: every figure is then slower).

Run::

    .venv/bin/python benchmarks/fit_abm.py [--step 20] [--evaluations default|24,9,3] [--bound hoeffding]
        [--workers N] [--no-confirm] [--search-wavelengths 32|0]

``--search-wavelengths 0`` searches on every fitted wavelength (the fit before issue 31's speed-up,
``search_wavelengths=None``); each progress line carries the seconds since the fit began (where
the time goes: table, search stages, estimate, confirmation). The options the checkout's
``vm.fit`` does not know (an older checkout) are left out of the call.
"""

from __future__ import annotations

import argparse
import datetime
import os
import sys
import time

import numpy as np

TRUTH = {"chlorophyll_a": 3.9775, "carotenoids": 1.1323, "thickness": 1.66e-4}
BOUNDS = {"chlorophyll_a": (1.0, 8.0), "carotenoids": (0.3, 3.0), "thickness": (1.0e-4, 3.0e-4)}


def simd_width() -> str:
    try:
        flags = open("/proc/cpuinfo").read()
    except OSError:
        return "unknown"
    return "AVX-512 (16 lanes)" if "avx512f" in flags else "AVX2 (8 lanes)" if "avx2" in flags else "unknown"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--step", type=float, default=20.0, help="wavelength step, nm")
    parser.add_argument("--evaluations", default="24,9,3",
                        help="forward readings per refinement stage, or 'default' (the fit's own)")
    parser.add_argument("--search-wavelengths", type=int, default=None,
                        help="wavelengths of the search stages (0: all; default: the fit's own)")
    parser.add_argument("--bound", default="hoeffding")
    parser.add_argument("--forward-mu", type=float, default=0.002)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--no-confirm", action="store_true", help="keep the coarse verdicts (fit(confirm=False))")
    args = parser.parse_args()
    import virtspec_mi as vm

    wavelengths = list(np.arange(400.0, 2500.0 + 1e-9, args.step))
    started = time.perf_counter()
    measured = vm.measure("soybean_abmb", wavelengths=wavelengths, mu=0.004, delta=0.01, seed=2026, progress=False)
    measuring = time.perf_counter() - started
    evaluations = None if args.evaluations == "default" else tuple(int(e) for e in args.evaluations.split(","))
    import inspect

    from virtspec_mi.applications.fitting import forward as forward_module
    from virtspec_mi.applications.fitting import inversion

    started, cpu = time.perf_counter(), time.process_time()

    def timed(progress: bool, line: str) -> None:  # each progress line with the seconds since the fit began
        if progress:
            print(f"[{time.perf_counter() - started:7.1f} s] {line}", file=sys.stderr, flush=True)

    forward_module.note = inversion.note = timed
    options = {}
    if args.search_wavelengths is not None:
        if "search_wavelengths" not in inspect.signature(vm.fit).parameters:
            raise SystemExit("--search-wavelengths: this checkout's vm.fit has no search_wavelengths")
        options["search_wavelengths"] = args.search_wavelengths or None
    result = vm.fit({"reflectance": measured, "transmittance": measured}, "soybean_abmb", BOUNDS,
                    forward_mu=args.forward_mu, evaluations=evaluations, profile_points=0, seed=1, delta=0.05,
                    bound=args.bound, workers=args.workers, confirm=not args.no_confirm, progress=True, **options)
    seconds, cpu = time.perf_counter() - started, time.process_time() - cpu
    print(f"# ABM-B 3-parameter fit ({datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
          f"{os.cpu_count()} CPUs, {simd_width()}, load {os.getloadavg()[0]:.2f}); "
          f"{len(wavelengths)} wavelengths 400-2500 nm, R and T, bound {args.bound}, evaluations {evaluations}, "
          f"confirm {not args.no_confirm}, search wavelengths {options.get('search_wavelengths', 'default')}, "
          f"vm from {os.path.dirname(vm.__file__)}")
    print(f"measured spectrum (mu 0.004): {measuring:.1f} s")
    print(result.summary())
    for i, name in enumerate(result.names):
        low, high = result.intervals[i]
        print(f"  truth {name} = {TRUTH[name]:g}: {'inside' if low <= TRUTH[name] <= high else 'OUTSIDE'} "
              f"the interval; estimate error {result.estimate[i] - TRUTH[name]:+.3g}")
    print(f"fit wall time {seconds:.1f} s, CPU time {cpu:.1f} s (both threads; on 2 idle cores the wall time is "
          f"about CPU / 2 = {cpu / 2:.1f} s); forward error at the optimum {result.forward_tolerance:.4f}; "
          f"{result.traced_rays:,} rays traced, {result.traced_rays / seconds / 1e6:.1f} M rays/s")


if __name__ == "__main__":
    main()
