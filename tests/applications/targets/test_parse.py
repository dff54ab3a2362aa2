"""
Targets written as text (virtspec_mi/applications/targets/parse.py): parse_target reads
``KIND[:ARG]...[,NAME=VALUE]...`` by the table TARGETS, converts options by the
constructor's annotations, refuses unknown kinds and options naming the allowed ones and an
option given twice; the --target help lists every row.
"""

from __future__ import annotations

import pytest

from virtspec_mi.applications.targets.parse import TargetFlags, kinds, parse_target, target_help
from virtspec_mi.applications.targets.targets import TARGETS


def test_every_kind_is_read():
    assert parse_target("color,dE00=0.5,step=5").tolerance_dE00 == 0.5
    assert parse_target("colour,tolerance_dE00=0.7").tolerance_dE00 == 0.7  # the long name too
    assert [b.name for b in parse_target("band:B04:650-680,tolerance=0.002").bands] == ["B04", "650-680"]
    assert parse_target("index:NDVI,tolerance=0.002").index.name == "NDVI"
    assert parse_target("fapar,tolerance=0.01,low=410").low == 410
    assert parse_target("albedo,illuminant=A,tolerance=0.01").bands[0].name == "albedo_A"


def test_bad_texts_are_refused_naming_the_allowed_ones():
    with pytest.raises(ValueError, match="--target: the kind must be one of colour, band, index, fapar, albedo"):
        parse_target("ndvi")
    with pytest.raises(ValueError, match="NAME one of tolerance, step"):
        parse_target("index:NDVI,dE00=1")
    with pytest.raises(ValueError, match="--target fapar: low must be a number"):
        parse_target("fapar,low=blue")
    with pytest.raises(ValueError, match="--target band: tolerance given twice"):
        parse_target("band:B04,tolerance=0.01,tolerance=0.02")
    with pytest.raises(ValueError, match="--target colour: tolerance_dE00 given twice"):
        parse_target("colour,dE00=1,tolerance_dE00=2")
    with pytest.raises(ValueError, match="--target band needs at least 1 ':' argument"):
        parse_target("band,tolerance=0.01")
    with pytest.raises(ValueError, match="--target index needs 1 ':' argument"):
        parse_target("index:NDVI:GNDVI")
    with pytest.raises(ValueError, match="--target fapar takes no ':' arguments"):
        parse_target("fapar:B04")


def test_the_help_and_the_kinds_come_from_the_rows():
    assert list(kinds()) == list(TARGETS) and kinds()["fapar"] == ("tolerance", "illuminant", "low", "high", "step")
    text = target_help()
    assert all(kind.describe(name) in text for name, kind in TARGETS.items())
    assert "index:ARG (tolerance, step)" in text and "band:ARG... (tolerance, quantity, step)" in text
    assert TargetFlags.describe().startswith("target = none: certify a derived quantity")
