"""
Tests of :mod:`virtspec_mi.applications.klems` (its ``__init__``): the application's row.

It declares ``virtspec klems``, extends the goniophotometer's ``virtspec gonio`` with
``--klems``, and registers the Klems measurement as a result kind. Its example is run by the
contract test (``tests/applications/test_applications.py``).
"""

from __future__ import annotations

from virtspec_mi.applications import APPLICATIONS, extensions
from virtspec_mi.applications.klems import KlemsApplication
from virtspec_mi.applications.klems.command import GONIO_KLEMS, KLEMS
from virtspec_mi.results.kinds import kind_of


def test_the_row_declares_its_command_extension_and_result():
    assert APPLICATIONS["klems"] is KlemsApplication
    assert KlemsApplication.commands == (KLEMS,) and KLEMS.name == "klems"
    assert GONIO_KLEMS in extensions("gonio") and GONIO_KLEMS.command == "gonio"
    (result,) = KlemsApplication.results
    assert kind_of(result.FORMAT) is result


def test_the_example_measures_the_quarter_basis_isotropically():
    example = KlemsApplication.example
    argv = example["argv"]
    assert argv[:2] == ("klems", "diamond_collimated") and argv[argv.index("--basis") + 1] == "quarter"
    assert "--isotropic" in argv and example["outputs"] == ("k.xml", "k.nc")
