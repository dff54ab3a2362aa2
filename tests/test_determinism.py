"""
Determinism of the goniophotometer and the integrating sphere (issue 22, item 6): their
counts — every fate, every bin, every sum — do not depend on how the rays are cut into
kernel chunks (``chunk_size``, and the time-bounded chunk sizes of
:class:`virtspec_mi.kernel.tracer._Pace`, here forced to arbitrary sequences), nor on the
number of Dr.Jit threads. In-process vs two Dask workers: ``tests/runtime/test_scaleout.py``
(``test_a_goniophotometer_reading_and_a_sphere_spectrum_on_two_workers_are_bit_identical``,
slow; its workers run one Dr.Jit thread each).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.kernel import tracer

ROOT = Path(__file__).resolve().parents[1]
SPHERE = str(ROOT / "scenes" / "sphere_150mm_8d.xml")


def _gonio(scene: dict, **extra) -> vm.GonioResult:
    return vm.gonio(scene, theta_i=[0, 50], wavelengths="500, 650", rays=12_000, theta_o_bins=5, phi_o_bins=6,
                    seed=4, progress=False, **extra)


def _sphere(**extra) -> vm.SphereResult:
    return vm.sphere_measure(SPHERE, wavelengths="450, 700", rays=6000, seed=4, progress=False, **extra)


def _same_gonio(a: vm.GonioResult, b: vm.GonioResult) -> None:
    assert np.array_equal(a.bin_counts, b.bin_counts)
    for name in ("reflected", "transmitted", "absorbed", "capped", "invalid_directions", "rays"):
        assert np.array_equal(getattr(a.result, name), getattr(b.result, name)), name


def _same_sphere(a: vm.SphereResult, b: vm.SphereResult) -> None:
    for configuration in ("sample", "standard"):
        assert a.counts[configuration].keys() == b.counts[configuration].keys()
        for name, values in a.counts[configuration].items():
            assert np.array_equal(values, b.counts[configuration][name]), (configuration, name)


@pytest.fixture(scope="module")
def specimens(mi):
    """A rough dielectric (one sample() per ray) and the soybean leaf (a random walk on queued lanes)."""

    return {"rough": vm.instrument_scene({"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5}),
            "leaf": vm.instrument_scene({"type": "abm_b"})}


@pytest.fixture
def chunk_sequence(monkeypatch):
    """Force the kernel's chunk sizes to a given cycle of sizes (whatever the time they take)."""

    def force(sizes: list[int]) -> None:
        cycle = iter(sizes * 1000)
        original = tracer._Pace.__init__

        def init(self, cap, seconds, key):
            original(self, cap, None, key)
            self.size = next(cycle)

        def update(self, size, elapsed):
            self.size = next(cycle)

        monkeypatch.setattr(tracer._Pace, "__init__", init)
        monkeypatch.setattr(tracer._Pace, "update", update)

    return force


@pytest.mark.parametrize("name", ["rough", "leaf"])
def test_goniophotometer_counts_do_not_depend_on_the_chunks(specimens, chunk_sequence, name):
    scene = specimens[name]
    paced = _gonio(scene)  # chunks sized by their time
    _same_gonio(paced, _gonio(scene, chunk_size=1024))
    chunk_sequence([5000, 1024, 8192, 3001])  # arbitrary cuts, readings straddling chunks
    _same_gonio(paced, _gonio(scene))


def test_sphere_counts_do_not_depend_on_the_chunks(chunk_sequence):
    paced = _sphere()
    _same_sphere(paced, _sphere(chunk_size=1024))
    chunk_sequence([2048, 777 + 1024, 4096])
    _same_sphere(paced, _sphere())


def test_goniophotometer_and_sphere_counts_do_not_depend_on_the_drjit_threads(specimens):
    import drjit as dr

    gonio, sphere = _gonio(specimens["leaf"]), _sphere()
    threads = dr.thread_count()
    try:
        dr.set_thread_count(1)
        _same_gonio(gonio, _gonio(specimens["leaf"]))
        _same_sphere(sphere, _sphere())
        dr.set_thread_count(max(3, threads + 1))  # more threads than cores: other packet orders
        _same_gonio(gonio, _gonio(specimens["leaf"]))
        _same_sphere(sphere, _sphere())
    finally:
        dr.set_thread_count(threads)
