"""
An outside package adds an instrument through the entry-point group ``virtspec_mi.instruments``
(virtspec_mi.instruments.discovered), as xarray's backends do: a throw-away package is
installed with pip into a folder of its own and, with that folder on the path, its
instrument is a ``virtspec`` subcommand, reads through ``vm.take`` and writes files, with no
edit of virtspec-mi.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings
from importlib.metadata import EntryPoint

import pytest

import virtspec_mi as vm
from virtspec_mi import instruments

PYPROJECT = """\
[build-system]
requires = ["setuptools"]
build-backend = "setuptools.build_meta"

[project]
name = "tiny-instrument"
version = "0.1"

[project.entry-points."virtspec_mi.instruments"]
tiny = "tiny_instrument:Tiny"

[tool.setuptools]
py-modules = ["tiny_instrument"]
"""

MODULE = '''\
"""The smallest outside instrument: the spectrophotometer under another name."""

from typing import ClassVar

from virtspec_mi.instruments.command import Command
from virtspec_mi.instruments.hemispherical import Hemispherical


class Tiny(Hemispherical):
    """A spectrophotometer reading, from an outside package."""

    name: ClassVar[str] = "tiny"
    commands: ClassVar[tuple] = (Command(
        "tiny", "a tiny outside instrument", "The spectrophotometer's reading, from an outside package's entry point.",
        ("virtspec tiny diamond_conical --rays 1000",), one_reading=True),)
'''


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The throw-away package, installed by pip into a folder of its own; the environment that sees it."""

    source, target = tmp_path_factory.mktemp("tiny"), tmp_path_factory.mktemp("site")
    (source / "pyproject.toml").write_text(PYPROJECT)
    (source / "tiny_instrument.py").write_text(MODULE)
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--target", str(target), str(source)], check=True, capture_output=True)
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(target), os.environ.get("PYTHONPATH", "")])}


def virtspec(env: dict, *args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "virtspec_mi", *args], env=env, cwd=cwd, capture_output=True,
                          text=True, timeout=300)


def test_an_installed_instrument_is_a_subcommand_with_files(installed, mi, tmp_path):
    listing = virtspec(installed, "--help")
    assert listing.returncode == 0 and "tiny" in listing.stdout and "a tiny outside instrument" in listing.stdout
    out = tmp_path / "tiny.json"
    ran = virtspec(installed, "tiny", "diamond_conical", "--theta-i", "30", "--rays", "2000", "--seed", "3",
                   "--quiet", "--out", str(out))
    assert ran.returncode == 0, ran.stderr
    here = vm.measure("diamond_conical", theta_i=30, rays=2000, seed=3, progress=False)
    back = vm.read_result(out)
    assert back.reflected.ravel().tolist() == here.reflected.tolist()
    code = ("import json, virtspec_mi as vm; r = vm.take('tiny', 'diamond_conical', theta_i=30, rays=2000, seed=3, "
            "progress=False); print(json.dumps(r.reflected.ravel().tolist()))")
    taken = subprocess.run([sys.executable, "-c", code], env=installed, capture_output=True, text=True, timeout=300)
    assert taken.returncode == 0, taken.stderr
    assert json.loads(taken.stdout) == here.reflected.tolist()


def test_without_the_package_there_is_no_such_subcommand(mi):
    ran = virtspec(dict(os.environ), "tiny", "diamond_conical")
    assert ran.returncode == 2 and "invalid choice: 'tiny'" in ran.stderr


def test_a_broken_entry_point_is_left_out_with_a_warning(monkeypatch):
    points = [EntryPoint("broken", "no_such_module:Nothing", instruments.ENTRY_POINTS),
              EntryPoint("sphere", "virtspec_mi.instruments.sphere:IntegratingSphere", instruments.ENTRY_POINTS),
              EntryPoint("plain", "virtspec_mi.settings:Settings", instruments.ENTRY_POINTS)]
    import virtspec_mi.base.entry_points as rows

    monkeypatch.setattr(rows, "entry_points", lambda group: points)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        found = instruments.discovered(tuple(instruments.INSTRUMENTS.values()))
    assert list(found) == list(instruments.INSTRUMENTS)
    messages = " | ".join(str(w.message) for w in caught)
    assert "'broken' (no_such_module:Nothing) could not be loaded" in messages
    assert "takes the name 'sphere', already taken" in messages
    assert "'plain' (virtspec_mi.settings:Settings) is not a virtspec_mi Instrument class" in messages


CLASH = '''\
from typing import ClassVar

from virtspec_mi.instruments.command import Command
from virtspec_mi.instruments.hemispherical import Hemispherical


class Clash(Hemispherical):
    name: ClassVar[str] = "clash"
    commands: ClassVar[tuple] = (Command("fit", "not the fit", "An outside subcommand named as a built-in one.",
                                         ("virtspec fit x",), one_reading=True),
                                 Command("measure", "not measure", "Another.", ("virtspec measure x",),
                                         one_reading=True))
'''


def test_outside_packages_that_exit_or_take_a_builtin_name_are_left_out_and_the_tool_runs(monkeypatch, tmp_path):
    """One that calls sys.exit(3) at import ended every command; one declaring `fit` or `measure` crashed --help."""

    import virtspec_mi.base.entry_points as rows
    from virtspec_mi.cli import build_parser
    from virtspec_mi.cli.measuring import measuring_commands

    (tmp_path / "exits_at_import.py").write_text("import sys\nsys.exit(3)\n")
    (tmp_path / "raises_at_import.py").write_text("raise RuntimeError('broken outside package')\n")
    (tmp_path / "clash_instrument.py").write_text(CLASH)
    monkeypatch.syspath_prepend(str(tmp_path))
    points = [EntryPoint("exits", "exits_at_import:Nothing", instruments.ENTRY_POINTS),
              EntryPoint("raises", "raises_at_import:Nothing", instruments.ENTRY_POINTS),
              EntryPoint("clash", "clash_instrument:Clash", instruments.ENTRY_POINTS)]
    monkeypatch.setattr(rows, "entry_points", lambda group: points)
    builtin = tuple(instruments.INSTRUMENTS.values())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        found = instruments.discovered(builtin)
        monkeypatch.setattr(instruments, "INSTRUMENTS", found)
        rows = measuring_commands()
        parser = build_parser()
    messages = " | ".join(str(w.message) for w in caught)
    assert "'exits' (exits_at_import:Nothing) could not be loaded: it exited (SystemExit 3); left out" in messages
    assert "'raises' (raises_at_import:Nothing) could not be loaded: RuntimeError: broken outside package" in messages
    assert "the outside instrument 'clash' (clash_instrument) declares the subcommand 'fit', which virtspec itself " \
           "already has" in messages
    assert "declares the subcommand 'measure', which hemispherical already has" in messages
    assert "clash" in found and rows["measure"].instrument == "hemispherical" and "fit" not in rows
    assert parser.parse_args(["bounds"]).command == "bounds"
