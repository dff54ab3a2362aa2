"""
Reference values of the NPSG C++ ABM implementation (its runs of the soybean and corn leaves) and the tolerance
used to compare a reading with them.

Both sides are Monte Carlo estimates: the reference with ``ref_rays`` rays per entry,
printed to 3 decimals (rounding error ≤ 0.0005), ours with N rays. A comparison passes
when |ours − ref| ≤ Z·sqrt(p(1 − p)(1/N + 1/N_ref)) + 0.0005, with p the larger of the two
values (+ 0.0005, at most 0.5) so the variance is not underestimated. Z = 4.5: a
two-sided normal tail of 6.8e-6 per comparison, so at most 1e-3 false-failure
probability over the 140 comparisons of the soybean tables (3e-4 over corn's 44).
"""

from __future__ import annotations

import numpy as np

Z = 4.5
ROUNDING = 0.0005

SOYBEAN_WAVELENGTHS = (465, 551, 608, 680, 800, 1450, 2200)
SOYBEAN_COLUMNS = ("0", "8", "45", "60", "abax 8")  # incidence; "abax 8" = abaxial side, 8 deg
SOYBEAN_RAYS = 1_000_000
# the NPSG C++ reference runs (soybean), R / T per wavelength (rows) and column, sieve & detour ON / OFF.
SOYBEAN = {
    True: [
        [(0.045, 0.007), (0.045, 0.007), (0.061, 0.006), (0.104, 0.006), (0.216, 0.011)],
        [(0.100, 0.125), (0.101, 0.125), (0.116, 0.115), (0.156, 0.108), (0.236, 0.151)],
        [(0.065, 0.072), (0.065, 0.072), (0.080, 0.067), (0.121, 0.061), (0.218, 0.090)],
        [(0.043, 0.018), (0.043, 0.018), (0.056, 0.016), (0.098, 0.015), (0.207, 0.026)],
        [(0.485, 0.479), (0.484, 0.480), (0.503, 0.461), (0.529, 0.436), (0.423, 0.549)],
        [(0.187, 0.238), (0.187, 0.238), (0.201, 0.223), (0.236, 0.208), (0.263, 0.277)],
        [(0.221, 0.288), (0.221, 0.288), (0.235, 0.270), (0.268, 0.253), (0.271, 0.331)],
    ],
    False: [
        [(0.045, 0.018), (0.045, 0.017), (0.060, 0.016), (0.103, 0.015), (0.216, 0.015)],
        [(0.076, 0.148), (0.076, 0.147), (0.089, 0.135), (0.129, 0.124), (0.231, 0.145)],
        [(0.054, 0.101), (0.054, 0.101), (0.068, 0.092), (0.109, 0.084), (0.216, 0.096)],
        [(0.041, 0.037), (0.041, 0.037), (0.055, 0.034), (0.096, 0.031), (0.206, 0.032)],
        [(0.442, 0.456), (0.442, 0.455), (0.458, 0.435), (0.486, 0.410), (0.404, 0.518)],
        [(0.129, 0.233), (0.129, 0.233), (0.139, 0.215), (0.174, 0.199), (0.244, 0.243)],
        [(0.152, 0.271), (0.153, 0.270), (0.160, 0.249), (0.192, 0.230), (0.242, 0.286)],
    ],
}

CORN_WAVELENGTHS = (450, 550, 600, 680, 700, 800, 1200, 1450, 1650, 1940, 2200)
CORN_RAYS = 100_000
# the NPSG C++ reference runs (corn), C++ reference at 8 deg, R / T, sieve & detour ON / OFF.
CORN = {
    True: [(0.069, 0.002), (0.135, 0.087), (0.106, 0.044), (0.071, 0.006), (0.130, 0.086), (0.451, 0.502),
           (0.424, 0.475), (0.163, 0.149), (0.327, 0.377), (0.070, 0.014), (0.189, 0.210)],
    False: [(0.061, 0.005), (0.110, 0.106), (0.086, 0.064), (0.063, 0.014), (0.106, 0.104), (0.420, 0.469),
            (0.372, 0.432), (0.131, 0.161), (0.262, 0.337), (0.059, 0.027), (0.152, 0.208)],
}


def tolerance(ours: np.ndarray, ref: np.ndarray, rays: int, ref_rays: int) -> np.ndarray:
    """Combined Monte Carlo tolerance of the module docstring (elementwise)."""

    p = np.minimum(np.maximum(ours, ref) + ROUNDING, 0.5)
    return Z * np.sqrt(p * (1 - p) * (1.0 / rays + 1.0 / ref_rays)) + ROUNDING


def mismatches(ours: np.ndarray, ref: np.ndarray, rays: int, ref_rays: int) -> list[str]:
    """Human-readable list of the entries outside the tolerance (empty when all pass)."""

    ours, ref = np.asarray(ours, dtype=float), np.asarray(ref, dtype=float)
    tol = tolerance(ours, ref, rays, ref_rays)
    bad = np.abs(ours - ref) > tol
    return [f"entry {idx}: ours {ours[idx]:.4f} ref {ref[idx]:.3f} tol {tol[idx]:.4f}"
            for idx in zip(*np.nonzero(bad))]
