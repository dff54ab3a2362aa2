"""The instrument seam (virtspec_mi.instruments): the registry and init / process / postprocess."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments import INSTRUMENTS
from virtspec_mi.instruments.base import Instrument
from virtspec_mi.settings import Options, Settings


def test_the_registry_holds_each_instrument_under_its_name():
    assert set(INSTRUMENTS) >= {"hemispherical", "goniophotometer", "sphere"}
    for name, instrument in INSTRUMENTS.items():
        assert issubclass(instrument, Instrument) and instrument.name == name
        assert instrument.options is None or issubclass(instrument.options, Options)
        assert isinstance(instrument.result, type)


def test_run_runs_init_process_postprocess_and_gives_the_apis_counts(mi):
    scene = vm.instrument_scene({"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5})
    bench = vm.find_bench(scene)
    settings = Settings(theta_i=30, rays=3000, seed=4)
    reading = INSTRUMENTS["hemispherical"]().run(bench, settings).squeeze()
    assert isinstance(reading, INSTRUMENTS["hemispherical"].result)
    assert np.array_equal(reading.reflected, vm.measure(scene, theta_i=30, rays=3000, seed=4).reflected)
    gonio = INSTRUMENTS["goniophotometer"]
    binned = gonio().run(bench, settings, gonio.options(theta_o_bins=2, phi_o_bins=3))
    assert isinstance(binned, gonio.result) and binned.bins.shape == (4, 3)
    assert np.array_equal(binned.result.reflected[:, 0], reading.reflected)


def test_each_instrument_refuses_what_it_cannot_take(mi):
    bench = vm.find_bench(vm.instrument_scene({"type": "diffuse"}))
    gonio = INSTRUMENTS["goniophotometer"]
    with pytest.raises(ValueError, match="bound='two-stage' cannot size these readings: bound 'two-stage' cannot "
                                         "size guarantee 'dkw'"):  # the rule row's reason, before any tracing
        gonio().run(bench, Settings(bound="two-stage"), gonio.options(guarantee="dkw"))
    with pytest.raises(ValueError, match="needs a sphere"):
        INSTRUMENTS["sphere"]().run(bench, Settings(rays=10), INSTRUMENTS["sphere"].options())
