"""
The contract every instrument of the registry keeps (virtspec_mi.instruments): one test per
row, parametrised by the registry itself, so that an instrument added there (or through the
entry-point group) is held to it with no test written for it.

For each instrument, with its own fixture (``Instrument.example``: a small reading of a
shipped scene, and a longer one):

- the API (``vm.take(name, …)``) and the command line (its first subcommand, generated from
  the registry, ``--out``) give the same exact counts;
- its result is a result kind of the file family: written and read back in every format
  with the same counts and the same plain data; ``sel`` and ``plot`` work on it, from
  Python and from ``--plot``;
- its subcommand, killed with SIGKILL mid-run and run again, resumes to the uninterrupted
  counts (slow);
- two Dask workers give the in-process counts (slow).
"""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

import virtspec_mi as vm
from killed_runs import kill_then_resume
from virtspec_mi.cli import main
from virtspec_mi.instruments import INSTRUMENTS

ROWS = list(INSTRUMENTS)


def example(name: str) -> tuple[str, dict]:
    """The instrument's small reading: its scene and API keywords."""

    keywords = dict(INSTRUMENTS[name].example)
    keywords.pop("long")
    return keywords.pop("scene"), keywords


def flags(keywords: dict) -> list[str]:
    """The command-line flags of API keywords (lists as several words; parameters as --param)."""

    words: list[str] = []
    for name, value in keywords.items():
        if name == "parameters":
            for key, values in value.items():
                words += ["--param", f"{key}={','.join(map(str, values))}"]
        elif isinstance(value, bool):
            words += [f"--{name.replace('_', '-')}"] if value else []
        else:
            words += [f"--{name.replace('_', '-')}", *map(str, np.atleast_1d(value))]
    return words


def counts(result) -> dict[str, np.ndarray]:
    """Every labelled array of a result (its exact counts), squeezed (one reading prints as one)."""

    return {name: np.squeeze(values) for name, (_, values) in result._labelled().items()}


def assert_same_counts(a, b) -> None:
    ours, theirs = counts(a), counts(b)
    assert ours.keys() == theirs.keys()
    for name in ours:
        assert np.array_equal(ours[name], theirs[name], equal_nan=ours[name].dtype.kind == "f"), name


@pytest.fixture(scope="module")
def readings(mi):
    """Each instrument's small reading through the API, once."""

    return {name: vm.take(name, example(name)[0], progress=False, **example(name)[1]) for name in ROWS}


def test_every_instrument_declares_a_subcommand_a_result_kind_and_an_example():
    from virtspec_mi.results.base import KINDS

    for name, instrument in INSTRUMENTS.items():
        assert instrument.commands, name
        assert instrument.result in KINDS.values(), name
        assert vm.scenes.path(instrument.example["scene"]).is_file(), name
        assert "long" in instrument.example and "readings" in instrument.example["long"], name


def test_every_subcommand_is_an_api_function_with_the_instruments_options():
    import inspect

    for instrument in INSTRUMENTS.values():
        for command in instrument.commands:
            function = getattr(vm, command.function or command.name)  # a generated alias where none is written
            names = set(inspect.signature(function).parameters)
            assert set(vm.Settings.names()) - {"theta_i"} <= names, command.name
            assert instrument.options is None or set(instrument.options.names()) <= names, command.name


@pytest.mark.parametrize("name", ROWS)
def test_the_api_and_the_command_line_give_the_same_counts(name, readings, tmp_path, capsys):
    scene, keywords = example(name)
    command = INSTRUMENTS[name].commands[0]
    if command.one_reading:
        keywords = {k: (v[0] if k == "theta_i" and np.ndim(v) else v) for k, v in keywords.items()}
    out, figure = tmp_path / f"{name}.nc", tmp_path / f"{name}.png"
    assert main([command.name, scene, *flags(keywords), "--quiet", "--out", str(out), "--plot", str(figure)]) == 0
    expected = vm.take(name, scene, progress=False, **keywords) if command.one_reading else readings[name]
    assert_same_counts(vm.read_result(out), expected)
    assert figure.read_bytes()[:4] == b"\x89PNG" or any(tmp_path.glob(f"{name}_*.png"))
    assert main([command.name, scene, *flags(keywords), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["format"] == INSTRUMENTS[name].result.FORMAT


@pytest.mark.parametrize("suffix", [".nc", ".json", ".csv", ".zarr"])
@pytest.mark.parametrize("name", ROWS)
def test_the_result_is_a_kind_of_the_file_family(name, suffix, readings, tmp_path):
    result = readings[name]
    back = vm.read_result(result.write(tmp_path / f"{name}{suffix}"))
    assert type(back) is type(result) and back.dims == result.dims
    assert_same_counts(back, result)
    assert back.as_dict() == result.as_dict()


@pytest.mark.parametrize("name", ROWS)
def test_the_result_selects_and_plots(name, readings, tmp_path):
    result = readings[name]
    one = result.sel(wavelength=float(np.atleast_1d(result.coords["wavelength"])[0]))
    assert "wavelength" not in one.dims and "wavelength" in one.coords
    drawn = result.squeeze().isel(theta_i=0) if "theta_i" in result.squeeze().dims else result.squeeze()
    drawn.plot(tmp_path / f"{name}.png")
    assert (tmp_path / f"{name}.png").read_bytes()[:4] == b"\x89PNG"
    assert result.summary()


@pytest.mark.slow
@pytest.mark.parametrize("name", ROWS)
def test_a_killed_subcommand_resumes_to_the_uninterrupted_counts(name, mi, tmp_path):
    small = dict(INSTRUMENTS[name].example)
    longer = small.pop("long")
    long = {**small, **longer}
    scene, readings = long.pop("scene"), long.pop("readings")
    command = INSTRUMENTS[name].commands[0]
    out = tmp_path / f"{name}.nc"
    kill_then_resume([sys.executable, "-m", "virtspec_mi.cli", command.name, scene, *flags(long), "--quiet",
                      "--out", str(out)], out, readings, tmp_path)
    whole = vm.take(name, scene, progress=False, **long)
    assert_same_counts(vm.read_result(out), whole.squeeze() if command.one_reading else whole)


@pytest.mark.slow
@pytest.mark.parametrize("name", ROWS)
def test_two_dask_workers_give_the_in_process_counts(name, readings):
    scene, keywords = example(name)
    assert_same_counts(vm.take(name, scene, workers=2, progress=False, **keywords), readings[name])
