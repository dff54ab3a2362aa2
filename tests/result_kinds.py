"""
Results of every kind for the tests of :mod:`virtspec_mi.results` (``tests/results/``):
made from counts (no tracing) where the labels matter, traced (a few hundred rays) where
the kind's own machinery does.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import virtspec_mi as vm
from virtspec_mi.instruments.goniophotometer.bins import make_bins
from virtspec_mi.kernel.counts import Counts

WAVELENGTHS = [400.0, 550.0, 700.0]
ANGLES = [0.0, 30.0, 60.0]
THICKNESS = [1.0e-4, 2.0e-4]
ROUGH = {"type": "roughdielectric", "alpha": 0.3}


def hemispherical_grid(seed: int = 0) -> vm.Result:
    """A parameter sweep over (wavelength, theta_i, specimen.thickness): random exact counts of 10^4 rays."""

    rng = np.random.default_rng(seed)
    shape = (len(WAVELENGTHS), len(ANGLES), len(THICKNESS))
    reflected = rng.integers(1000, 5000, shape)
    counts = replace(Counts.zeros(shape), rays=np.full(shape, 10**4, dtype=np.int64), reflected=reflected,
                     transmitted=rng.integers(0, 4000, shape), specular_reflected=reflected // 4)
    parameters = {"names": ["specimen.thickness"], "keys": ["specimen.thickness.value"], "points": False,
                  "values": [THICKNESS]}
    return vm.Result(("wavelength", "theta_i", "specimen.thickness"),
                     {"wavelength": np.array(WAVELENGTHS), "theta_i": np.array(ANGLES),
                      "specimen.thickness": np.array(THICKNESS)},
                     counts, None, vm.Settings(wavelengths=WAVELENGTHS), vm.InstrumentGeometry(8, 12.5, 100), 1.0,
                     scene="sha256:0123456789abcdef", parameters=parameters,
                     source={"scene": "soybean_abmb", "defines": {"seed": "3", "side": "abaxial"}})


def sphere_grid(seed: int = 0) -> vm.SphereResult:
    """
    A sphere result over (wavelength, theta_i, point) from random counts, each configuration
    with its own N per reading (as a budget sized per configuration would give).
    """

    rng = np.random.default_rng(seed)
    shape = (len(WAVELENGTHS), 2, 2)
    counts = {}
    for configuration, rays in (("sample", np.full(shape, 20_000)), ("standard", rng.integers(15_000, 25_000, shape))):
        detected = rng.integers(4000, 8000, shape)
        reflected = rng.integers(8000, 10_000, shape)
        zeros = np.zeros(shape, dtype=np.int64)
        counts[configuration] = {
            "rays": rays.astype(np.int64), "detected": detected, "absorbed_wall": rays - detected - 200,
            "absorbed_specimen": zeros + 100, "absorbed_other": zeros, "capped": zeros, "invalid_directions": zeros,
            "lost_entrance": zeros + 100, "hemispherical_reflected": reflected,
            "hemispherical_specular": reflected // 10, "hemispherical_transmitted": zeros,
            "detected_from_upper": detected // 2, "wall_reflections": rays * 30, "weight_violations": zeros,
            "rounded_weights": zeros}
    parameters = {"names": ["specimen.reflectance"], "keys": ["specimen.reflectance.value"], "points": True,
                  "values": [[0.3, 0.6]]}
    return vm.SphereResult(
        dims=("wavelength", "theta_i", "point"),
        coords={"wavelength": np.array(WAVELENGTHS), "theta_i": np.array([8.0, 10.0]), "point": np.arange(2),
                "specimen.reflectance": np.array([0.3, 0.6])},
        counts=counts, wall_reflectance=np.broadcast_to(np.array([0.97, 0.98, 0.99])[:, None, None], shape).copy(),
        sphere="150 mm sphere, 4 ports", cap_fractions={"sample": 0.007, "entrance": 0.003},
        options={"measurement": "reflectance", "specular": "SCI", "method": "substitution", "standard": 0.99,
                 "max_bounces": 100_000},
        settings=vm.Settings(wavelengths=WAVELENGTHS, theta_i=8, beam="collimated"), seconds=0.5,
        scene="sha256:fedcba9876543210", specimen_radius=12.7, parameters=parameters,
        source={"scene": "my_sphere.xml", "defines": {}})


def gonio_reading() -> vm.GonioResult:
    """A goniophotometer reading of a rough dielectric over 3 wavelengths x 2 theta_i, 3 x 2 bins."""

    scene = vm.mitsuba().load_dict(vm.instrument_scene(ROUGH))
    return vm.gonio(scene, theta_i=[10, 50], wavelengths=WAVELENGTHS, theta_o_bins=3, phi_o_bins=2, rays=600)


def sphere_reading() -> vm.SphereResult:
    """The 150 mm 8°/d sphere reading its grey specimen at 3 wavelengths (a few hundred rays)."""

    return vm.sphere_measure("scenes/sphere_150mm_8d.xml", rays=800, wavelengths="400, 550, 700")


def gonio_from_counts(seed: int = 0) -> vm.GonioResult:
    """A goniophotometer reading over 3 wavelengths x 2 theta_i, 2 x 3 bins, from random exact counts."""

    rng = np.random.default_rng(seed)
    shape = (len(WAVELENGTHS), 2)
    rays = np.full(shape, 5000, dtype=np.int64)
    reflected, transmitted = rng.integers(500, 2000, shape), rng.integers(500, 2000, shape)
    counts = Counts.zeros(shape)
    counts = Counts(**{**{n: getattr(counts, n) for n in Counts.names()}, "rays": rays, "reflected": reflected,
                       "transmitted": transmitted, "specular_reflected": reflected // 3})
    result = vm.Result(("wavelength", "theta_i"), {"wavelength": np.array(WAVELENGTHS), "theta_i": np.array([10., 50.])},
                       counts, None, vm.Settings(wavelengths=WAVELENGTHS, rays=5000), vm.InstrumentGeometry(8, 12.5, 100),
                       0.25, scene="sha256:0123")
    bins = make_bins(1, 3)  # one theta_o bin per hemisphere, 3 phi_o bins
    bin_counts = np.zeros((*shape, 2, 3), dtype=np.int64)
    bin_counts[..., 0, :] = np.stack([reflected // 3, reflected // 3, reflected - 2 * (reflected // 3)], axis=-1)
    bin_counts[..., 1, :] = np.stack([transmitted // 3, transmitted // 3, transmitted // 3], axis=-1)
    return vm.GonioResult(result=result, bin_counts=bin_counts, bins=bins, guarantee="union")


def counts(data: dict) -> dict:
    """The exact counts of a result's ``as_dict()``, whatever its kind."""

    if data["format"].startswith("virtspec-mi gonio"):
        return {"bin_counts": data["bin_counts"], **counts(data["result"])}
    if data["format"].startswith("virtspec-mi sphere"):
        return data["counts"]
    return {name: data[name] for name in ("rays", "reflected", "transmitted", "absorbed", "capped")}
