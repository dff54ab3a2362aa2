"""The applications' subcommands generated from their rows (virtspec_mi.cli.applying): flags, session, report."""

from __future__ import annotations

import argparse
import json

import pytest

from virtspec_mi.applications import commands
from virtspec_mi.cli import build_parser, main
from virtspec_mi.cli.applying import ApplicationSession, application_commands


class _Result:
    def as_dict(self):
        return {"value": 1}


def _session(argv):
    args = build_parser().parse_args(argv)
    return ApplicationSession(args, application_commands()[argv[0]])


def test_every_application_command_is_a_subcommand_with_its_flags_checked():
    assert set(application_commands()) == set(commands()) >= {"fit", "albedo-table", "klems", "compare"}
    session = _session(["albedo-table", "--out", "a.nc", "b.h", "--out", "c.npy", "--cosines", "1,0.5"])
    assert session.flags.out == ("a.nc", "b.h", "c.npy") and session.flags.mu == "1,0.5"
    session = _session(["fit", "leaf.csv", "--specimen", "prospect_d", "--free", "Cab=10:80", "--free", "Cm=0:1",
                        "-D", "side=abaxial"])
    assert session.flags.free == (("Cab", "10:80"), ("Cm", "0:1")) and session.flags.defines == ("side=abaxial",)


def test_the_report_prints_text_and_files_or_one_json_object(capsys):
    assert _session(["compare", "r.nc", "m.csv"]).report(_Result(), "text", written=["a"], figures=["b.png"],
                                                          after="more") == 0
    assert capsys.readouterr().out == "text\nwritten: a\nplot: b.png\nmore\n"
    _session(["compare", "r.nc", "m.csv", "--json"]).report(_Result(), "text", data={"x": 2})
    assert json.loads(capsys.readouterr().out) == {"x": 2}


@pytest.mark.parametrize("argv, message", [
    (["fit", "leaf.csv", "--specimen", "prospect_d", "--free", "Cab"], "--free: --free takes NAME=LOWEST:HIGHEST"),
    (["fit", "leaf.csv", "--specimen", "prospect_d", "--free", "Cab=1:2", "--delta", "2"], "--delta: delta must"),
    (["klems", "leaf.xml", "--out", "k.xml", "--wavelengths", "x"], "--wavelengths:"),
    (["albedo-table", "--seed", "-1"], "--seed: seed must be a whole number"),
    (["compare", "r.nc", "m.csv", "--sel", "theta_i"], "--sel: --sel takes NAME=VALUE"),
])
def test_a_bad_value_is_one_line_naming_its_flag_before_anything_runs(argv, message, capsys):
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.startswith("virtspec: error: ") and message in err and err.count("\n") == 1, err


def test_a_required_flag_left_out_is_argparses_usage_error(capsys):
    with pytest.raises(SystemExit) as done:
        main(["klems", "diamond_collimated"])
    assert done.value.code == 2 and "--out" in capsys.readouterr().err
    assert isinstance(_session(["klems", "s.xml", "--out", "k.xml"]).args, argparse.Namespace)
