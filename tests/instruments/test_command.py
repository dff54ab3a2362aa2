"""
Tests of :mod:`virtspec_mi.instruments.command`: the rows an instrument declares its subcommands with.

A command without figure flags draws the result's first figure as ``--plot``; with them, the
first is ``--plot`` and says what it draws; every registered instrument's commands are
:class:`Command` rows with distinct names, a one-line summary, a description and examples
that run ``virtspec`` on a shipped scene, and only the outputs the command line prints.
The subcommands run from these rows are tested in ``tests/instruments/test_contract.py``.

References
----------
Python documentation, ``argparse`` (sub-commands).
"""

from __future__ import annotations

import dataclasses

import pytest

from virtspec_mi.instruments import INSTRUMENTS
from virtspec_mi.instruments.command import Command, FigureFlag, Subcommand


def test_a_command_without_figure_flags_draws_the_results_figure():
    command = Command("measure", "one reading", "Measure one reading.", ("virtspec measure diamond",))
    assert isinstance(command, Subcommand)
    assert command.plot == "the result's figure"
    assert command.all_figures() == (FigureFlag("--plot", "", "the result's figure"),)
    assert (command.one_reading, command.flags, command.function, command.respond, command.output) == (
        False, None, None, None, "summary")
    with pytest.raises(dataclasses.FrozenInstanceError):
        command.name = "other"  # type: ignore[misc]


def test_declared_figure_flags_come_first_as_declared():
    polar = FigureFlag("--plot", "polar", "the lobes, one polar plot per wavelength", dim="wavelength")
    series = FigureFlag("--plot-series", "series", "the series", keywords={"quantity": "brdf"})
    command = Command("gonio", "lobes", "Measure lobes.", (), figures=(polar, series))
    assert command.plot == "the lobes, one polar plot per wavelength"
    assert command.all_figures() == (polar, series)
    assert series.keywords == {"quantity": "brdf"} and polar.keywords == {}


def test_every_registered_command_is_a_complete_row():
    names = []
    for instrument in INSTRUMENTS.values():
        for command in instrument.commands:
            assert isinstance(command, Command), command
            names.append(command.name)
            assert command.summary and "\n" not in command.summary, command.name
            assert command.description and command.examples, command.name
            assert all(example.startswith("virtspec ") for example in command.examples), command.name
            assert command.output in ("summary", "table"), command.name
            assert command.all_figures()[0].flag == "--plot", command.name
            flags = [figure.flag for figure in command.all_figures()]
            assert len(set(flags)) == len(flags), command.name
    assert len(set(names)) == len(names) and {"measure", "sweep", "gonio", "sphere"} <= set(names)
