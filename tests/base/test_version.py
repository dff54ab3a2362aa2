"""
Tests of :mod:`virtspec_mi.base.version`: one version, the same as the distribution's.

References
----------
PEP 440, Version Identification and Dependency Specification.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import virtspec_mi
from virtspec_mi.base.version import __all__ as exported
from virtspec_mi.base.version import __version__

ROOT = Path(__file__).resolve().parents[2]


def test_the_version_is_pep_440_and_the_distributions():
    # a canonical PEP 440 public version (its appendix B form, no epoch or local part)
    assert re.fullmatch(r"\d+(\.\d+)*((a|b|rc)\d+)?(\.post\d+)?(\.dev\d+)?", __version__)
    assert tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"] == __version__


def test_the_package_exports_the_one_version():
    assert exported == ["__version__"]
    assert virtspec_mi.__version__ is __version__
