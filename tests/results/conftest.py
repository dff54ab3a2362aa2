"""Fixtures of tests/results/: one result of every kind (tests/result_kinds.py), made once per test module."""

from __future__ import annotations

import pytest

from result_kinds import gonio_reading, hemispherical_grid, sphere_grid


@pytest.fixture(scope="module")
def hemispherical():
    """A hemispherical parameter sweep over (wavelength, theta_i, specimen.thickness), from counts."""

    return hemispherical_grid()


@pytest.fixture(scope="module")
def sphere():
    """A sphere result over (wavelength, theta_i, point), from counts."""

    return sphere_grid()


@pytest.fixture(scope="module")
def gonio(mi):
    """A traced goniophotometer reading of a rough dielectric (3 wavelengths x 2 theta_i, 3 x 2 bins)."""

    return gonio_reading()
