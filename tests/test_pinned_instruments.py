"""
Counts of the goniophotometer and the integrating sphere pinned across refactors, bit for bit.

The sphere cases cover both shipped spheres (150 mm 8°/d SCI and SCE, the 60 mm leaf
sphere's reflectance and transmittance), the comparison method, several wavelengths and
a chunk size that splits a reading; the goniophotometer cases a random-walk leaf on
queued lanes, the wavelength-independent diamond at several θi (one wavelength) and at
several wavelengths (one θi), a Mitsuba built-in with projected, folded and given-edge
bins, and a chunk size that splits a reading. Their counts were recorded by
``python tests/test_pinned_instruments.py --write`` before the kernel took plain values
and the engine ran every instrument (issue 21) and must never change: a refactor keeps
every ray's random numbers and fate. (A goniophotometer reading of a wavelength-
independent specimen at several wavelengths *and* several θi is not pinned: keyed
readings number those rays differently, as the issue allows.)

Counts are bit-identical on one SIMD instruction set, whatever the chunks, threads and
workers; across instruction sets a ray may move to a neighbouring bin. Mitsuba's direction
arithmetic (``dr.normalize``, ``dr.rsqrt``) uses the processor's approximate reciprocal
square root refined by one Newton step, whose last bit differs between AVX2 (``vrsqrtps``)
and AVX-512 (``vrsqrt14ps``); a direction within an ulp of a bin edge is then binned
differently (one ray of 80,000 in ``gonio_rough_projected_folded``). The pins were recorded
on AVX2; :data:`PINNED_BY_ISA` holds, per instruction set, the counts that differ from
them, recorded by ``python tests/test_pinned_instruments.py --write-isa``.
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
PINNED = Path(__file__).with_name("data") / "pinned_instruments.json"
PINNED_BY_ISA = Path(__file__).with_name("data") / "pinned_instruments_by_isa.json"
SCENES = ROOT / "scenes"

_ROUGH = {"type": "roughconductor", "alpha": 0.3}
CASES: dict[str, tuple[str, dict]] = {
    "sphere_150mm_sci_chunks": ("sphere", {"scene": "sphere_150mm_8d.xml", "rays": 5000,
                                           "wavelengths": "450, 550, 650", "chunk_size": 1024}),
    "sphere_150mm_sce": ("sphere", {"scene": "sphere_150mm_8d.xml", "specular": "SCE", "rays": 3000,
                                    "wavelengths": "500, 600", "seed": 4}),
    "sphere_150mm_comparison": ("sphere", {"scene": "sphere_150mm_8d.xml", "method": "comparison",
                                           "rays": 3000, "wavelengths": "550"}),
    "sphere_leaf_reflectance": ("sphere", {"scene": "sphere_leaf_60mm.xml", "rays": 3000,
                                           "wavelengths": "465, 800, 1450"}),
    "sphere_leaf_transmittance": ("sphere", {"scene": "sphere_leaf_60mm.xml", "measurement": "transmittance",
                                             "rays": 3000, "wavelengths": "465, 800", "chunk_size": 2048}),
    "gonio_leaf_queued": ("gonio", {"scene": "soybean_abmb.xml", "theta_i": [0, 45], "wavelengths": [465, 800],
                                    "rays": 3000, "theta_o_bins": 9, "phi_o_bins": 12}),
    "gonio_diamond_angles": ("gonio", {"scene": "diamond_conical.xml", "theta_i": [0, 30, 60], "rays": 20_000,
                                       "theta_o_bins": 18, "phi_o_bins": 36}),
    "gonio_diamond_spectral": ("gonio", {"scene": "diamond_collimated.xml", "theta_i": [30],
                                         "wavelengths": [450, 650], "rays": 10_000, "theta_o_bins": 6,
                                         "phi_o_bins": 8}),
    "gonio_rough_projected_folded": ("gonio", {"bsdf": _ROUGH, "theta_i": [20, 50], "wavelengths": [500, 600],
                                               "rays": 20_000, "binning": "projected", "fold_phi": True,
                                               "theta_o_bins": 10, "phi_o_bins": 9, "chunk_size": 4096}),
    "gonio_rough_edges": ("gonio", {"bsdf": _ROUGH, "theta_i": [40], "rays": 20_000,
                                    "theta_o_bins": "0, 10, 30, 60, 90, 120, 180",
                                    "phi_o_bins": "0, 45, 170, 190, 300, 360", "seed": 7}),
}


def run_case(kind: str, spec: dict) -> dict[str, list]:
    """Every count of one case by name (nested lists)."""

    spec = dict(spec)
    scene = str(SCENES / spec.pop("scene")) if "scene" in spec else vm.instrument_scene(spec.pop("bsdf"))
    if kind == "sphere":
        result = vm.sphere_measure(scene, **spec)
        return {f"{config}.{name}": np.asarray(values, dtype=np.int64).tolist()
                for config, counts in sorted(result.counts.items()) for name, values in sorted(counts.items())}
    result = vm.gonio(scene, **spec)
    counts = {name: np.asarray(getattr(result.result, name), dtype=np.int64).tolist()
              for name in ("rays", "reflected", "transmitted", "capped", "specular_reflected", "regular_transmitted")}
    counts["bin_counts"] = np.asarray(result.bin_counts, dtype=np.int64).tolist()
    return counts


def simd_isa() -> str:
    """The widest SIMD instruction set Dr.Jit's LLVM backend uses here: ``"avx512"`` or ``"avx2"``."""

    flags = Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").exists() else ""
    return "avx512" if "avx512f" in flags.split() else "avx2"


