"""
Tests of ``virtspec_mi.api.take``: any instrument of the registry by name, through the API's
keyed path — the same counts as its own entry (``gonio``) or as the engine's in-process
``Instrument.run``, a checkpoint and Dask workers as for a sweep, errors at the boundary.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments import INSTRUMENTS

ROUGH = {"type": "roughconductor", "alpha": 0.05}


@pytest.fixture(scope="module")
def mirror(mi):
    return vm.instrument_scene(ROUGH)


def test_a_gloss_reading_by_name_counts_as_the_engines_own(mirror):
    reading = vm.take("gloss", mirror, theta_i=60, cone=3, rays=20_000, wavelengths=[450, 650])
    meter = INSTRUMENTS["gloss"]
    own = meter().run(vm.find_bench(mirror), vm.Settings(rays=20_000, wavelengths=[450, 650]), meter.options(cone=3),
               theta_i=[60])
    assert np.array_equal(reading.glossy, own.glossy) and np.array_equal(reading.reflected, own.reflected)
    assert reading.source == {"scene": "scene dict, specimen RoughConductor", "defines": {}}


def test_the_goniophotometer_by_name_is_gonio(mirror):
    options = dict(theta_i=[20, 40], rays=5000, theta_o_bins=6, phi_o_bins=4)
    assert np.array_equal(vm.take("goniophotometer", mirror, **options).bin_counts,
                          vm.gonio(mirror, **options).bin_counts)


def test_a_checkpointed_reading_leaves_no_checkpoint_and_the_same_counts(mirror, tmp_path):
    checkpoint = tmp_path / "gloss.partial.json"
    reading = vm.take("gloss", mirror, theta_i=60, cone=3, rays=4000, checkpoint=checkpoint)
    assert not checkpoint.exists()
    assert np.array_equal(reading.glossy, vm.take("gloss", mirror, theta_i=60, cone=3, rays=4000).glossy)


@pytest.mark.slow
def test_a_gloss_reading_on_two_workers_counts_as_in_process(mirror):
    options = dict(theta_i=60, cone=3, rays=20_000, wavelengths=[450, 550, 650])
    assert np.array_equal(vm.take("gloss", mirror, workers=2, **options).glossy,
                          vm.take("gloss", mirror, **options).glossy)


def test_a_gloss_reading_is_a_result_kind_with_files(mirror, tmp_path):
    reading = vm.take("gloss", mirror, theta_i=60, cone=3, rays=4000, out=tmp_path / "gloss.nc")
    back = vm.read_result(tmp_path / "gloss.nc")
    assert type(back) is type(reading) and back.cone == 3
    assert np.array_equal(back.glossy, reading.glossy) and np.array_equal(back.reflected, reading.reflected)
    assert np.all(back.glossy <= back.reflected)


def test_errors_name_the_instrument_the_option_and_the_file(mirror, tmp_path):
    with pytest.raises(ValueError, match="instrument must be one of hemispherical, goniophotometer, sphere, gloss"):
        vm.take("lamp", mirror)
    with pytest.raises(ValueError, match=r"out must end in one of"):
        vm.take("gloss", mirror, out=tmp_path / "gloss.txt")
    with pytest.raises(TypeError, match="take\\(\\) got unexpected keyword argument\\(s\\) bins; .* the gloss meter "
                                        "options are cone"):
        vm.take("gloss", mirror, bins=3)
    with pytest.raises(ValueError, match="cone"):
        vm.take("gloss", mirror, cone=120)
