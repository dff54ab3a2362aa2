"""
Tests of :mod:`virtspec_mi.exchange.measured.flags`: the flags that say how to read a measured file.

References
----------
ASD Inc. (2017), *ASD File Format*, version 8.
"""

from __future__ import annotations

import argparse

import pytest

from virtspec_mi.exchange.measured.base import MeasuredFile
from virtspec_mi.exchange.measured.flags import add_measured_flags, measured_from


@pytest.fixture
def parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="virtspec compare", exit_on_error=False)
    parser.add_argument("measured")
    add_measured_flags(parser)
    return parser


def test_no_flag_leaves_the_path_as_it_is(parser):
    args = parser.parse_args(["leaf.asd"])
    assert measured_from(args, "leaf.asd") == "leaf.asd"
    assert measured_from(argparse.Namespace(), "leaf.asd") == "leaf.asd"  # a command without the flags
    assert measured_from(parser.parse_args(["x", "--splice"]), None) is None


def test_flags_make_a_measured_file(parser):
    args = parser.parse_args(["leaves.csv", "--sample", "3", "--measured-quantity", "transmittance",
                              "--measured-scale", "percent", "--splice", "--measured-format", "table"])
    assert measured_from(args, args.measured) == MeasuredFile("leaves.csv", sample=3, quantity="transmittance",
                                                              scale="percent", splice=True, format="table")
    labelled = measured_from(parser.parse_args(["leaves.csv", "--sample", "oak-2"]), "leaves.csv")
    assert labelled.sample == "oak-2" and labelled.quantity is None and labelled.splice is False


def test_choices_are_the_allowed_values(parser):
    with pytest.raises(argparse.ArgumentError) as refused:
        parser.parse_args(["x", "--measured-quantity", "absorptance"])
    assert "absorptance" in str(refused.value) and "reflectance" in str(refused.value)
    assert "transmittance" in str(refused.value)
    with pytest.raises(argparse.ArgumentError) as refused:
        parser.parse_args(["x", "--measured-scale", "permille"])
    assert "fraction" in str(refused.value) and "percent" in str(refused.value)
