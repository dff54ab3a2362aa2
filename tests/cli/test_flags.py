"""
Tests of :mod:`virtspec_mi.cli.flags`: the common flags and the one flag builder.

One flag per option of the settings, named from the field (``--theta-i``), with its choices and
a switch for a ``bool``; :func:`given` returns only what was given (several words joined) and
names the flag of a bad value, with the hint for a one-reading command given several angles;
the small helpers parse ``NAME=VALUE`` pairs and name flags and destinations.
"""

from __future__ import annotations

import argparse

import pytest

from virtspec_mi.cli.flags import (
    COMMON_FLAGS,
    SEVERAL,
    dest,
    flag_of,
    flagged,
    given,
    option_flags,
    pairs,
    settings_options,
)


@pytest.fixture
def settings_parser():
    settings = settings_options()
    parser = argparse.ArgumentParser(prog="virtspec sweep", exit_on_error=False)
    option_flags(parser, settings, words=("theta_i",))
    return parser, settings


def test_one_flag_per_setting_with_its_choices_and_switches(settings_parser):
    parser, settings = settings_parser
    flags = {option for action in parser._actions for option in action.option_strings}
    assert {"--theta-i", "--phi-i", "--wavelengths", "--mu", "--delta", "--bound", "--joint", "--beam",
            "--sampling", "--seed", "--chunk-size"} <= flags
    args = parser.parse_args(["--joint", "--beam", "diffuse"])
    assert args.joint is True and args.beam == "diffuse" and args.mu is None  # left out: None (the scene's)
    with pytest.raises(argparse.ArgumentError):
        parser.parse_args(["--beam", "laser"])
    helps = {action.dest: action.help for action in parser._actions}
    assert helps["mu"] == "certified tolerance, 0 < mu < 0.5 (default: the scene's, else 0.005)"
    assert "; several values or start:stop:step ranges, one reading each (default: the scene's, else 0)" in \
        helps["theta_i"]
    sceneless = argparse.ArgumentParser()
    option_flags(sceneless, settings, scene=False)
    assert {action.dest: action.help for action in sceneless._actions}["mu"].endswith("(default 0.005)")


def test_given_returns_what_was_given_joined(settings_parser):
    parser, settings = settings_parser
    args = parser.parse_args(["--mu", "0.01", "--theta-i", "0", "10:30:10", "--wavelengths", "450", "550"])
    assert given(args, settings, several=("theta_i",)) == {"theta_i": "0 10:30:10", "wavelengths": "450 550",
                                                          "mu": "0.01"}
    assert given(parser.parse_args([]), settings) == {}


def test_a_bad_value_names_its_flag(settings_parser):
    parser, settings = settings_parser
    with pytest.raises(ValueError, match=r"^--mu: mu must satisfy 0 < mu < 0.5 \(got 2\)$"):
        given(parser.parse_args(["--mu", "2"]), settings)
    with pytest.raises(ValueError, match=r"^--theta-i: theta_i must be a number \(got '0 10'\); use sweep$"):
        given(parser.parse_args(["--theta-i", "0", "10"]), settings, hint="; use sweep")
    assert SEVERAL == {"theta_i": "parse_theta_i"}


def test_pairs_of_a_repeatable_flag():
    assert pairs(["a=1", " b = x y "], "-D") == {"a": "1", "b": "x y"}
    with pytest.raises(ValueError, match=r"-D takes NAME=VALUE \(got 'a'\)"):
        pairs(["a"], "-D")
    with pytest.raises(ValueError, match=r"-D takes NAME=VALUE \(got '=1'\)"):
        pairs(["=1"], "-D")
    with pytest.raises(ValueError, match="--param specimen.alpha is given twice"):
        pairs(["specimen.alpha=0.1", "specimen.alpha=0.2"], "--param")


def test_flag_names_and_destinations():
    assert flag_of("theta_i") == "--theta-i" and dest("--plot-series") == "plot_series" and dest("-D") == "D"
    assert flagged("--out", lambda v: v.upper(), "a.nc") == "A.NC"

    def check(value):
        raise ValueError("out must end in .nc")

    with pytest.raises(ValueError, match=r"^--out: out must end in .nc$"):
        flagged("--out", check, "a.txt")


def test_the_common_flags_are_distinct_and_two_are_exclusive():
    names = [flag.name for flag in COMMON_FLAGS]
    assert len(set(names)) == len(names)
    assert {flag.name for flag in COMMON_FLAGS if flag.exclusive} == {"--workers", "--scheduler"}
    parser = argparse.ArgumentParser(exit_on_error=False)
    for flag in COMMON_FLAGS:
        parser.add_argument(flag.name, **flag.keywords)
    args = parser.parse_args(["-D", "eta=1.5", "-D", "n=2", "--workers", "3"])
    assert args.defines == ["eta=1.5", "n=2"] and args.workers == 3 and args.params == []
