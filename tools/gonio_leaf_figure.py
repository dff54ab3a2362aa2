"""
The figures docs/figures/gonio_leaf.png and docs/figures/gonio_leaf_series.png: a goniophotometer
reading of the soybean leaf (``abm_b``, NPSG data in ``$VIRTSPEC_LEAF_DATA``), collimated
beam at θi = 0, 30, 60°, 551 nm, 2 × 9 θo bins × 12 folded φo bins (K = 216), N sized by
the union bound at μ = 0.01, δ = 0.01 (53,368 rays per reading), seed 0 — the manual's
reading. ``gonio_leaf.png`` is ``GonioResult.plot`` (polar, log scale: f in the plane of
incidence and across it with the certified band); ``gonio_leaf_series.png`` is
:func:`virtspec_mi.instruments.goniophotometer.plot.plot_series` (the distribution over θi as a series). The
reading's summary is printed.

Run: VIRTSPEC_LEAF_DATA=DIR python tools/gonio_leaf_figure.py [--out-dir docs/figures], DIR holding the
NPSG data files (the ``data/`` folder of github.com/turtlesoupy/ABM-U-and-ABM-B-CPP, BSD-3).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import virtspec_mi as vm
from virtspec_mi.instruments.goniophotometer.plot import plot_series

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "figures")
    args = parser.parse_args()
    leaf = vm.instrument_scene({"type": "abm_b"})
    reading = vm.gonio(leaf, theta_i=[0, 30, 60], beam="collimated", wavelengths=[551],
                       theta_o_bins=9, phi_o_bins=12, fold_phi=True, mu=0.01)
    print(reading.summary())
    reading.plot(args.out_dir / "gonio_leaf.png", log=True)
    plot_series(reading, args.out_dir / "gonio_leaf_series.png")
    print(f"wrote {args.out_dir / 'gonio_leaf.png'} and {args.out_dir / 'gonio_leaf_series.png'}")


if __name__ == "__main__":
    main()
