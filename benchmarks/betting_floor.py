"""
The most a variance-adaptive certificate can save on a linear target (issue 39)
===============================================================================

Issue 39 asks every certified target to take at least 2× fewer rays than Hoeffding's
route. For a linear target L = Σₖ wₖ pₖ this script computes the ceiling on that
ratio that **no** valid interval can pass, from the specimen's own spectrum: the
Gaussian oracle, which knows every stratum's variance σₖ² = pₖ(1 − pₖ) in advance,
allocates rays by Neyman's rule and uses the normal interval at δ/m per statement
(m functionals, Bonferroni, as the targets do):

    N_oracle = z² (Σₖ |wₖ| σₖ)² / t²,   z = Φ⁻¹(1 − δ/(2m)),

against Hoeffding's N = (Σₖ |wₖ|)² ln(2m/δ) / (2 t²) (the route's eq. (1)). Exact
binomial intervals (Clopper–Pearson) need about as many rays as the oracle at these
counts, and a confidence sequence valid at every batch needs more, so the oracle's
ratio is an upper bound on the gain of any certificate. Functionals on disjoint
wavelengths (B04 and B08) add their rays; otherwise the largest counts.

The spectrum is the shipped soybean leaf's (``soybean_abmb``, collimated, θi = 8°),
measured at the functionals' wavelengths with 10⁵ rays each (its error moves σₖ by
< 0.3 %).

Run::

    PYTHONPATH=$PWD .venv/bin/python benchmarks/betting_floor.py

References
----------
Neyman, J. (1934). On the two different aspects of the representative method.
*J. R. Stat. Soc.* 97(4), 558–625 (the allocation nₖ ∝ |wₖ| σₖ).
Hoeffding, W. (1963). Probability inequalities for sums of bounded random variables.
*J. Am. Stat. Assoc.* 58(301), 13–30 (Theorem 2).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import norm

import virtspec_mi as vm

DELTA = 0.01
TOLERANCE = 0.002


def spectrum(functionals, scene) -> dict[str, np.ndarray]:
    """p of each functional's quantity at its wavelengths (absorptance = 1 − ρ − τ)."""

    wavelengths = np.unique(np.concatenate([f.wavelengths for f in functionals]))
    result = vm.measure(scene, wavelengths=wavelengths, rays=100_000, theta_i=8.0, beam="collimated", seed=0)
    rho, tau = np.ravel(result.reflectance), np.ravel(result.transmittance)
    looked = {"reflectance": rho, "transmittance": tau, "absorptance": 1.0 - rho - tau}
    return {f.name: np.interp(f.wavelengths, wavelengths, looked[f.quantity]) for f in functionals}


def rays(functionals, p: dict[str, np.ndarray]) -> tuple[float, float]:
    """(Hoeffding's rays, the Gaussian oracle's rays) for every functional within ±TOLERANCE at once."""

    m = len(functionals)
    z = norm.ppf(1 - DELTA / (2 * m))
    hoeffding = [f.total_weight ** 2 * math.log(2 * m / DELTA) / (2 * TOLERANCE ** 2) for f in functionals]
    oracle = [z ** 2 * float(np.sum(np.abs(f.weights) * np.sqrt(p[f.name] * (1 - p[f.name])))) ** 2 / TOLERANCE ** 2
              for f in functionals]
    disjoint = len(np.concatenate([f.wavelengths for f in functionals])) == \
        len(np.unique(np.concatenate([f.wavelengths for f in functionals])))
    combine = sum if disjoint else max
    return combine(hoeffding), combine(oracle)


def main() -> None:
    scene = vm.scenes.path("soybean_abmb")
    targets = [("S2 B04", vm.band("B04", tolerance=TOLERANCE)), ("S2 B08", vm.band("B08", tolerance=TOLERANCE)),
               ("S2 B04 & B08", vm.band("B04", "B08", tolerance=TOLERANCE)), ("fAPAR", vm.fapar(tolerance=TOLERANCE))]
    print(f"soybean_abmb, collimated 8 deg, delta = {DELTA}, tolerance +-{TOLERANCE}\n")
    print("| target | mean p (rays-weighted) | Hoeffding: rays | Gaussian oracle: rays | most any certificate saves |")
    print("|---|---:|---:|---:|---:|")
    for name, target in targets:
        functionals = target.functionals()
        p = spectrum(functionals, scene)
        hoeffding, oracle = rays(functionals, p)
        mean = np.mean([float(np.dot(np.abs(f.weights), p[f.name]) / f.total_weight) for f in functionals])
        print(f"| {name} | {mean:.3f} | {hoeffding:,.0f} | {oracle:,.0f} | {hoeffding / oracle:.2f}x |")


if __name__ == "__main__":
    main()
