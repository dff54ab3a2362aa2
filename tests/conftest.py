"""Shared fixtures: the paper's instrument around a few specimens."""

from __future__ import annotations

from pathlib import Path

import pytest

import virtspec_mi
from virtspec_mi.plugins.leaf_data import leaf_data_dir

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
# The NPSG leaf data for the ABM specimens: the package's shipped copy (VIRTSPEC_LEAF_DATA,
# when set, points elsewhere).
LEAF_DATA = leaf_data_dir()


@pytest.fixture(scope="session")
def mi():
    """The ``mitsuba`` module, set up by virtspec-mi (libLLVM, variant, plugins)."""

    return virtspec_mi.mitsuba()


@pytest.fixture(scope="session")
def diamond(mi):
    """The paper's instrument around ``simple_dielectric`` (eta = 2.419), loaded."""

    return mi.load_dict(virtspec_mi.instrument_scene({"type": "simple_dielectric"}))


@pytest.fixture(scope="session")
def scenes_dir() -> Path:
    return SCENES


@pytest.fixture(scope="session")
def leaf_data_dir() -> Path:
    """Directory of the NPSG leaf data used by the ABM tests."""

    return LEAF_DATA
