"""
The applications' contract (issue 38 items 2 and 5), as ``tests/instruments/test_contract.py``
is the instruments': every row of :data:`virtspec_mi.applications.APPLICATIONS` is run
through the same checks from its own fixture (``Application.example``):

- its declarations: commands with help, examples and an ``Options`` class of flags (each
  with its check), extensions of an instrument's subcommand with what they take; the
  command line generated from them (``virtspec NAME --help`` lists every flag);
- the command line and its Python function give the same counts;
- every file it writes is read back with those counts, in every format it writes;
- an interrupted run (SIGINT at a safe point, its work kept) resumes to the same counts,
  for the applications that resume (``slow``);
- two Dask workers give the in-process counts, for the applications that use them (``slow``).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

from killed_runs import default_signals
from virtspec_mi.applications import APPLICATIONS, Application, Command, commands
from virtspec_mi.cli import build_parser, main
from virtspec_mi.cli.flags import flag_name
from virtspec_mi.settings import Options

ROWS = sorted(APPLICATIONS)
ROOT = Path(__file__).resolve().parents[2]


def words(argv, folder: Path) -> list[str]:
    return [word.replace("{tmp}", str(folder)) for word in argv]


def prepared(name: str, folder: Path) -> dict:
    example = APPLICATIONS[name].example
    if "inputs" in example:
        example["inputs"](folder)
    return example


def test_every_application_declares_its_commands_and_an_example():
    assert {"targets", "fitting", "tables", "klems", "comparison"} <= set(ROWS)
    for name, application in APPLICATIONS.items():
        assert issubclass(application, Application) and application.name == name and application.summary
        assert application.commands or application.extensions, name
        for command in application.commands:
            assert isinstance(command, Command) and command.summary and command.description and command.examples
            assert issubclass(command.flags, Options) and callable(command.respond)
            assert all(callable(item.metadata["check"]) for item in fields(command.flags))
        for extension in application.extensions:
            assert issubclass(extension.flags, Options) and extension.active in extension.flags.names()
        example = application.example
        assert {"argv", "api", "counts"} <= set(example), name
        assert ("printed" in example) == ("--json" in example["argv"]), name
        assert example["argv"][0] in commands() or any(e.command == example["argv"][0]
                                                       for e in application.extensions), name


def test_the_command_line_is_generated_from_the_rows(capsys):
    parser = build_parser()
    subcommands = next(a for a in parser._actions if a.dest == "command").choices
    for name, (_, command) in commands().items():
        assert name in subcommands
        with pytest.raises(SystemExit) as done:
            main([name, "--help"])
        shown = capsys.readouterr().out
        assert done.value.code == 0 and command.summary.split()[0] in parser.format_help()
        for item in fields(command.flags):
            if not item.metadata.get("hidden"):
                assert (flag_name(item) if not item.metadata.get("positional") else
                        (item.metadata.get("metavar") or item.name)) in shown, (name, item.name)
        for example in command.examples:
            assert f"virtspec {name}" in example


@pytest.mark.parametrize("name", ROWS)
def test_the_command_line_and_the_python_function_give_the_same_counts(name, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    example = prepared(name, tmp_path)
    assert main(words(example["argv"], tmp_path)) == 0, capsys.readouterr().err
    printed = capsys.readouterr().out
    expected = example["counts"](example["api"](tmp_path))
    if "printed" in example:
        np.testing.assert_array_equal(example["printed"](json.loads(printed)), expected)
    for output in example.get("outputs", ()):
        assert (tmp_path / output).is_file(), output
    for output in example.get("outputs", ())[:1]:
        np.testing.assert_array_equal(example["counts"](example["read"](tmp_path / output)), expected)


@pytest.mark.parametrize("name", [name for name in ROWS if APPLICATIONS[name].example.get("formats")])
def test_every_file_format_is_read_back_with_the_same_counts(name, tmp_path):
    example = prepared(name, tmp_path)
    result = example["api"](tmp_path)
    for suffix in example["formats"]:
        path = tmp_path / f"written{suffix}"
        result.write(path)
        np.testing.assert_array_equal(example["counts"](example["read"](path)), example["counts"](result))


def _kept(path: Path) -> bool:
    """Whether the checkpoint ``path`` (a file, or a folder of results) holds finished work."""

    return path.is_file() or (path.is_dir() and any(p.suffix == ".nc" for p in path.iterdir()))


@pytest.mark.slow
@pytest.mark.parametrize("name", [name for name in ROWS if "resume" in APPLICATIONS[name].example])
def test_an_interrupted_command_resumes_to_the_same_counts(name, tmp_path):
    example = prepared(name, tmp_path)
    resume = example["resume"]
    command = [sys.executable, "-m", "virtspec_mi", *words(resume["argv"], tmp_path)]
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    checkpoint, out = tmp_path / resume["checkpoint"], tmp_path / resume["out"]
    run = subprocess.Popen(command, cwd=tmp_path, env=environment, stderr=subprocess.PIPE, text=True,
                           preexec_fn=default_signals)
    deadline = time.monotonic() + 300
    while not _kept(checkpoint) and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    run.send_signal(signal.SIGINT)
    _, err = run.communicate(timeout=120)
    assert run.returncode == 130, f"the run ended before it could be interrupted: {err}"
    assert "re-run the same command to resume" in err and _kept(checkpoint) and not out.exists(), err
    again = subprocess.run(command, cwd=tmp_path, env=environment, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    whole = tmp_path / "whole"
    whole.mkdir()
    prepared(name, whole)
    uninterrupted = subprocess.run([*command[:3], *words(resume["argv"], whole)], cwd=whole, env=environment,
                                   capture_output=True, text=True, timeout=600)
    assert uninterrupted.returncode == 0, uninterrupted.stderr
    np.testing.assert_array_equal(example["counts"](example["read"](out)),
                                  example["counts"](example["read"](whole / resume["out"])))


@pytest.mark.slow
@pytest.mark.parametrize("name", [name for name in ROWS if APPLICATIONS[name].example.get("workers")])
def test_two_dask_workers_give_the_in_process_counts(name, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    example = prepared(name, tmp_path)
    argv = words(example["argv"], tmp_path)
    assert main([*argv, "--workers", "2"]) == 0, capsys.readouterr().err
    output = example["outputs"][0]
    np.testing.assert_array_equal(example["counts"](example["read"](tmp_path / output)),
                                  example["counts"](example["api"](tmp_path)))