def pinned_counts(case: str) -> dict[str, list]:
    """The pinned counts of ``case`` on this machine's instruction set (:data:`PINNED_BY_ISA` over :data:`PINNED`)."""

    by_isa = json.loads(PINNED_BY_ISA.read_text()).get(simd_isa(), {}) if PINNED_BY_ISA.exists() else {}
    return {**json.loads(PINNED.read_text())[case], **by_isa.get(case, {})}


def test_instruction_set_pins_differ_from_the_recorded_pins_by_a_few_rays_only() -> None:
    """An instruction set's own pins move at most a few rays between bins: the same rays, the same fates."""

    pinned = json.loads(PINNED.read_text())
    for isa, cases in json.loads(PINNED_BY_ISA.read_text()).items():
        for case, counts in cases.items():
            assert set(counts) == {"bin_counts"}, f"{isa} {case}: only bins may differ between instruction sets"
            own, base = np.asarray(counts["bin_counts"]), np.asarray(pinned[case]["bin_counts"])
            assert own.sum() == base.sum() and 0 < np.abs(own - base).sum() <= 10, f"{isa} {case}"


@pytest.mark.parametrize("case", sorted(CASES))
def test_instrument_counts_are_pinned(case: str) -> None:
    pinned = pinned_counts(case)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        counts = run_case(*CASES[case])
    # every pinned name is still counted; a sphere result now also names each configuration's N ("….rays")
    extra = sorted(set(counts) - set(pinned))
    assert set(pinned) <= set(counts) and all(name.endswith(".rays") for name in extra), f"{case}: names changed"
    for name, value in pinned.items():
        assert counts[name] == value, f"{case}: {name} changed"


if __name__ == "__main__":
    if sys.argv[1:] not in (["--write"], ["--write-isa"]):
        sys.exit("usage: python tests/test_pinned_instruments.py --write       (records the current counts)\n"
                 "       python tests/test_pinned_instruments.py --write-isa   (records this instruction set's "
                 "differences)")
    warnings.simplefilter("ignore")
    current = {case: run_case(*CASES[case]) for case in sorted(CASES)}
    if sys.argv[1] == "--write":
        PINNED.parent.mkdir(exist_ok=True)
        PINNED.write_text(json.dumps(current) + "\n")
        print(f"wrote {PINNED}")
    else:
        recorded = json.loads(PINNED.read_text())
        differences = {case: {name: value for name, value in counts.items() if recorded[case].get(name) != value}
                       for case, counts in current.items()}
        by_isa = json.loads(PINNED_BY_ISA.read_text()) if PINNED_BY_ISA.exists() else {}
        by_isa[simd_isa()] = {case: names for case, names in differences.items() if names}
        PINNED_BY_ISA.write_text(json.dumps(by_isa, sort_keys=True) + "\n")
        print(f"wrote {PINNED_BY_ISA} ({simd_isa()}: {sorted(by_isa[simd_isa()])})")
