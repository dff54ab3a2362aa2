"""
Counts pinned across refactors: every shipped scene and a set of settings, bit for bit.

The cases below cover every beam, sampling, ray budget (two-stage and joint included),
wavelength-independent and spectral specimens, random walks, Mitsuba built-ins with
mixed delta lobes, multi-chunk sweeps and ``mi.render``. Their counts were recorded by
``python tests/test_pinned_counts.py --write`` before the core was reshaped (issue
"One result, one engine, one set of settings") and must never change: a refactor that
moves code keeps every ray's random numbers and fate.
"""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm

ROOT = Path(__file__).resolve().parents[1]
PINNED = Path(__file__).with_name("data") / "pinned_counts.json"
SCENES = ROOT / "scenes"

_DIFFUSE = {"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 400, "wavelength_max": 700,
                                               "values": "0.1, 0.5, 0.9"}}
CASES: dict[str, tuple[str, dict]] = {
    "diamond_conical_default": ("measure", {"scene": "diamond_conical.xml"}),
    "diamond_conical_backlit": ("measure", {"scene": "diamond_conical.xml", "theta_i": 88, "sampling": "random",
                                            "seed": 3, "rays": 50_000}),
    "diamond_conical_concentric_joint_two_stage": ("measure", {"scene": "diamond_conical.xml", "theta_i": 45,
                                                               "sampling": "concentric", "joint": True,
                                                               "bound": "two-stage", "seed": 5}),
    "diamond_collimated_exact": ("measure", {"scene": "diamond_collimated.xml", "theta_i": 30, "bound": "exact"}),
    "diamond_collimated_two_stage_spectral": ("measure", {"scene": "diamond_collimated.xml", "theta_i": 60,
                                                          "bound": "two-stage", "wavelengths": [450, 550, 650]}),
    "mcml_slab_collimated": ("measure", {"scene": "mcml_slab.xml", "rays": 20_000, "seed": 1}),
    "mcml_slab_diffuse": ("measure", {"scene": "mcml_slab.xml", "beam": "diffuse", "rays": 20_000}),
    "soybean": ("measure", {"scene": "soybean_abmb.xml", "wavelengths": [465, 800, 1450], "rays": 20_000}),
    "corn": ("measure", {"scene": "corn_abmu.xml", "wavelengths": [551, 800], "rays": 20_000, "seed": 9}),
    "roughconductor": ("measure", {"bsdf": {"type": "roughconductor", "alpha": 0.3}, "theta_i": 45,
                                   "rays": 20_000}),
    "plastic_spectral": ("measure", {"bsdf": {"type": "plastic"}, "theta_i": 30, "rays": 20_000,
                                     "wavelengths": [450, 600], "beam": "collimated"}),
    "principled_coloured": ("measure", {"bsdf": {"type": "principled", "base_color": {"type": "rgb",
                                                                                       "value": [0.9, 0.2, 0.1]}},
                                        "theta_i": 20, "rays": 20_000, "wavelengths": [450, 650]}),
    "diffuse_sweep_chunks": ("sweep", {"bsdf": _DIFFUSE, "theta_i": [0, 40, 80], "wavelengths": [400, 550, 700],
                                       "rays": 5_000, "chunk_size": 4096, "seed": 11}),
    "diamond_sweep_two_stage": ("sweep", {"scene": "diamond_collimated.xml", "theta_i": "0:90:30",
                                          "bound": "two-stage"}),
    "slab_sweep_diffuse_beam": ("sweep", {"scene": "mcml_slab.xml", "theta_i": [0], "beam": "diffuse",
                                          "rays": 10_000, "seed": 2}),
    "render_spp": ("render", {"scene": "diamond_conical.xml", "spp": 1000, "seed": 2}),
}

FIELDS = ("rays", "reflected", "transmitted", "capped", "specular_reflected", "regular_transmitted", "pilot_rays")


def run_case(kind: str, spec: dict) -> dict[str, list]:
    """Counts of one case by field name (nested lists; ``None`` where a field is absent)."""

    spec = dict(spec)
    scene = str(SCENES / spec.pop("scene")) if "scene" in spec else vm.instrument_scene(spec.pop("bsdf"))
    if kind == "render":
        mi = vm.mitsuba()
        loaded = mi.load_file(scene)
        mi.render(loaded, seed=spec["seed"], spp=spec["spp"])
        result = loaded.integrator().last_reading
    elif kind == "sweep":
        result = vm.sweep(scene, progress=False, **spec)
    else:
        result = vm.measure(scene, **spec)
    counts = {}
    for name in FIELDS:
        value = getattr(result, name, None)
        counts[name] = None if value is None else np.asarray(value, dtype=np.int64).tolist()
    return counts


@pytest.mark.parametrize("case", sorted(CASES))
def test_counts_are_pinned(case: str) -> None:
    pinned = json.loads(PINNED.read_text())[case]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the built-ins with weights > 1 warn; their counts are pinned too
        counts = run_case(*CASES[case])
    for name, value in pinned.items():
        if value is not None:
            assert counts[name] == value, f"{case}: {name} changed"


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python tests/test_pinned_counts.py --write   (records the current counts)")
    import os

    os.environ.setdefault("VIRTSPEC_LEAF_DATA", str(ROOT.parent / "shared" / "data" / "abm-npsg"))
    warnings.simplefilter("ignore")
    PINNED.parent.mkdir(exist_ok=True)
    PINNED.write_text(json.dumps({case: run_case(*CASES[case]) for case in sorted(CASES)}, indent=1) + "\n")
    print(f"wrote {PINNED}")
