"""
How close Mitsuba's ``measured`` plugin, on a goniophotometer reading exported as an RGL
``.bsdf``, comes to the specimen itself: a rough conductor (Mitsuba's ``roughconductor``,
GGX, α = 0.3) measured on the file's grid (``binning="rgl"``) at θi = 20, 40, 60° with
n = 16, 32 and 64 nodes per axis (2·10⁶ rays per reading), both BSDFs evaluated at 20,000
random outgoing directions at θi = 40°, 550 nm. Prints the relative difference where f·cos θo exceeds 10 % of its peak,
and both hemispherical integrals (2π × the mean of f·cos θo over uniform directions).

Run: ``python tools/rgl_fidelity.py`` (seconds).

References
----------
Dupuy & Jakob (2018), ACM Trans. Graph. 37(6), 274; Walter et al. (2007), EGSR (GGX).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

import virtspec_mi as vm

SPECIMEN = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3}


def main() -> None:
    readings = {n: vm.gonio(vm.instrument_scene(SPECIMEN), theta_i=[20, 40, 60], wavelengths=[550], rays=2_000_000,
                            binning="rgl", rgl_resolution=n, beam="collimated", seed=1) for n in (16, 32, 64)}
    mi = vm.mitsuba()
    specimen = mi.load_dict(SPECIMEN)
    rng = np.random.default_rng(0)
    k, theta_i = 20_000, np.radians(40.0)
    wo = rng.normal(size=(k, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1)[:, None]
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(np.full(k, np.sin(theta_i)), np.zeros(k), np.full(k, np.cos(theta_i)))
    si.wavelengths = mi.Spectrum(*([mi.Float(np.full(k, 550.0))] * 4))
    directions = mi.Vector3f(wo[:, 0], wo[:, 1], wo[:, 2])
    truth = np.array(specimen.eval(mi.BSDFContext(), si, directions)[0])
    peak = truth > 0.1 * truth.max()
    with tempfile.TemporaryDirectory() as work:
        for n in (16, 32, 64):
            path = Path(work) / f"rough{n}.bsdf"
            readings[n].to_rgl(path)
            measured = mi.load_dict({"type": "measured", "filename": str(path)})
            got = np.array(measured.eval(mi.BSDFContext(), si, directions)[0])
            relative = np.abs(got - truth)[peak] / truth[peak]
            print(f"n = {n}: |measured - specimen| / specimen where f cos > 10 % of its peak: median "
                  f"{np.median(relative):.3f}, 90th percentile {np.percentile(relative, 90):.3f}; hemispherical "
                  f"integral {2 * np.pi * got.mean():.4f} (specimen {2 * np.pi * truth.mean():.4f})")


if __name__ == "__main__":
    main()
