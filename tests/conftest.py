"""Shared fixtures: the paper's instrument around a few specimens."""

from __future__ import annotations

from pathlib import Path

import pytest

import virtspec_mi

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"


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
