"""
Tests of :mod:`virtspec_mi.instruments.hemispherical` (its ``__init__``): the spectrophotometer's row.

The densities of ``virtspec sweep --densities`` are log10 N each, within what a reading can
trace, refused otherwise naming the flag's meaning; the row has no options, the readings'
result kind and the two subcommands; a reading's fates account for every ray (α = 1 − ρ − τ
exactly, 0 for a lossless dielectric) and ``measure`` is a sweep's reading at one θi (the same
keyed counts as ``sweep`` over that one θi); ``--densities`` excludes ``--rays`` and ``--json``.

References
----------
Baranoski et al. (2001), eqs. (2), (23), (24); Figs. 5 and 6.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments.hemispherical import Hemispherical, SweepFlags, _check_densities
from virtspec_mi.results.readings import Result


def test_densities_are_log10_rays_within_a_readings_reach():
    assert _check_densities("3, 4 5.5") == (3.0, 4.0, 5.5)
    assert _check_densities([0, 2]) == (0.0, 2.0)
    with pytest.raises(ValueError, match=r"densities must be numbers, log10 N each \(got 'many'\)"):
        _check_densities("3 many")
    top = math.log10(2**32 - 1)
    with pytest.raises(ValueError, match=rf"densities must satisfy 0 <= log10 N <= {top:.2f} .*got 10\)"):
        _check_densities([3, 10])
    with pytest.raises(ValueError, match=r"got -1\)"):
        _check_densities("-1")
    assert SweepFlags().densities is None


def test_the_row():
    assert Hemispherical.name == "hemispherical" and Hemispherical.options is None and Hemispherical.result is Result
    assert [command.name for command in Hemispherical.commands] == ["measure", "sweep"]
    measure, sweep = Hemispherical.commands
    assert measure.one_reading and measure.function == "sweep" and not sweep.one_reading
    assert sweep.flags is SweepFlags and sweep.output == "table"


@pytest.fixture(scope="module")
def readings(mi):
    return vm.sweep("diamond_collimated", theta_i=[0, 45], wavelengths=[450, 650], rays=4000, seed=1)


def test_every_ray_has_one_fate(readings):
    counts = readings.counts
    assert np.all(counts.rays == 4000)
    np.testing.assert_array_equal(counts.absorbed, counts.rays - counts.reflected - counts.transmitted)
    assert np.all(counts.absorbed == 0)  # a lossless dielectric
    np.testing.assert_allclose(np.asarray(readings.reflectance) + np.asarray(readings.transmittance), 1.0)


def test_measure_is_a_sweeps_reading_at_one_angle(mi):
    """The keyed counts of ``measure`` at θi are those of ``sweep`` over that one θi (``virtspec measure``'s help)."""

    one = vm.measure("diamond_collimated", theta_i=45, wavelengths=[450, 650], rays=4000, seed=1)
    swept = vm.sweep("diamond_collimated", theta_i=[45], wavelengths=[450, 650], rays=4000, seed=1)
    np.testing.assert_array_equal(np.ravel(one.counts.reflected), np.ravel(swept.counts.reflected))
    other = vm.measure("diamond_collimated", theta_i=45, wavelengths=[450, 650], rays=4000, seed=2)
    assert not np.array_equal(np.ravel(other.counts.reflected), np.ravel(one.counts.reflected))


def test_densities_exclude_rays_and_json(mi, capsys):
    from virtspec_mi.cli import main

    assert main(["sweep", "diamond_collimated", "--densities", "2", "--rays", "100", "--quiet"]) == 1
    assert "--rays and --densities exclude each other" in capsys.readouterr().err
    assert main(["sweep", "diamond_collimated", "--densities", "2", "--json", "--quiet"]) == 1
    assert "--json prints one result and --densities a table" in capsys.readouterr().err
