"""Shared fixtures: the paper's instrument around a few specimens."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import virtspec_mi

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
# The NPSG leaf data (third party, not committed) for the ABM specimens: ../shared beside
# the checkout unless VIRTSPEC_LEAF_DATA points elsewhere.
LEAF_DATA = Path(os.environ.setdefault("VIRTSPEC_LEAF_DATA", str(ROOT.parent / "shared" / "data" / "abm-npsg")))


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
