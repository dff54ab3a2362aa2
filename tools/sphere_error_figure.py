"""
The figure docs/figures/sphere_error.png: the instrument error (reading − hemispherical reading of
the same rays) of the shipped spheres against the reflectance of a grey Lambertian sample,
single-beam substitution and (150 mm sphere) comparison method, with each reading's
certified interval (105,967 rays per configuration, δ = 0.01), and the sphere theory's
curve for the same sphere (``virtspec_mi.instruments.sphere.theory.instrument_reading`` with the
inputs of ``virtspec_mi.instruments.sphere.model.theory_inputs``: flat model, exact cap fractions;
the theory models no baffle, the 150 mm sphere has one).

Run: python tools/sphere_error_figure.py [--rays N] [--out docs/figures/sphere_error.png]
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np

import virtspec_mi as vm
from virtspec_mi.instruments.sphere import theory as st

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"150 mm, 8°/d (SCI)": "scenes/sphere_150mm_8d.xml", "60 mm leaf sphere": "scenes/sphere_leaf_60mm.xml"}


def grey_scene(path: str, rho: float):
    """The scene with its specimen replaced by a grey Lambertian of reflectance ``rho``."""

    text = (ROOT / path).read_text()
    text = re.sub(r'<bsdf type="[a-z_]+">.*?</bsdf>', f'<bsdf type="diffuse"><float name="reflectance" '
                  f'value="{rho}"/></bsdf>', text, flags=re.S)
    return vm.mitsuba().load_string(text)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rays", type=int, default=105_967)
    parser.add_argument("--out", default=str(ROOT / "docs/figures/sphere_error.png"))
    args = parser.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rhos = np.round(np.arange(0.05, 0.96, 0.1), 2)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    rows = []
    rows_theory = []
    for label, path in SCENES.items():
        methods = ("substitution", "comparison") if "150" in label else ("substitution",)
        for method in methods:
            errors, lows, highs = [], [], []
            for rho in rhos:
                r = vm.sphere_measure(grey_scene(path, float(rho)), rays=args.rays, method=method)
                errors.append(r.instrument_error[0])
                lows.append(r.reading_interval[0, 0] - r.hemispherical[0])
                highs.append(r.reading_interval[0, 1] - r.hemispherical[0])
                rows.append((label, method, float(rho), float(r.reading[0]), float(r.hemispherical[0]),
                             float(r.instrument_error[0])))
            line, = ax.plot(rhos, errors, "o", label=f"{label}, {method}")
            ax.fill_between(rhos, lows, highs, color=line.get_color(), alpha=0.15)
            fine = np.linspace(0.0, 1.0, 201)
            theory = st.instrument_reading(fine, **r.theory_inputs())  # r: this sphere and method
            ax.plot(fine, theory - fine, "--", color=line.get_color(), lw=1)
            for rho, error in zip(rhos, errors):
                rows_theory.append((label, method, float(rho),
                                    float(st.instrument_reading(float(rho), **r.theory_inputs())[0] - rho)))
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel("reflectance of the grey Lambertian sample (hemispherical reading)")
    ax.set_ylabel("instrument error: reading − hemispherical")
    ax.plot([], [], "k--", lw=1, label="sphere theory (flat model; no baffle)")
    ax.set_title(f"Integrating-sphere error, standard 0.99, N = {args.rays:,} per configuration; "
                 "dashed: theory", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    for row, theory in zip(rows, rows_theory):
        print("%-22s %-12s rho=%.2f reading=%.4f hemispherical=%.4f error=%+.4f" % row + " theory=%+.4f" % theory[3])


if __name__ == "__main__":
    main()
