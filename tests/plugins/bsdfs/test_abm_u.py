"""``abm_u`` (corn) against the NPSG C++ reference (its runs of the corn leaf)."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from abm_reference import CORN, CORN_RAYS, CORN_WAVELENGTHS, mismatches


def corn(sieve: bool, rays: int, seed: int = 0) -> np.ndarray:
    scene = vm.instrument_scene({"type": "abm_u", "sieve_detour": sieve})
    reading = vm.measure(scene, theta_i=8, beam="collimated", wavelengths=CORN_WAVELENGTHS, rays=rays, seed=seed)
    assert reading.capped.sum() == 0 and reading.weight_violations.sum() == 0
    return np.stack([reading.reflectance, reading.transmittance], axis=1)


def test_corn_sieve_on_matches_reference(mi):
    rays = 100_000
    assert not mismatches(corn(True, rays), np.array(CORN[True]), rays, CORN_RAYS)


@pytest.mark.slow
def test_corn_sieve_off_matches_reference(mi):
    rays = 200_000
    assert not mismatches(corn(False, rays, seed=3), np.array(CORN[False]), rays, CORN_RAYS)


def test_corn_scene_from_xml(mi, scenes_dir):
    reading = vm.measure(str(scenes_dir / "corn_abmu.xml"), rays=10_000, wavelengths=[550, 800])
    assert reading.settings.beam == "collimated" and reading.theta_i == 8
    assert reading.capped.sum() == 0 and 0.4 < reading.reflectance[1] < 0.5  # reference 0.451
