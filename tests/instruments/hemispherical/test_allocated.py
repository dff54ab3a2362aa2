"""The spectrophotometer with rays allocated per wavelength (virtspec_mi.instruments.hemispherical.allocated)."""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.engine.readings import trace_allocated
from virtspec_mi.instruments.hemispherical.allocated import Allocated, Allocation
from virtspec_mi.runtime.reading import scene_options
from virtspec_mi.runtime.scene import loaded
from virtspec_mi.settings import Settings


def test_its_run_is_the_allocation_traced_in_one_call_with_the_same_counts(mi):
    scene = loaded("diamond_collimated")
    settings = scene_options(scene.bench, Settings).updated(theta_i=30.0, seed=4)
    grid, rays = np.array([450.0, 500.0, 550.0, 600.0]), np.array([3000, 0, 1200, 700])
    instrument = Allocated(scene.fingerprint, scene.source)
    result = instrument.run(scene.bench, settings, Allocation(grid, rays, 99), np.array([30.0]))
    assert instrument.used.tolist() == [0, 2, 3]
    assert result.coords["wavelength"].tolist() == [450.0, 550.0, 600.0] and result.settings.seed == 4
    direct = trace_allocated(scene.bench, settings.updated(seed=99), [(w, 30.0, 0.0) for w in grid[[0, 2, 3]]],
                             rays[[0, 2, 3]], offsets=np.array([0, 2, 3]) * 3000)
    np.testing.assert_array_equal(np.ravel(result.reflected), direct.counts.reflected)
    np.testing.assert_array_equal(np.ravel(result.rays), [3000, 1200, 700])


def test_it_takes_an_allocation_at_one_angle_in_this_process(mi):
    scene = loaded("diamond_collimated")
    settings = scene_options(scene.bench, Settings)
    with pytest.raises(ValueError, match="takes an Allocation"):
        Allocated().init(scene.bench, settings, None, np.array([0.0]), None)
    with pytest.raises(ValueError, match="at one theta_i"):
        Allocated().init(scene.bench, settings, Allocation(np.array([500.0]), np.array([10]), 0), np.array([0.0, 9.0]),
                         None)
    instrument = Allocated()
    plan = instrument.init(scene.bench, settings, Allocation(np.array([500.0]), np.array([10]), 0), np.array([0.0]),
                           None)
    with pytest.raises(ValueError, match="no checkpoint, no workers"):
        instrument.process(plan, checkpoint="x.json")
