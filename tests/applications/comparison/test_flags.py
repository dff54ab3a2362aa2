"""
Tests of :mod:`virtspec_mi.applications.comparison.flags`: how to read a measured file, as one options class.

Its fields are the flags ``--sample``, ``--measured-quantity``, ``--measured-scale``, ``--splice`` and
``--measured-format`` of every application command that takes a measured file (the one flag builder
makes them); the quantity and scale take only the values a measured file may hold, refused by name.
"""

from __future__ import annotations

import argparse
from dataclasses import fields

import pytest

from virtspec_mi.applications.comparison.flags import MeasuredFlags
from virtspec_mi.cli.flags import given, option_flags


def test_the_fields_and_their_defaults():
    assert [item.name for item in fields(MeasuredFlags)] == ["sample", "measured_quantity", "measured_scale", "splice",
                                                            "measured_format"]
    flags = MeasuredFlags()
    assert (flags.sample, flags.measured_quantity, flags.measured_scale, flags.splice, flags.measured_format) == (
        None, None, None, False, None)
    assert MeasuredFlags.title == "measured file"


def test_the_flags_they_make_and_read_back():
    parser = argparse.ArgumentParser(exit_on_error=False)
    option_flags(parser, MeasuredFlags, scene=False)
    args = parser.parse_args(["--sample", "oak-2", "--measured-quantity", "transmittance", "--measured-scale",
                              "percent", "--splice", "--measured-format", "asd"])
    assert given(args, MeasuredFlags) == {"sample": "oak-2", "measured_quantity": "transmittance",
                                          "measured_scale": "percent", "splice": True, "measured_format": "asd"}
    with pytest.raises(argparse.ArgumentError):
        parser.parse_args(["--measured-scale", "permille"])


@pytest.mark.parametrize("field, value", [("measured_quantity", "absorptance"), ("measured_scale", "permille")])
def test_values_a_measured_file_cannot_hold_are_refused_by_name(field, value):
    check = {item.name: item.metadata["check"] for item in fields(MeasuredFlags)}[field]
    with pytest.raises(ValueError, match=rf"{field}"):
        check(value)
