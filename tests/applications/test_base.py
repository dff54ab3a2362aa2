"""
An application's row (virtspec_mi.applications.base): ``Application``, ``Command``,
``Extension``; the registry refuses a subcommand two rows declare; and the how-to "Add an
application" (docs/guide/add_an_application.md): its code run from a folder of its own, its
toy application installed from its entry point, then held to the applications' contract
test like a built-in row (``slow``).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import code_blocks
import virtspec_mi.applications as applications
from virtspec_mi.applications.base import Application, Command, Extension
from virtspec_mi.applications.klems.command import GONIO_KLEMS, KlemsFlags
from virtspec_mi.cli import main

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "guide" / "add_an_application.md"


def test_an_extension_is_given_by_its_active_flag_and_declares_what_it_takes():
    assert not GONIO_KLEMS.given(KlemsFlags()) and GONIO_KLEMS.given(KlemsFlags(klems="k.xml"))
    assert "mu" in GONIO_KLEMS.takes and "out" not in GONIO_KLEMS.takes and GONIO_KLEMS.reason
    assert Application.commands == () and Application.extensions == ()


def test_a_subcommand_two_applications_declare_is_refused(monkeypatch):
    fit = applications.APPLICATIONS["fitting"].commands[0]

    class Twin(Application):
        name = "twin"
        summary = "declares fit again"
        commands = (Command("fit", "again", "again", ("virtspec fit",), fit.flags, fit.respond),)

    monkeypatch.setitem(applications.APPLICATIONS, "twin", Twin)
    with pytest.raises(ValueError, match="application 'twin' declares the subcommand 'fit', which application "
                                         "'fitting' already has"):
        applications.commands()


def test_an_extension_refuses_every_other_flag_in_one_message(capsys):
    assert main(["gonio", "missing.xml", "--klems", "k.xml", "--out", "g.nc", "--plot", "g.png", "-D", "a=1"]) == 1
    err = capsys.readouterr().err
    assert "--klems takes none of -D, --out, --plot (" in err and err.count("\n") == 1


@pytest.mark.slow
def test_the_how_to_runs_and_its_application_passes_the_contract_test(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for index, source in enumerate(code_blocks.blocks(PAGE, "python")):
        exec(compile(source, f"{PAGE.name} python block {index}", "exec"), {"__name__": "__main__"})
    assert (tmp_path / "site-mean" / "spectral_mean.py").is_file()
    path = os.pathsep.join([str(tmp_path / "site-mean"), str(ROOT), str(ROOT / "tests")])
    contract = subprocess.run([sys.executable, "-m", "pytest", "-v", "-p", "no:cacheprovider",
                               str(ROOT / "tests" / "applications" / "test_applications.py"), "-k",
                               "spectral-mean or declares or generated"], cwd=ROOT, capture_output=True, text=True,
                              env={**os.environ, "PYTHONPATH": path}, timeout=600)
    assert contract.returncode == 0, contract.stdout[-3000:]
    for test in ("test_every_application_declares_its_commands_and_an_example",
                 "test_the_command_line_is_generated_from_the_rows",
                 "test_the_command_line_and_the_python_function_give_the_same_counts[spectral-mean]"):
        assert f"{test} PASSED" in contract.stdout, contract.stdout[-3000:]
