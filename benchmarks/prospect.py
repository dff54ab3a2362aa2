"""
PROSPECT-D forward spectra per second: virtspec-mi's NumPy model against ``prosail`` (issue 31)
==============================================================================================

Both compute PROSPECT-D (Féret et al. 2017) at 400–2500 nm, 1 nm (2101 wavelengths) from the
same numbers (``prosail``'s ``prospect_d_spectra.txt``, which virtspec-mi's shipped table copies), side
by side in one run, one thread each (``OMP_NUM_THREADS=1``):

1. **prosail** — ``prosail.run_prospect`` called once per leaf (its API: one leaf per call);
2. **virtspec-mi, one leaf per call** — :func:`virtspec_mi.plugins.bsdfs.prospect_model.prospect_d`;
3. **virtspec-mi, vectorised** — one call for all the leaves (arrays of parameters).

Each is the best of 3 runs over the same random leaves (Cab 10–80, Cm 0.002–0.02, N 1.2–2.5),
after checking that the spectra agree to 1e-12. The 1-minute load average is printed: the
machine may be shared, which slows every figure (ratios, measured side by side, suffer less).

Run::

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/prospect.py [--leaves 2000]
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import time

import numpy as np


def best_of(runs: int, work) -> float:
    times = []
    for _ in range(runs):
        started = time.perf_counter()
        work()
        times.append(time.perf_counter() - started)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--leaves", type=int, default=2000)
    args = parser.parse_args()
    import prosail

    from virtspec_mi.plugins.bsdfs.prospect_model import prospect_coefficients, prospect_d

    rng = np.random.default_rng(31)
    n = args.leaves
    leaves = {"N": rng.uniform(1.2, 2.5, n), "Cab": rng.uniform(10, 80, n), "Car": rng.uniform(2, 15, n),
              "Cw": rng.uniform(0.005, 0.03, n), "Cm": rng.uniform(0.002, 0.02, n), "Anth": rng.uniform(0, 5, n)}
    data = prospect_coefficients()
    batch_r, batch_t = prospect_d(coefficients=data, **leaves)
    for i in range(0, n, max(1, n // 10)):
        _, r, t = prosail.run_prospect(leaves["N"][i], leaves["Cab"][i], leaves["Car"][i], 0.0, leaves["Cw"][i],
                                       leaves["Cm"][i], ant=leaves["Anth"][i])
        assert np.abs(r - batch_r[i]).max() < 1e-12 and np.abs(t - batch_t[i]).max() < 1e-12

    def with_prosail():
        for i in range(n):
            prosail.run_prospect(leaves["N"][i], leaves["Cab"][i], leaves["Car"][i], 0.0, leaves["Cw"][i],
                                 leaves["Cm"][i], ant=leaves["Anth"][i])

    def one_by_one():
        for i in range(n):
            prospect_d(coefficients=data, **{k: v[i] for k, v in leaves.items()})

    def vectorised():
        prospect_d(coefficients=data, **leaves)

    figures = {name: n / best_of(3, work) for name, work in
               (("prosail run_prospect", with_prosail), ("virtspec-mi one leaf per call", one_by_one),
                ("virtspec-mi vectorised", vectorised))}
    print(f"# PROSPECT-D spectra per second, 2101 wavelengths, {n} leaves, best of 3 "
          f"({datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {platform.processor() or 'cpu'}, "
          f"load {os.getloadavg()[0]:.2f}, OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')})")
    reference = figures["prosail run_prospect"]
    for name, rate in figures.items():
        print(f"{name:32} {rate:10,.0f} spectra/s  {rate / reference:5.2f}x prosail")


if __name__ == "__main__":
    main()
